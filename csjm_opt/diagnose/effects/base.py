"""Base class of the unmodelled effects (one class per file in this package).

An effect augments the moment balance of :mod:`csjm_opt.diagnose.fitting.augmented`
through one or more hooks, each given the effect's own parameter slice ``p``:

``adjust_load``      the external moment and the platform's first mass moment;
``adjust_frame``     the true pose of the measured body from the tracked pose (registration);
``adjust_pose``      the pose of the cable-driven platform from the measured pose;
``adjust_geometry``  hole positions;
``adjust_rest``      the actual rest lengths from the commanded ones (drive offsets);
``adjust_tension``   the tension law ``T(e)`` of the cables (``e = c - l``);
``adjust_balance``   further moments on the cable platform (joint friction).

Every hook defaults to "no change", and every effect reduces to the nominal
model when its strength parameters are zero (``x0`` starts there), so
augmented models nest the nominal one (a nested F-test applies). ``scales`` are typical
magnitudes (for the optimiser and for
the weak ridge prior that keeps rank-deficient fits well posed).

Plausibility: every effect declares prior ranges ``(lo, hi)`` for its
parameters (:meth:`Effect.default_ranges`, what a real rig of this kind can
show: hole offsets of a few mm, a bias within the sensor's range, ...). A fit
whose parameters leave them is reported as implausible
(:meth:`Effect.implausible`). ``ranges`` given to the constructor override the
defaults per rig: keys are parameter names or ``fnmatch`` patterns
(``"dA*_m"``).
"""

from __future__ import annotations

import abc
import fnmatch
from typing import ClassVar, Mapping

import numpy as np

#: Standard errors by which a fitted parameter must leave its prior range to be implausible.
PLAUSIBLE_Z = 2.0


