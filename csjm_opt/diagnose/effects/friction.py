"""``friction``: dry friction of the cables at their guides, with memory across rows and cycles.

Where a cable slides through its guide (or its drive), the tension the platform
feels, ``T_p``, differs from the elastic tension ``T = k e`` by a friction term
whose sign follows the cable's motion and which holds any value in between
while the cable sticks. Two laws, chosen by the data
(:func:`csjm_opt.diagnose.selection.decision.diagnose` fits both and keeps the better):

* ``capstan`` (friction over the hole's curved surface): ``T_p = T exp(mu_beta_i s_i)``;
* ``coulomb`` (a constant force at the drive or guide): ``T_p = T + F_i s_i`` (N).

The band position ``s_i in [-1, 1]`` follows the cable as a play (stop) operator::

    s_i[j] = clip(s_i[j-1] + (dc_i[j] + f dl_i[j]) / travel_i[j], -1, 1)
    travel_i = f * band_i / k_i        (band_i = mu_beta_i T_i or F_i)

``dc`` is the change of the cable's geometric length since the previous row and
``dl`` the change of its commanded rest length: while the cable sticks at the
guide, drawing it out (``dc > 0``) raises the platform side's tension and
paying out the drive (``dl > 0``) lowers the drive side's, both moving ``s``
up. For a cable stuck at one point between a platform-side segment holding a
share ``rho`` of its compliance and a drive-side segment holding ``1 - rho``,
the friction force changes by ``k (dc / rho + dl / (1 - rho))``; with the band
written as the deviation of ``T_p`` from the elastic tension ``k (c - l)``,
that is ``(k / band) (dc / f + dl)`` with ``f = rho / (1 - rho)``: one
parameter, the stick travel factor ``f``, weighs both (a weight of ``dl`` of
its own would only be identified by the few changes of rest length between
cycles, and wandered there to unphysical values). MuJoCo's tendon friction is
the limit ``f -> 0`` (the tendon's length is held while it sticks). ``f -> 0``
is pure sliding (``s = sign(dc)``).

Between rows the rig moves along a quasi-static ramp of its inputs, and the play
operator remembers the extremes of its input: each row's change is applied in
``RAMP_SUBSTEPS`` steps along the shape of the ramp
(:mod:`csjm_opt.diagnose.fitting.friction_ramp`), so a cable that draws out and back in
while the platform swings to the next cycle's pose leaves the state the swing
leaves, not the state of one step.

Memory: rows are in time order, and nobody relaxes the cables between load
cycles, so the state is carried through the whole log: a cycle's first row
continues from the previous cycle's last row, stepped by the changes between
them (``memory="carried"``, the default). Only the log's first row starts at a
fitted ``first_row_state``. ``memory="reset"`` starts every cycle there (a rig
that is re-homed between cycles). The length changes come from the measured
poses when fitting, and from the model's own predicted poses, row after row,
when predicting a held-out cycle, which starts where the measured history before
it leaves the state (:func:`csjm_opt.diagnose.fitting.augmented.with_entry`).
m + 2 parameters (eight on a six-cable rig): m band sizes, ``f``, ``first_row_state``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..fitting.friction_ramp import ramp_steps
from .base import Effect, one_hot

#: Smallest stick travel (m): keeps the play operator continuous in the pose for
#: forward solves (a pure sign switch has no equilibrium at a reversal).
MIN_TRAVEL_M = 5e-6
#: Rounding of the band's edges (in units of the half band).
CORNER = 0.02
#: Above this, ``a + log1p(exp(-a))`` rounds to ``a`` (``exp(-40) < 1e-17``, half an ulp of 40 is 3.6e-15).
SOFTPLUS_LINEAR = 40.0
#: Friction laws and memory modes.
LAWS = ("capstan", "coulomb")
MEMORIES = ("carried", "reset", "settled")
#: Band positions kept per effect (a fit's Jacobian and pose tangent re-evaluate the log at the same stick
#: travels: every column of a parameter the travel does not depend on, every pose step under the Coulomb law).
BAND_MEMO = 16


@njit(cache=True)
def _soft_clip(x: float, w: float) -> float:   # pragma: no cover (compiled)
    """``clip(x, -1, 1)`` with corners rounded over ``w`` (forward solves need continuity of slope)."""
    return -1.0 + w * _softplus((x + 1.0) / w) - w * _softplus((x - 1.0) / w)


@njit(cache=True)
def _softplus(a: float) -> float:   # pragma: no cover (compiled)
    """``log(1 + exp(a))``; above ``SOFTPLUS_LINEAR`` it is ``a`` to the last bit, and is not evaluated."""
    if a > SOFTPLUS_LINEAR:
        return a
    return a + np.log1p(np.exp(-a)) if a > 0 else np.log1p(np.exp(a))


@njit(cache=True)
def _ramp_play(prev: float, step: np.ndarray, i: int, j: int, w: float) -> float:   # pragma: no cover
    """The play operator over the steps ``step[i, :, j]`` of one ramp (corners rounded over ``w / S``)."""
    S = step.shape[1]
    for q in range(S):
        prev = _soft_clip(prev + step[i, q, j], w / S)
    return prev


@njit(cache=True)
def _carried_band(step: np.ndarray, s0: float, w: float) -> np.ndarray:   # pragma: no cover (compiled)
    """The play operator over the whole log in order, ramp by ramp (``step`` (n, S, m))."""
    n, _, m = step.shape
    s = np.empty((n, m))
    for j in range(m):
        prev = s0
        s[0, j] = s0
        for i in range(1, n):
            prev = _ramp_play(prev, step, i, j, w)
            s[i, j] = prev
    return s


@njit(cache=True)
def _rows_band(prev: np.ndarray, step: np.ndarray, w: float) -> np.ndarray:   # pragma: no cover (compiled)
    """The play operator over each row's own ramp from the states ``prev`` (n, m) (rows independent)."""
    n, _, m = step.shape
    s = np.empty((n, m))
    for i in range(n):
        for j in range(m):
            s[i, j] = _ramp_play(prev[i, j], step, i, j, w)
    return s


