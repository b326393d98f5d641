"""Base class of the unmodelled effects (one class per file in this package).

An effect augments the moment balance of :mod:`csjm_opt.diagnose.augmented`
through one or more hooks, each given the effect's own parameter slice ``p``:

``adjust_load``      the external moment and the platform's first mass moment;
``adjust_pose``      the pose of the cable-driven platform from the measured pose;
``adjust_geometry``  hole positions;
``adjust_tension``   the tension law ``T(e)`` of the cables (``e = c - l``).

Every hook defaults to "no change", and every effect reduces to the nominal
model when its strength parameters are zero (``x0`` starts there), so
augmented models nest the nominal one (a nested F-test applies). ``scales`` are typical
magnitudes (for the optimiser and for
the weak ridge prior that keeps rank-deficient fits well posed).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import numpy as np


class Effect(abc.ABC):
    """One unmodelled effect with named, SI-unit parameters (all zero = nominal)."""

    name: ClassVar[str]
    description: ClassVar[str]

    @property
    @abc.abstractmethod
    def param_names(self) -> tuple[str, ...]:
        """Names with units, e.g. ``"bias_x_Nm"``."""

    @property
    @abc.abstractmethod
    def scales(self) -> np.ndarray:
        """Typical magnitude of each parameter (same units)."""

    @property
    def lower_bounds(self) -> np.ndarray:
        return np.full(len(self.param_names), -np.inf)

    @property
    def upper_bounds(self) -> np.ndarray:
        return np.full(len(self.param_names), np.inf)

    @property
    def prior_sd(self) -> np.ndarray | None:
        """Standard deviation of a zero-mean ridge prior, or None for no prior."""
        return None

    def x0(self) -> np.ndarray:
        """Starting values (the nominal model)."""
        return np.zeros(self.n_params)

    def extra_starts(self) -> list[np.ndarray]:
        """Further starting values for effects that trade off with the nuisance parameters."""
        return []

    @property
    def n_params(self) -> int:
        return len(self.param_names)

    # hooks (``ev`` is an :class:`~csjm_opt.diagnose.augmented.Evaluation`)
    def adjust_load(self, ev, p: np.ndarray) -> None:
        """Change ``ev.tau_ext_A_Nm`` (n, 3) or ``ev.first_moment_A_kgm`` (3,)."""

    def adjust_pose(self, ev, p: np.ndarray) -> None:
        """Change ``ev.R_cable`` (n, 3, 3) and ``ev.link_rotation`` (n, 3, 3)."""

    def adjust_geometry(self, ev, p: np.ndarray) -> None:
        """Change ``ev.A_m``, ``ev.B_m`` (6, 3)."""

    def adjust_tension(self, ev, stretch_m: np.ndarray, T_N: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Return the tensions (n, 6) given stretch and the tensions so far."""
        return T_N

    def describe(self, p: np.ndarray) -> dict:
        """Derived, physically readable quantities for the report (JSON-able)."""
        return {}