class Effect(abc.ABC):
    """One unmodelled effect with named, SI-unit parameters (all zero = nominal)."""

    name: ClassVar[str]
    description: ClassVar[str]
    path_dependent: ClassVar[bool] = False
    #: How well a model's evidence is predicted one Gauss-Newton step from nominal values of this effect (the
    #: pair screen, :func:`csjm_opt.diagnose.fitting.model_fits.predicted_pair_evidence`): ``"tight"``; ``"loose"``
    #: where a fit reaches well beyond the step (the effect moves the pose tangent, or a loading path's state
    #: moves with it), and the screen allows a wider margin; ``"none"`` where the step from nominal sees almost
    #: nothing of what a fit reaches (cable friction's bands), and no prediction is made.
    step_from_nominal: ClassVar[str] = "tight"
    #: per-rig overrides of the prior ranges (name or fnmatch pattern -> (lo, hi))
    range_overrides: Mapping[str, tuple[float, float]] = {}
    #: the rig's cable count m (per-cable parameters are sized by it)
    n_cables: int = 6

    def __init__(self, n_cables: int = 6):
        self.n_cables = int(n_cables)

    def with_ranges(self, overrides: Mapping[str, tuple[float, float]] | None) -> "Effect":
        """Override the prior ranges of this effect in place.

        Parameters
        ----------
        overrides : Mapping[str, tuple[float, float]] or None
            Parameter name or ``fnmatch`` pattern -> ``(lo, hi)``; patterns matching none of the
            names are ignored. None or empty leaves the ranges unchanged.

        Returns
        -------
        Effect
            The same effect (``self``), for chaining.
        """
        if overrides:
            self.range_overrides = {**self.range_overrides, **{k: (float(lo), float(hi))
                                                             for k, (lo, hi) in overrides.items()}}
        return self

    def default_ranges(self) -> dict[str, tuple[float, float]]:
        """Plausible ``(lo, hi)`` of each parameter on a real rig (SI units of the parameter)."""
        return {n: (-np.inf, np.inf) for n in self.param_names}

    def ranges(self) -> dict[str, tuple[float, float]]:
        """Prior ranges after the per-rig overrides."""
        out = self.default_ranges()
        for pattern, rng in self.range_overrides.items():
            for n in out:
                if fnmatch.fnmatchcase(n, pattern):
                    out[n] = rng
        return out

    def implausible(self, p: np.ndarray, sd: np.ndarray | None = None, z: float = PLAUSIBLE_Z) -> list[str]:
        """Names of the parameters outside their prior ranges.

        With standard errors ``sd`` only those the data put outside: beyond a bound by more
        than ``z`` standard errors (a weakly determined parameter that wanders past a bound
        within its uncertainty is not evidence against the effect).
        """
        p = np.asarray(p, float)
        slack = np.zeros_like(p) if sd is None else z * np.nan_to_num(np.asarray(sd, float), nan=0.0)
        return [n for (n, (lo, hi)), v, e in zip(self.ranges().items(), p, slack)
                if not (lo - e <= v <= hi + e)]

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
        """Lower bounds of the parameters for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``-inf`` for every parameter unless overridden.
        """
        return np.full(len(self.param_names), -np.inf)

    @property
    def upper_bounds(self) -> np.ndarray:
        """Upper bounds of the parameters for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``+inf`` for every parameter unless overridden.
        """
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
        """Number of parameters.

        Returns
        -------
        int
            ``len(param_names)``.
        """
        return len(self.param_names)

    # hooks (``ev`` is an :class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`)
    def adjust_load(self, ev, p: np.ndarray) -> None:
        """Change ``ev.tau_ext_A_Nm`` (n, 3) or ``ev.first_moment_A_kgm`` (3,)."""

    def adjust_frame(self, ev, p: np.ndarray) -> None:
        """Change ``ev.R_body`` (n, 3, 3), the true pose of the measured body (before its weight is taken)."""

    def adjust_pose(self, ev, p: np.ndarray) -> None:
        """Change ``ev.R_cable`` (n, 3, 3) and ``ev.link_rotation`` (n, 3, 3)."""

    def adjust_geometry(self, ev, p: np.ndarray) -> None:
        """Change ``ev.A_m``, ``ev.B_m`` (m, 3)."""

    def adjust_rest(self, ev, p: np.ndarray) -> None:
        """Change ``ev.rest_lengths_m`` (n, m): the actual rest lengths from the commanded ones."""

    def adjust_tension(self, ev, stretch_m: np.ndarray, T_N: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Return the tensions (n, m) given stretch and the tensions so far."""
        return T_N

    def adjust_balance(self, ev, g_Nm: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Return the balance (n, 3) N m with the moments this effect adds on the cable platform."""
        return g_Nm

    # Tangents (forward mode) of the late hooks: the exact derivative of the balance with respect to the
    # parameters that enter at the load, rest, tension or balance stage (:meth:`AugmentedModel.balance_derivative`).
    # ``cols`` holds the column of each of this effect's parameters among the P derivative columns (-1: none);
    # ``d_*`` arrays carry a trailing axis of P columns. An effect that overrides a late hook and cannot give its
    # tangent (``tangent_ok`` False) leaves the model's Jacobian to finite differences.
    #: a pose hook that reads the loads (link compliance): load parameters then move the cables too
    reads_load: ClassVar[bool] = False

    def overrides(self, hook: str) -> bool:
        """Whether this effect's class overrides the hook ``hook`` (a method name) of :class:`Effect`."""
        return getattr(type(self), hook) is not getattr(Effect, hook)

    def has_tangent(self, hook: str) -> bool:
        """Whether this effect overrides ``hook`` and gives its tangent (``d_<hook>``)."""
        return self.overrides(hook) and self.overrides(f"d_{hook}")

    def tangent_ok(self, rows) -> bool:
        """Whether this effect's late hooks give their tangents on ``rows`` (default: whichever it overrides)."""
        return all(self.has_tangent(h) for h in LATE_HOOKS if self.overrides(h))

    def d_adjust_load(self, ev, p: np.ndarray, cols: np.ndarray, d_tau: np.ndarray,
                      d_first: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tangents ``(d tau_ext (n, 3, P), d first_moment (3, P))`` after :meth:`adjust_load` (``ev``: its inputs)."""
        raise NotImplementedError

    def d_adjust_pose(self, ev, p: np.ndarray, cols: np.ndarray, d_load: np.ndarray, d_eta: np.ndarray,
                      d_link: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
        """Tangents after :meth:`adjust_pose`: the cable platform's pose and the link's rotation.

        The pose's as a right rotation (n, 3, P), the link's rotation matrix's (n, 3, 3, P) (None: zero);
        ``d_load``: the tangent of ``tau_ext + tau_weight`` (n, 3, P).
        """
        raise NotImplementedError

    def d_adjust_geometry(self, ev, p: np.ndarray, cols: np.ndarray, d_A: np.ndarray,
                          d_B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tangents of the holes (m, 3, P) (or per row) after :meth:`adjust_geometry`."""
        raise NotImplementedError

    def d_adjust_rest(self, ev, p: np.ndarray, cols: np.ndarray, d_rest: np.ndarray) -> np.ndarray:
        """Tangent of the rest lengths (n, m, P) after :meth:`adjust_rest`."""
        raise NotImplementedError

    def d_adjust_tension(self, ev, stretch_m: np.ndarray, d_stretch: np.ndarray, T_N: np.ndarray, d_T: np.ndarray,
                         T_out_N: np.ndarray, p: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Tangent of the tensions (n, m, P) after :meth:`adjust_tension` (``T_N`` in, ``T_out_N`` out)."""
        raise NotImplementedError

    def d_adjust_balance(self, ev, d_g: np.ndarray, p: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Tangent of the balance (n, 3, P) after :meth:`adjust_balance`."""
        raise NotImplementedError

    def describe(self, p: np.ndarray) -> dict:
        """Derived, physically readable quantities for the report (JSON-able)."""
        return {}


#: The hooks after the cables are placed (and the loads, unless a pose hook reads them): their tangents are exact.
LATE_HOOKS = ("adjust_load", "adjust_rest", "adjust_tension", "adjust_balance")
#: Hooks that place the measured body, the cable platform or the holes (their parameters: finite differences).
EARLY_HOOKS = ("adjust_frame", "adjust_pose", "adjust_geometry")


def one_hot(cols: np.ndarray, n_cols: int) -> np.ndarray:
    """``(k, P)``: row ``i`` is the unit vector of column ``cols[i]`` (a zero row where ``cols[i] < 0``)."""
    cols = np.asarray(cols, int)
    out = np.zeros((len(cols), n_cols))
    ok = cols >= 0
    out[np.flatnonzero(ok), cols[ok]] = 1.0
    return out
