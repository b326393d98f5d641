"""Controllers for the closed-loop simulation (one class per file, like pink's tasks).

A controller maps an :class:`Observation` (time, measured pose, measured
external moment, optionally angular velocity) to a :class:`Command` (tensions
and rest lengths); every controller runs on every plant of
:mod:`csjm_opt.control.plants`. The dynamic ones (:class:`InverseDynamicsController`,
:class:`SO3FeedbackController`) use the rig's inertia and damping. Write
your own by subclassing :class:`Controller` (or :class:`PoseHoldingController`
to reuse the pose reference, integral correction and rest-length conversion).
"""

from .base import Command, Controller, Observation, PoseHoldingController
from .inverse_dynamics import InverseDynamicsController
from .so3_feedback import SO3FeedbackController
from .stiffness_shaping import StiffnessShapingController
from .tension_planning import TensionPlanningController

__all__ = [
    "Command", "Controller", "InverseDynamicsController", "Observation", "PoseHoldingController",
    "SO3FeedbackController", "StiffnessShapingController", "TensionPlanningController",
]
