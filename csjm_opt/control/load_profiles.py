"""External load profiles for the closed-loop simulation: moments fixed in {A} (N m) versus time (s).

Profiles are frozen dataclasses, callable as ``profile(t) -> (3,)`` and
summable with ``+``: ``Step(0.1, [0, 0.5, 0]) + Sinusoid([0.1, 0, 0], 2.0)``.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Sequence

import numpy as np

from .._validate import as_vector3


def _vec(value) -> np.ndarray:
    v = as_vector3(value, "moment")
    v.setflags(write=False)
    return v


class LoadProfile(abc.ABC):
    """A moment fixed in {A} as a function of time."""

    @abc.abstractmethod
    def __call__(self, t_s: float) -> np.ndarray:
        """Moment (3,) in N m at time ``t_s``."""

    def __add__(self, other: "LoadProfile") -> "LoadSum":
        return LoadSum((self, other))


@dataclasses.dataclass(frozen=True, eq=False)
class Constant(LoadProfile):
    """The same moment ``moment_A_Nm`` (N m, in {A}) at every time."""

    moment_A_Nm: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "moment_A_Nm", _vec(self.moment_A_Nm))

    def __call__(self, t_s: float) -> np.ndarray:
        """The constant moment, a fresh copy.

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3,) array
            Moment (N m, in {A}).
        """
        return self.moment_A_Nm.copy()


@dataclasses.dataclass(frozen=True, eq=False)
class Step(LoadProfile):
    """``before`` until ``t0_s``, then ``after``."""

    t0_s: float
    after_A_Nm: np.ndarray
    before_A_Nm: np.ndarray = (0.0, 0.0, 0.0)  # type: ignore[assignment]  # array in __post_init__

    def __post_init__(self):
        object.__setattr__(self, "after_A_Nm", _vec(self.after_A_Nm))
        object.__setattr__(self, "before_A_Nm", _vec(self.before_A_Nm))

    def __call__(self, t_s: float) -> np.ndarray:
        """``before_A_Nm`` before ``t0_s``, ``after_A_Nm`` from ``t0_s`` on.

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3,) array
            Moment (N m, in {A}).
        """
        return (self.after_A_Nm if t_s >= self.t0_s else self.before_A_Nm).copy()


@dataclasses.dataclass(frozen=True, eq=False)
class Ramp(LoadProfile):
    """Linear from ``start`` at ``t0_s`` to ``end`` at ``t1_s``, constant outside."""

    t0_s: float
    t1_s: float
    end_A_Nm: np.ndarray
    start_A_Nm: np.ndarray = (0.0, 0.0, 0.0)  # type: ignore[assignment]  # array in __post_init__

    def __post_init__(self):
        if not self.t1_s > self.t0_s:
            from ..errors import InvalidInput
            raise InvalidInput(f"ramp needs t1 > t0, got {self.t0_s}, {self.t1_s}", "t1_s")
        object.__setattr__(self, "end_A_Nm", _vec(self.end_A_Nm))
        object.__setattr__(self, "start_A_Nm", _vec(self.start_A_Nm))

    def __call__(self, t_s: float) -> np.ndarray:
        """The ramp's moment at ``t_s`` (linear between ``t0_s`` and ``t1_s``, held outside).

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3,) array
            Moment (N m, in {A}).
        """
        s = min(1.0, max(0.0, (t_s - self.t0_s) / (self.t1_s - self.t0_s)))
        return self.start_A_Nm + s * (self.end_A_Nm - self.start_A_Nm)


@dataclasses.dataclass(frozen=True, eq=False)
class Sinusoid(LoadProfile):
    """``amplitude sin(2 pi f (t - t0) + phase)`` for ``t >= t0_s`` (zero before)."""

    amplitude_A_Nm: np.ndarray
    frequency_hz: float
    phase_rad: float = 0.0
    t0_s: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "amplitude_A_Nm", _vec(self.amplitude_A_Nm))

    def __call__(self, t_s: float) -> np.ndarray:
        """The sinusoid's moment at ``t_s`` (zero before ``t0_s``).

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3,) array
            Moment (N m, in {A}).
        """
        if t_s < self.t0_s:
            return np.zeros(3)
        return self.amplitude_A_Nm * np.sin(2 * np.pi * self.frequency_hz * (t_s - self.t0_s) + self.phase_rad)


@dataclasses.dataclass(frozen=True, eq=False)
class LoadSum(LoadProfile):
    """Sum of profiles."""

    terms: Sequence[LoadProfile]

    def __call__(self, t_s: float) -> np.ndarray:
        """The sum of the terms' moments at ``t_s``.

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3,) array
            Moment (N m, in {A}).
        """
        return sum((p(t_s) for p in self.terms), np.zeros(3))

    def __add__(self, other: LoadProfile) -> "LoadSum":
        return LoadSum(tuple(self.terms) + (other,))