@njit(cache=True)
def _soft_clip_slope(x: float, w: float) -> float:   # pragma: no cover (compiled)
    """Derivative of :func:`_soft_clip` in ``x`` (the logistic of each rounded edge; 1 where it is linear)."""
    return _softplus_slope((x + 1.0) / w) - _softplus_slope((x - 1.0) / w)


@njit(cache=True)
def _softplus_slope(a: float) -> float:   # pragma: no cover (compiled)
    """Derivative of :func:`_softplus` (exactly 1 on its linear branch)."""
    if a > SOFTPLUS_LINEAR:
        return 1.0
    return 1.0 / (1.0 + np.exp(-a)) if a > 0 else np.exp(a) / (1.0 + np.exp(a))


@njit(cache=True)
def _band_tangent(step: np.ndarray, d_step: np.ndarray, s0: float, d_s0: np.ndarray, restart: np.ndarray,
                  w: float) -> tuple[np.ndarray, np.ndarray]:   # pragma: no cover (compiled)
    """The play operator over the rows in order and its tangent (forward mode).

    ``step`` (n, S, m) and its tangent ``d_step`` (n, S, m, P); rows with ``restart`` start at ``s0`` (tangent
    ``d_s0`` (P,)), every other row continues from the previous one along its ramp, as :func:`_carried_band`
    (``restart`` only on the first row) and the reset memory (on every cycle's first row) do.
    """
    n, S, m = step.shape
    P = d_step.shape[3]
    s = np.empty((n, m))
    ds = np.empty((n, m, P))
    dprev = np.empty(P)
    for j in range(m):
        prev = s0
        for i in range(n):
            if restart[i]:
                prev = s0
                dprev[:] = d_s0
            else:
                for q in range(S):
                    x = prev + step[i, q, j]
                    slope = _soft_clip_slope(x, w / S)
                    for c in range(P):
                        dprev[c] = slope * (dprev[c] + d_step[i, q, j, c])
                    prev = _soft_clip(x, w / S)
            s[i, j] = prev
            ds[i, j, :] = dprev
    return s, ds


