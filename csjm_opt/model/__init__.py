"""The rig and its physics: geometry, the CasADi model, numeric evaluation, statics, stiffness."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from . import casadi_model, hexagon
    from .joint_stiffness import stiffness, stiffness_batch
    from .numeric import Model
    from .rig import Rig, load_rig, paper_rig
    from .statics import Equilibrium, EquilibriumSolver, rest_lengths_for, solve_equilibrium

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'casadi_model': ('.casadi_model', None),
    'hexagon': ('.hexagon', None),
    'stiffness': ('.joint_stiffness', 'stiffness'),
    'stiffness_batch': ('.joint_stiffness', 'stiffness_batch'),
    'Model': ('.numeric', 'Model'),
    'Rig': ('.rig', 'Rig'),
    'load_rig': ('.rig', 'load_rig'),
    'paper_rig': ('.rig', 'paper_rig'),
    'Equilibrium': ('.statics', 'Equilibrium'),
    'EquilibriumSolver': ('.statics', 'EquilibriumSolver'),
    'rest_lengths_for': ('.statics', 'rest_lengths_for'),
    'solve_equilibrium': ('.statics', 'solve_equilibrium'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["Equilibrium", "EquilibriumSolver", "Model", "Rig", "casadi_model", "hexagon", "load_rig",
           "paper_rig", "rest_lengths_for", "solve_equilibrium", "stiffness", "stiffness_batch"]
