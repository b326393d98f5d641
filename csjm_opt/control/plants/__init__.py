"""Plants for the closed-loop simulation (one class per file): what the controller's commands act on.

* :class:`QuasiStaticPlant`: settles at the static equilibrium after every
  command (the project's forward statics; no inertia, no damping);
* :class:`MujocoPlant`: the rig as a MuJoCo model (inertia, damping,
  pull-only cable springs, winch rate limits), stepped in real time.

Both take the same :class:`~csjm_opt.control.controllers.base.Command`.
"""

from .base import Plant, PlantState
from .mujoco import MujocoPlant
from .quasi_static import QuasiStaticPlant

__all__ = ["MujocoPlant", "Plant", "PlantState", "QuasiStaticPlant"]