def ramp_input(dc_m: np.ndarray, dl_m: np.ndarray, shape_m: np.ndarray | None, travel_m: np.ndarray,
               rest_weight: float) -> np.ndarray:
    """The play operator's input steps (n, S, m) along each row's ramp, in units of the stick travel.

    Parameters
    ----------
    dc_m, dl_m : numpy.ndarray
        Changes (n, m) of the cable lengths and of the rest lengths since the previous row (m).
    shape_m : numpy.ndarray or None
        The ramp's deviation from even steps (:func:`csjm_opt.diagnose.fitting.friction_ramp.predict_ramp`),
        or None (one step).
    travel_m : numpy.ndarray
        Stick travel (n, m) of each row and cable (m).
    rest_weight : float
        Weight of the rest-length change (the stick travel factor: one compliance split).

    Returns
    -------
    numpy.ndarray
        ``(dc_q + w dl / S) / travel``; the rest lengths ramp evenly.
    """
    dc_q = ramp_steps(np.asarray(dc_m, float), shape_m)
    S = dc_q.shape[1]
    return np.ascontiguousarray((dc_q + (rest_weight / S) * np.asarray(dl_m, float)[:, None, :])
                                / travel_m[:, None, :], dtype=np.float64)


def band_position(rows, travel_m: np.ndarray, s0: float = 0.0, rest_weight: float = 0.0,
                  carried: bool = True) -> np.ndarray:
    """``s`` (n, m) of the play operator over the log's rows (``travel_m`` (n, m) > 0).

    Each row is reached from the previous row of the log along the ramp of its inputs
    (``rows.ramp_shape_m``; one step where it is None).

    Parameters
    ----------
    rows : Rows
        The log's rows in time order (steps at the measured or predicted poses).
    travel_m : numpy.ndarray
        Stick travel of each row and cable (m).
    s0 : float, optional
        State of the log's first row (and of every cycle's first row unless ``carried``).
    rest_weight : float, optional
        Weight of the rest-length change (the stick travel factor: one compliance split).
    carried : bool, optional
        Carry the state across cycle boundaries.

    Returns
    -------
    numpy.ndarray
    """
    dc, dl = rows.steps_since_previous
    step = ramp_input(dc, dl, rows.ramp_shape_m, travel_m, rest_weight)
    if not carried:
        s = np.full(dc.shape, float(s0))
        for idx in rows.sequence:
            s[idx] = _rows_band(np.ascontiguousarray(s[idx - 1]), np.ascontiguousarray(step[idx]), CORNER)
        return s
    return _carried_band(step, float(s0), CORNER)


