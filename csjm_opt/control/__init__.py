"""Closed-loop simulation: controllers, load profiles and plants."""

from . import controllers, load_profiles, plants
from .closed_loop import ClosedLoopLog, plot_closed_loop, plot_closed_loop_stiffness, simulate

__all__ = ["ClosedLoopLog", "controllers", "load_profiles", "plants", "plot_closed_loop",
           "plot_closed_loop_stiffness", "simulate"]
