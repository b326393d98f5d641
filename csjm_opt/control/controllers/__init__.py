"""Controllers for the closed-loop simulation (one class per file, like pink's tasks).

A controller maps an :class:`Observation` (time, measured pose, measured
external moment) to a :class:`Command` (tensions and rest lengths). Write
your own by subclassing :class:`Controller` (or :class:`PoseHoldingController`
to reuse the pose reference, integral correction and rest-length conversion).
"""

from .base import Command, Controller, Observation, PoseHoldingController
from .stiffness_shaping import StiffnessShapingController
from .tension_planning import TensionPlanningController

__all__ = sorted(["Command", "Controller", "Observation", "PoseHoldingController",
                  "StiffnessShapingController", "TensionPlanningController"])