class Friction(Effect):
    """Dry cable friction: m band sizes (one per cable), the stick travel factor, the first state."""

    #: from zero friction forces the step sees almost nothing of the bands a fit opens: over the 47 validation
    #: logs a pair's fit reached up to 2.3 times the gap the step predicted (``studies/pair_screen``)
    step_from_nominal = "none"
    name = "friction"
    description = ("dry cable friction with memory: T_platform = T exp(mu_beta_i s_i) (capstan) or "
                   "T + F_i s_i (Coulomb), s_i a play operator of the cable's motion carried over the log")

    def __init__(self, law: str = "capstan", memory: str = "carried", t_max_N: float = 100.0,
                 n_cables: int = 6):
        if law not in LAWS or memory not in MEMORIES:
            raise ValueError(f"law must be one of {LAWS} and memory one of {MEMORIES}")
        if memory == "settled" and law != "coulomb":
            raise ValueError("settled friction is a Coulomb band (law='coulomb')")
        self.law, self.memory, self.t_max_N = law, memory, float(t_max_N)
        self.n_cables = int(n_cables)
        # settled: the rest pose is any static Coulomb equilibrium (:mod:`..fitting.friction_stick`), no path
        self.settled = memory == "settled"
        self._memo: dict = {}

    @property
    def path_dependent(self) -> bool:  # type: ignore[override]
        """Whether the state follows the loading path (not for settled friction: any static equilibrium)."""
        return not self.settled

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_memo"] = {}               # a cache, not state: not pickled (fits travel back from workers)
        return state

    def _band_position(self, rows, travel_m: np.ndarray, s0: float, rest_weight: float) -> np.ndarray:
        """:func:`band_position` of the whole log, remembered for the last ``BAND_MEMO`` inputs.

        The play operator is a deterministic function of the rows and of these inputs, so a remembered
        result is the one a new evaluation would return, bit for bit.
        """
        travel_m = np.ascontiguousarray(travel_m, dtype=np.float64)
        key = (id(rows), travel_m.tobytes(), float(s0), float(rest_weight), self.memory)
        memo = self.__dict__.setdefault("_memo", {})
        hit = memo.pop(key, None)
        if hit is not None and hit[0] is rows:
            memo[key] = hit                          # most recently used last
            return hit[1].copy()
        s = band_position(rows, travel_m, s0, rest_weight, self.memory == "carried")
        memo[key] = (rows, s.copy())                 # the rows held: their id stays theirs while cached
        while len(memo) > BAND_MEMO:
            memo.pop(next(iter(memo)))
        return s

    @property
    def _band(self) -> str:
        return "mu_beta" if self.law == "capstan" else "F"

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            m band sizes (``mu_beta_i`` for the capstan law, ``F_i_N`` in N for Coulomb; ``i = 1..m``),
            then ``stick_travel_factor`` and ``first_row_state``.
        """
        unit = "" if self.law == "capstan" else "_N"
        bands = tuple(f"{self._band}_{i + 1}{unit}" for i in range(self.n_cables))
        return bands if self.memory == "settled" else bands + ("stick_travel_factor", "first_row_state")

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            Band scale (0.03, or 2 % of ``t_max_N`` in N) for the m bands, 0.5 for the other two.
        """
        band = 0.03 if self.law == "capstan" else 0.02 * self.t_max_N
        return np.r_[np.full(self.n_cables, band), 0.5, 0.5][:self.n_params]

    @property
    def lower_bounds(self):
        """Lower bounds for the optimiser.

        Returns
        -------
        numpy.ndarray
            Zero for the bands and the stick factor; -1 for the first state.
        """
        return np.r_[np.zeros(self.n_cables + 1), -1.0][:self.n_params]

    @property
    def upper_bounds(self):
        """Upper bounds for the optimiser.

        Returns
        -------
        numpy.ndarray
            Unbounded for the bands and the stick factor; 1 for the first state.
        """
        return np.r_[np.full(self.n_cables + 1, np.inf), 1.0][:self.n_params]

    def default_ranges(self):
        """Plausible ranges of the friction parameters.

        Capstan factors up to 0.3 (35 % tension band: a badly worn guide), or Coulomb forces up to 10 % of
        the rig's largest tension; stick factor up to 2; first state in [-1, 1].

        Returns
        -------
        dict
            Parameter name -> ``(lo, hi)``.
        """
        top = 0.3 if self.law == "capstan" else 0.1 * self.t_max_N
        out = {n: (0.0, top) for n in self.param_names[:self.n_cables]}
        if self.memory != "settled":
            out.update({"stick_travel_factor": (0.0, 2.0), "first_row_state": (-1.0, 1.0)})
        return out

    def x0(self) -> np.ndarray:
        """Starting values: no friction, stick factor 0.5, first state 0.

        Returns
        -------
        numpy.ndarray
            The m + 2 starting values.
        """
        return np.r_[np.zeros(self.n_cables), 0.5, 0.0][:self.n_params]

    def stick_columns(self, ev) -> tuple[np.ndarray, np.ndarray]:
        """Generators of the settled variant's stick set in the balance: each cable's moment per newton.

        Parameters
        ----------
        ev : Evaluation
            With ``cable_jacobian`` set.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            ``J^T`` (n, 3, m) (N m per N of friction force along each cable) and the band parameter of
            each column (cable j: band j).
        """
        return np.swapaxes(np.asarray(ev.cable_jacobian), 1, 2).copy(), np.arange(self.n_cables)

    def adjust_tension(self, ev, stretch_m, T_N, p):
        """Platform-side tensions with dry friction, ``T exp(mu_beta_i s_i)`` or ``max(T + F_i s_i, 0)``.

        Capstan or Coulomb law. The band position ``s_i`` in [-1, 1] is a play operator of each
        cable's motion (carried over the log, or one row per cycle); it is stored in ``ev.state_out``.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`).
        stretch_m : numpy.ndarray
            Cable stretch ``e = c - l`` (m), shape (n, m).
        T_N : numpy.ndarray
            Tensions from the tension law so far (N), shape (n, m).
        p : numpy.ndarray
            m band sizes, the stick travel factor, the first state.

        Returns
        -------
        numpy.ndarray
            The changed tensions (N), shape (n, m).
        """
        if self.memory == "settled":              # friction forces are latent per row: no mean tension change
            return T_N
        m = self.n_cables
        band, factor, s0 = p[:m], p[m], p[m + 1]
        w = factor                                   # one compliance split weighs both sides
        travel = self._travel(ev, T_N, p)[0]
        rows = ev.rows
        if rows.state_prev is None:                  # whole log at measured poses
            s = self._band_position(rows, travel, s0, w)
        else:                                        # one row per cycle, sequential prediction
            first = np.isnan(rows.lengths_prev_m)
            _, dl = rows.steps_since_previous
            dc = np.where(first, 0.0, ev.lengths_m - rows.lengths_prev_m)    # (NaN only where discarded)
            step = ramp_input(dc, np.where(first, 0.0, dl), rows.ramp_shape_m, travel, w)
            s = np.where(first, s0, _rows_band(np.ascontiguousarray(rows.state_prev, dtype=np.float64), step, CORNER))
        ev.state_out = s
        if self.law == "capstan":
            return T_N * np.exp(s * band)
        return np.maximum(T_N + s * band, 0.0)

    def _travel(self, ev, T_N: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stick travel (n, m) of each row and cable, the band size behind it, and the travel before its floor."""
        m = self.n_cables
        band, factor = p[:m], p[m]
        if self.law == "capstan":
            size = band * np.maximum(T_N, 1e-3)
            raw = factor * size / ev.cable_stiffness_N_per_m
        else:                     # the same band on every row
            size = np.broadcast_to(band, np.shape(T_N))
            raw = np.broadcast_to(factor * band / ev.cable_stiffness_N_per_m, np.shape(T_N))
        return np.maximum(raw, MIN_TRAVEL_M), size, raw

    def tangent_ok(self, rows) -> bool:
        """The tangent is taken over the whole log at given poses (not a sequential prediction's rows)."""
        return self.settled or rows.state_prev is None

    def d_adjust_tension(self, ev, stretch_m, d_stretch, T_N, d_T, T_out_N, p, cols):
        """Tangent of :meth:`adjust_tension` over the whole log: the play operator differentiated row by row.

        The input steps ``(dc + f dl / S) / travel`` move with the stick travel (the band, the stick factor and,
        under the capstan law, the tension); the state carries its tangent along the ramps
        (:func:`_band_tangent`); the first state has its own column.
        """
        if self.settled:
            return d_T
        m, P = self.n_cables, d_T.shape[-1]
        band, factor, s0 = p[:m], p[m], p[m + 1]
        hot = one_hot(cols, P)
        d_band, d_factor, d_s0 = hot[:m], hot[m], hot[m + 1]                  # (m, P), (P,), (P,)
        k = ev.cable_stiffness_N_per_m
        travel, size, raw = self._travel(ev, T_N, p)
        if self.law == "capstan":
            d_size = (np.maximum(T_N, 1e-3)[..., None] * d_band[None]
                      + (band * (T_N > 1e-3))[..., None] * d_T)
        else:
            d_size = np.broadcast_to(d_band[None], d_T.shape)
        d_travel = np.where((raw > MIN_TRAVEL_M)[..., None],
                            (size[..., None] * d_factor + factor * d_size) / k[:, None], 0.0)
        rows = ev.rows
        dc, dl = rows.steps_since_previous
        step = ramp_input(dc, dl, rows.ramp_shape_m, travel, factor)          # (n, S, m)
        S = step.shape[1]
        d_step = ((np.asarray(dl, float)[:, None, :, None] / S) * d_factor / travel[:, None, :, None]
                  - step[..., None] * (d_travel / travel[..., None])[:, None])
        restart = (np.arange(len(rows)) == 0) if self.memory == "carried" else rows.positions == 0
        s, ds = _band_tangent(step, np.ascontiguousarray(d_step), float(s0), np.ascontiguousarray(d_s0),
                              restart, CORNER)
        if self.law == "capstan":
            grow = np.exp(s * band)
            return d_T * grow[..., None] + (T_N * grow)[..., None] * (ds * band[:, None] + s[..., None] * d_band)
        slides = (T_N + s * band > 0)[..., None]
        return np.where(slides, d_T + ds * band[:, None] + s[..., None] * d_band, 0.0)

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            The law and memory, and the tension band per cable (percent, capstan) or the band forces (N, Coulomb).
        """
        p = np.asarray(p, float)
        if self.law == "capstan":
            return {"law": self.law, "memory": self.memory,
                    "tension_band_percent": (100 * (np.exp(p[:self.n_cables]) - 1)).tolist()}
        return {"law": self.law, "memory": self.memory, "friction_force_N": p[:self.n_cables].tolist()}
