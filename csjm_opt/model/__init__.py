"""The rig and its physics: geometry, the CasADi model, numeric evaluation, statics, stiffness."""

from . import casadi_model, hexagon
from .joint_stiffness import stiffness, stiffness_batch
from .numeric import Model
from .rig import Rig, load_rig, paper_rig
from .statics import Equilibrium, EquilibriumSolver, rest_lengths_for, solve_equilibrium

__all__ = ["Equilibrium", "EquilibriumSolver", "Model", "Rig", "casadi_model", "hexagon", "load_rig",
           "paper_rig", "rest_lengths_for", "solve_equilibrium", "stiffness", "stiffness_batch"]
