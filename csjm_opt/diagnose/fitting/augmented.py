"""The nominal moment balance augmented by effects, with nominal nuisance parameters.

For each row (rest lengths ``l``, measured moment ``tau_meas``, pose ``R_m``
of the measured body) the balance residual in N m is::

    g = J(R_c)^T T(e) + E (tau_ext + tau_w(R_m)),   e = c(R_c) - (l + dl)

with ``tau_ext = tau_meas`` and ``tau_w = (m r) x (R_b^T g_B)`` nominally,
``R_b = R_c = R_m`` (true body pose, cable platform pose) and ``E = I``
unless an effect says otherwise (see :mod:`csjm_opt.diagnose.effects.base`),
and ``T = k e`` for taut cables. The one nuisance parameter shared by every
model (the null model ``nominal_refit`` has only it) is ``dl_common_m``, a
common rest-length offset (pretension error: drives are zeroed to within a
fraction of a mm, always). A common stiffness error is the named effect
``stiffness_scale``, not a nuisance. Parameter vector: nuisance, then each
effect's.
``g(R) = 0`` defines the model's predicted pose (:func:`predict_poses`).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Sequence

import numpy as np

from ...model import kinematics as kin
from ...model.rig import Rig
from ..effects import Effect
from ..effects.base import EARLY_HOOKS, LATE_HOOKS, one_hot

NUISANCE_NAMES = ("dl_common_m",)
NUISANCE_SCALES = np.array([2e-4])
N_NUISANCE = len(NUISANCE_NAMES)


@dataclasses.dataclass(frozen=True, eq=False)
class Rows:
    """Per-row inputs of the balance (the part of a log the model needs)."""

    rest_lengths_m: np.ndarray     # (n, m)
    tau_meas_A_Nm: np.ndarray      # (n, 3)
    cycle: np.ndarray              # (n,) rows of a cycle consecutive, in time order
    cable_steps_m: np.ndarray      # (n, m) change of each cable length since the previous row
                                   # of the cycle (from measured poses; 0 on a cycle's first row)
    # Sequential mode (forward prediction row after row): the previous row's
    # path state and cable lengths (NaN on a cycle's first row), else None.
    state_prev: np.ndarray | None = None
    lengths_prev_m: np.ndarray | None = None
    # Changes since the previous row *of the log* (across cycle boundaries too; 0 on the
    # log's first row): cable lengths at the measured poses, and commanded rest lengths.
    log_steps_m: np.ndarray | None = None
    rest_steps_m: np.ndarray | None = None
    # Path state and cable lengths the measured history leaves at the row before each
    # cycle's first row (NaN where there is none): where a predicted cycle starts.
    entry_state: np.ndarray | None = None
    entry_lengths_m: np.ndarray | None = None
    # Shape (n, S, m) of each cable's motion along the quasi-static ramp of the inputs into each row,
    # as a deviation from even steps (:mod:`csjm_opt.diagnose.fitting.friction_ramp`); None: one step.
    ramp_shape_m: np.ndarray | None = None
    # Inputs and pose of the log's row before each cycle's first row (NaN elsewhere): where the
    # ramp into a predicted cycle starts (set by :func:`with_entry` with the entry state).
    entry_rest_m: np.ndarray | None = None
    entry_tau_A_Nm: np.ndarray | None = None
    entry_R: np.ndarray | None = None

    def __len__(self) -> int:
        return self.rest_lengths_m.shape[0]

    def take(self, idx: np.ndarray) -> "Rows":
        """Rows ``idx`` (whole cycles, in order, for the sequence to stay meaningful)."""
        def sub(a):
            return None if a is None else a[idx]

        return Rows(self.rest_lengths_m[idx], self.tau_meas_A_Nm[idx], self.cycle[idx],
                    self.cable_steps_m[idx], sub(self.state_prev), sub(self.lengths_prev_m),
                    sub(self.log_steps_m), sub(self.rest_steps_m), sub(self.entry_state),
                    sub(self.entry_lengths_m), sub(self.ramp_shape_m), sub(self.entry_rest_m),
                    sub(self.entry_tau_A_Nm), sub(self.entry_R))

    @property
    def steps_since_previous(self) -> tuple[np.ndarray, np.ndarray]:
        """``(cable, rest)`` length changes (n, m) since the previous row of the log (m)."""
        c = self.cable_steps_m if self.log_steps_m is None else self.log_steps_m
        r = np.zeros_like(c) if self.rest_steps_m is None else self.rest_steps_m
        return c, r

    @functools.cached_property
    def tiled3(self) -> "Rows":
        """These rows three times over (3 n rows): the poses of a tangent's three steps in one evaluation."""
        return self.take(np.tile(np.arange(len(self)), 3))

    @functools.cached_property
    def positions(self) -> np.ndarray:
        """Position of each row within its cycle (0 = first row)."""
        first = np.r_[True, self.cycle[1:] != self.cycle[:-1]]
        start = np.maximum.accumulate(np.where(first, np.arange(len(first)), 0))
        return np.arange(len(first)) - start

    @functools.cached_property
    def sequence(self) -> list[np.ndarray]:
        """Row indices at position 1, 2, ... within their cycle (position 0 = first rows)."""
        pos = self.positions
        return [np.flatnonzero(pos == j) for j in range(1, int(pos.max(initial=0)) + 1)]


@dataclasses.dataclass
class Evaluation:
    """Mutable working state of one evaluation of the balance (hooks edit it)."""

    A_m: np.ndarray
    B_m: np.ndarray
    first_moment_A_kgm: np.ndarray
    tau_ext_A_Nm: np.ndarray
    R_cable: np.ndarray
    link_rotation: np.ndarray
    rows: Rows
    cable_stiffness_N_per_m: np.ndarray
    R_body: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))   # true body pose (adjust_frame)
    tau_weight_A_Nm: np.ndarray | None = None
    lengths_m: np.ndarray | None = None       # cable lengths at R_cable (set before adjust_tension)
    rest_lengths_m: np.ndarray | None = None  # actual rest lengths (n, m): commanded + common offset (adjust_rest)
    cable_jacobian: np.ndarray | None = None  # J (n, m, 3) at R_cable: J^T T is the cables' moment, dc = -J dzeta
    state_out: np.ndarray | None = None       # path state after this row (path-dependent effects)
    d_g: np.ndarray | None = None             # (n, 3, P) derivative of the balance (AugmentedModel.balance_derivative)
    d_lengths_m: np.ndarray | None = None     # (n, m, P) tangents of the cable lengths (pose, hole parameters)
    d_cable_jacobian: np.ndarray | None = None  # (n, m, 3, P) and of J


class AugmentedModel:
    """Nominal rig + nuisance parameters + a list of effects."""

    def __init__(self, rig: Rig, effects: Sequence[Effect] = ()):
        self.rig = rig
        self.effects = tuple(effects)
        self._A = np.asarray(rig.platform_holes_A_m, float)
        self._B = np.asarray(rig.base_holes_B_m, float)
        self._k = np.asarray(rig.cable_stiffness_N_per_m, float)
        self._mr = rig.platform_mass_kg * np.asarray(rig.com_A_m, float)
        for a in (self._A, self._B, self._k, self._mr):
            if a.flags.writeable and a.base is None:
                a.setflags(write=False)   # the model's constants (and cache keys, :func:`_kept`)
        self._g = np.asarray(rig.gravity_B_m_per_s2, float)
        sizes = [len(NUISANCE_NAMES)] + [e.n_params for e in self.effects]
        self._offsets = np.cumsum([0] + sizes)
        self._geometry: tuple | None = None     # the last cable terms: (R, A, B, lengths, J)
        self._weight: tuple | None = None       # the last weight moment: (R, first moment, moment)
        self._eye: dict[int, np.ndarray] = {}   # identity link rotations (n, 3, 3) by n, read-only

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_geometry"] = state["_weight"] = None   # caches, not state: not pickled to the workers
        return state

    def cable_terms(self, R: np.ndarray, A_m: np.ndarray, B_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cable lengths and Jacobian (:func:`csjm_opt.model.kinematics.cable_terms`), the last ones remembered.

        A fit evaluates the balance at the same poses and holes for every parameter its Jacobian
        perturbs that leaves the geometry alone (loads, tension laws, rest lengths): the last result
        is returned when the poses and holes are equal to the last ones, value for value (read-only
        arrays: bit for bit what a new evaluation gives).
        """
        last = self._geometry
        if last is not None and _same(last[0], R) and _same(last[1], A_m) and _same(last[2], B_m):
            return last[3], last[4]
        lengths, J = kin.cable_terms(R, A_m, B_m)
        lengths.setflags(write=False)
        J.setflags(write=False)
        self._geometry = (_kept(R), _kept(A_m), _kept(B_m), lengths, J)
        return lengths, J

    def weight_moment(self, R: np.ndarray, first_moment_A_kgm: np.ndarray) -> np.ndarray:
        """The weight's moment (:func:`csjm_opt.model.kinematics.weight_moment`), the last one remembered.

        As :meth:`cable_terms`: the last result (read-only) when the poses and the first moment are equal
        to the last ones, value for value.
        """
        last = self._weight
        if last is not None and _same(last[0], R) and _same(last[1], first_moment_A_kgm):
            return last[2]
        tau = kin.weight_moment(R, first_moment_A_kgm, self._g)
        tau.setflags(write=False)
        self._weight = (_kept(R), _kept(first_moment_A_kgm), tau)
        return tau

    def _identity(self, n: int) -> np.ndarray:
        """Identity rotations (n, 3, 3), read-only, the same object for the same ``n``."""
        eye = self._eye.get(n)
        if eye is None:      # a prediction alternates between n rows and a tangent's 3 n
            eye = self._eye[n] = np.broadcast_to(np.eye(3), (n, 3, 3))
        return eye

    @property
    def name(self) -> str:
        """Model name: the effect names joined by ``+``.

        Returns
        -------
        str
            ``"none"`` for the nominal model alone.
        """
        return "+".join(e.name for e in self.effects) or "none"

    @property
    def param_names(self) -> tuple[str, ...]:
        """Parameter names: the nuisance parameter ``dl_common_m`` (m), then each effect's.

        Returns
        -------
        tuple of str
            One name per parameter, in the order of ``theta``.
        """
        return NUISANCE_NAMES + tuple(n for e in self.effects for n in e.param_names)

    @property
    def n_params(self) -> int:
        """Number of parameters (nuisance plus every effect's).

        Returns
        -------
        int
            Length of ``theta``.
        """
        return int(self._offsets[-1])

    @property
    def scales(self) -> np.ndarray:
        """Typical magnitude of each parameter, for the optimiser's scaling.

        Returns
        -------
        numpy.ndarray
            Nuisance scale (2e-4 m) then each effect's scales, same units as the parameters.
        """
        return np.concatenate([NUISANCE_SCALES] + [e.scales for e in self.effects])

    @property
    def lower_bounds(self) -> np.ndarray:
        """Lower bounds of the parameters.

        Returns
        -------
        numpy.ndarray
            ``-inf`` for the nuisance parameter, then each effect's lower bounds.
        """
        return np.concatenate([np.full(N_NUISANCE, -np.inf)] + [e.lower_bounds for e in self.effects])

    @property
    def upper_bounds(self) -> np.ndarray:
        """Upper bounds of the parameters.

        Returns
        -------
        numpy.ndarray
            ``+inf`` for the nuisance parameter, then each effect's upper bounds.
        """
        return np.concatenate([np.full(N_NUISANCE, np.inf)] + [e.upper_bounds for e in self.effects])

    @property
    def prior_sd(self) -> np.ndarray:
        """Ridge prior sd per parameter (inf = no prior)."""
        parts = [np.full(N_NUISANCE, np.inf)]
        for e in self.effects:
            parts.append(np.full(e.n_params, np.inf) if e.prior_sd is None else e.prior_sd)
        return np.concatenate(parts)

    def x0(self) -> np.ndarray:
        """Starting parameter vector: the nuisance parameter at zero and each effect's ``x0``.

        Returns
        -------
        numpy.ndarray
            Shape (n_params,).
        """
        return np.concatenate([np.zeros(N_NUISANCE)] + [e.x0() for e in self.effects])

    def starts(self) -> list[np.ndarray]:
        """Starting parameter vectors: the nominal model, then each effect's extra starts."""
        out = [self.x0()]
        for i, e in enumerate(self.effects):
            for alt in e.extra_starts():
                x = self.x0()
                x[self._offsets[i + 1]:self._offsets[i + 2]] = alt
                out.append(x)
        return out

    def effect_params(self, theta: np.ndarray) -> list[np.ndarray]:
        """Split a full parameter vector into the effects' slices.

        Parameters
        ----------
        theta : numpy.ndarray
            Full parameter vector: the nuisance parameters, then each effect's slice.

        Returns
        -------
        list of numpy.ndarray
            One slice (a view of ``theta``) per effect, in order.
        """
        return [theta[self._offsets[i + 1]:self._offsets[i + 2]] for i in range(len(self.effects))]

    @property
    def path_dependent(self) -> bool:
        """Whether any effect depends on the loading path (e.g. friction with memory).

        Returns
        -------
        bool
            True if some effect has ``path_dependent`` set.
        """
        return any(getattr(e, "path_dependent", False) for e in self.effects)

    def balance(self, R_m: np.ndarray, rows: Rows, theta: np.ndarray) -> np.ndarray:
        """Moment balance residual ``g`` (n, 3) N m at measured-body poses ``R_m``."""
        return self.evaluate(R_m, rows, theta)[0]

    def rows_independent(self, rows: Rows) -> bool:
        """Whether each row's balance depends on that row alone (then rows can be evaluated in any batch).

        True for a model without memory, and for a path-dependent one stepped row by row (``rows``
        carry the previous row's state: a sequential prediction); False where the state runs over
        the log (a fit at the measured poses), or where an effect says its rows are coupled
        (``rows_coupled``).
        """
        if any(getattr(e, "rows_coupled", False) for e in self.effects):
            return False
        return not self.path_dependent or rows.state_prev is not None

    def tangent(self, R_m: np.ndarray, rows: Rows, theta: np.ndarray, g0: np.ndarray | None = None,
                h: float = 1e-7) -> np.ndarray:
        """Finite-difference pose tangent ``dg/dzeta`` (n, 3, 3), as :func:`csjm_opt.model.kinematics.tangent`.

        Where the rows are independent (:meth:`rows_independent`) the three steps are one evaluation
        of the rows three times over (the same numbers, one pass through the effects instead of three).
        """
        if not self.rows_independent(rows):
            return kin.tangent(lambda R: self.balance(R, rows, theta), R_m, g0, h)
        g0 = self.balance(R_m, rows, theta) if g0 is None else g0
        n = len(rows)
        R3 = np.concatenate([R_m @ E for E in kin.basis_rotations(float(h))])
        g3 = self.balance(R3, rows.tiled3, theta).reshape(3, n, 3)
        G = np.empty(np.shape(g0) + (3,))
        for j in range(3):
            G[..., j] = (g3[j] - g0) / h
        return G

    def exact_params(self, rows: Rows) -> np.ndarray:
        """Which parameters :meth:`balance_derivative` differentiates exactly on ``rows`` (bool, (n_params,)).

        Every parameter whose effect's hooks all carry their tangents (``d_<hook>``): the common rest-length
        offset, loads, rest lengths, tension laws, further moments, and hole positions and the link's twist
        where every pose and geometry hook of the model carries its tangent (a guide's exit point does not:
        then only the parameters that enter after the cables are placed). Registration parameters (the measured
        body's frame) are left to differences. None where an effect cannot give the tangent of a late hook it
        overrides on these rows (e.g. friction stepped row by row in a prediction).
        """
        key = (rows.state_prev is None, rows.lengths_prev_m is None)
        known = self.__dict__.setdefault("_exact", {})
        if key not in known:
            known[key] = self._exact_params(rows)
        return known[key].copy()

    def _exact_params(self, rows: Rows) -> np.ndarray:
        mask = np.zeros(self.n_params, bool)
        if not all(e.tangent_ok(rows) for e in self.effects):
            return mask
        mask[:N_NUISANCE] = True
        placed = ("adjust_pose", "adjust_geometry")
        geometric = all(e.has_tangent(h) for e in self.effects for h in placed if e.overrides(h))
        reads_load = any(e.reads_load for e in self.effects)
        for i, e in enumerate(self.effects):
            hooks = {h for h in LATE_HOOKS + EARLY_HOOKS if e.overrides(h)}
            if "adjust_frame" in hooks or (hooks & set(placed) and not geometric):
                continue
            if "adjust_load" in hooks and reads_load and not geometric:
                continue
            mask[self._offsets[i + 1]:self._offsets[i + 2]] = True
        return mask

    def balance_derivative(self, R_m: np.ndarray, rows: Rows, theta: np.ndarray,
                           cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(g, dg/dtheta[:, :, cols])``: the balance and its exact derivative (forward mode) (n, 3, P).

        ``cols``: parameter indices among :meth:`exact_params` (N m per unit of each parameter).
        """
        g, ev = self.evaluate(R_m, rows, theta, np.asarray(cols, int))
        assert ev.d_g is not None
        return g, ev.d_g

    def evaluate(self, R_m: np.ndarray, rows: Rows, theta: np.ndarray,
                 tangent_cols: np.ndarray | None = None) -> tuple[np.ndarray, Evaluation]:
        """``(g, evaluation)``; the evaluation holds intermediate quantities (path state, lengths).

        ``tangent_cols``: parameters (indices, :meth:`exact_params`) whose derivative of ``g`` is carried
        alongside (forward mode through the hooks) into ``evaluation.d_g`` (n, 3, P).
        """
        theta = np.asarray(theta, float)
        n = len(rows)
        eye = self._identity(n)
        ev = Evaluation(self._A, self._B, self._mr, rows.tau_meas_A_Nm, R_m, eye, rows, self._k, R_m)
        params = self.effect_params(theta)
        tan: dict[str, Any] | None = None
        if tangent_cols is not None:
            where = np.full(self.n_params, -1)
            where[tangent_cols] = np.arange(len(tangent_cols))
            P = len(tangent_cols)
            # tangents: external moment, first moment, the cable platform's pose (a right rotation), the link's
            # rotation (None: zero), the holes
            tan = {"cols": [where[self._offsets[i + 1]:self._offsets[i + 2]] for i in range(len(self.effects))],
                   "tau": np.zeros((n, 3, P)), "first": np.zeros((3, P)), "nuisance": where[:N_NUISANCE],
                   "eta": np.zeros((n, 3, P)), "link": None,
                   "A": np.zeros(np.shape(self._A) + (P,)), "B": np.zeros(np.shape(self._B) + (P,))}
        for i, (e, p) in enumerate(zip(self.effects, params)):
            if tan is not None and e.has_tangent("adjust_load"):
                tan["tau"], tan["first"] = e.d_adjust_load(ev, p, tan["cols"][i], tan["tau"], tan["first"])
            e.adjust_load(ev, p)
        for e, p in zip(self.effects, params):
            e.adjust_frame(ev, p)
        assert ev.R_body is not None   # set by adjust_frame
        ev.R_cable = ev.R_body
        ev.tau_weight_A_Nm = self.weight_moment(ev.R_body, ev.first_moment_A_kgm)
        if tan is not None:
            # the weight's moment is linear in the first moment: its tangent is the moment of the first moment's
            tan["load"] = tan["tau"]
            if np.any(tan["first"]):
                unit = np.stack([kin.weight_moment(ev.R_body, e_k, self._g) for e_k in np.eye(3)], axis=-1)
                tan["load"] = tan["load"] + unit @ tan["first"]
        for i, (e, p) in enumerate(zip(self.effects, params)):
            if tan is not None and e.has_tangent("adjust_pose"):
                tan["eta"], tan["link"] = e.d_adjust_pose(ev, p, tan["cols"][i], tan["load"], tan["eta"],
                                                          tan["link"])
            e.adjust_pose(ev, p)
        for i, (e, p) in enumerate(zip(self.effects, params)):
            if tan is not None and e.has_tangent("adjust_geometry"):
                tan["A"], tan["B"] = e.d_adjust_geometry(ev, p, tan["cols"][i], tan["A"], tan["B"])
            e.adjust_geometry(ev, p)
        ev.rest_lengths_m = rows.rest_lengths_m + theta[0]
        if tan is not None:
            tan["rest"] = np.zeros(np.shape(ev.rest_lengths_m) + (P,))
            tan["rest"] += one_hot(tan["nuisance"], P)[0]
        for i, (e, p) in enumerate(zip(self.effects, params)):
            if tan is not None and e.has_tangent("adjust_rest"):
                tan["rest"] = e.d_adjust_rest(ev, p, tan["cols"][i], tan["rest"])
            e.adjust_rest(ev, p)
        lengths, J = self.cable_terms(ev.R_cable, ev.A_m, ev.B_m)
        ev.lengths_m, ev.cable_jacobian = lengths, J
        stretch = lengths - ev.rest_lengths_m
        T = self._k * np.maximum(stretch, 0.0)
        if tan is not None:
            d_stretch = -tan["rest"]
            if np.any(tan["eta"]) or np.any(tan["A"]) or np.any(tan["B"]):
                ev.d_lengths_m, ev.d_cable_jacobian = _cable_tangents(ev, lengths, tan["eta"], tan["A"], tan["B"])
                d_stretch = d_stretch + ev.d_lengths_m
            d_T = (self._k * (stretch > 0))[..., None] * d_stretch
        for i, (e, p) in enumerate(zip(self.effects, params)):
            T_in = T
            T = e.adjust_tension(ev, stretch, T, p)
            if tan is not None and e.has_tangent("adjust_tension"):
                d_T = e.d_adjust_tension(ev, stretch, d_stretch, T_in, d_T, T, p, tan["cols"][i])
        tau_load = ev.tau_ext_A_Nm + ev.tau_weight_A_Nm
        # the link's rotation is the identity unless an effect set one (then the product is tau_load exactly)
        g = np.einsum("nij,ni->nj", J, T) + (tau_load if ev.link_rotation is eye else
                                             np.einsum("nij,nj->ni", ev.link_rotation, tau_load))
        if tan is not None:
            d_g = np.swapaxes(J, 1, 2) @ d_T + (tan["load"] if ev.link_rotation is eye else
                                                 ev.link_rotation @ tan["load"])
            if ev.d_cable_jacobian is not None:
                d_g += (T[:, None, :] @ ev.d_cable_jacobian.reshape(n, T.shape[1], -1)).reshape(n, 3, P)
            if tan["link"] is not None:
                d_g += np.swapaxes((np.moveaxis(tan["link"], 3, 1) @ tau_load[:, None, :, None])[..., 0], 1, 2)
            ev.d_g = d_g
        for i, (e, p) in enumerate(zip(self.effects, params)):
            g = e.adjust_balance(ev, g, p)
            if tan is not None and ev.d_g is not None and e.has_tangent("adjust_balance"):
                ev.d_g = e.d_adjust_balance(ev, ev.d_g, p, tan["cols"][i])
        return g, ev

    def predict_poses(self, rows: Rows, theta: np.ndarray, R_init: np.ndarray) -> kin.PoseSolution:
        """Equilibrium poses of the measured body for each row (forward statics).

        Path-dependent models are stepped row after row within each cycle (all
        cycles at once), each row starting from the state the model itself
        reached on the previous row: predictions use only the log's inputs. Rows that carry ramps
        (``ramp_shape_m``, a path of :func:`csjm_opt.diagnose.fitting.friction_path.on_predicted_path`) are
        reached along the ramp of their inputs (:func:`csjm_opt.diagnose.fitting.friction_ramp.predict_ramp`).
        """
        if not self.path_dependent:
            return kin.solve_poses(lambda R: self.balance(R, rows, theta), R_init,
                                   tangent_fn=lambda R, g0: self.tangent(R, rows, theta, g0))
        if rows.ramp_shape_m is not None:
            from .friction_ramp import predict_ramp
            return predict_ramp(self, rows, theta, R_init)[0]
        n, m = np.shape(rows.rest_lengths_m)
        R_out, res = np.array(R_init, float), np.zeros(n)
        state, lengths = np.full((n, m), np.nan), np.full((n, m), np.nan)
        pos = rows.positions
        it = 0
        for j in range(int(pos.max(initial=0)) + 1):
            idx = np.flatnonzero(pos == j)
            prev = idx - 1 if j > 0 else None
            if prev is None:          # a cycle's first row: where the measured history left the path state
                has = rows.entry_state is not None and rows.entry_lengths_m is not None
                s_prev = rows.entry_state[idx] if has else np.zeros((len(idx), m))          # type: ignore[index]
                c_prev = rows.entry_lengths_m[idx] if has else np.full((len(idx), m), np.nan)  # type: ignore[index]
            else:
                s_prev, c_prev = state[prev], lengths[prev]
            sub = dataclasses.replace(rows.take(idx), state_prev=np.nan_to_num(s_prev), lengths_prev_m=c_prev)
            R0 = R_init[idx] if prev is None else R_out[prev]
            sol = kin.solve_poses(lambda R, sub=sub: self.balance(R, sub, theta), R0,  # type: ignore[misc]
                                  tangent_fn=lambda R, g0, sub=sub: self.tangent(R, sub, theta, g0))  # type: ignore[misc]
            _, ev = self.evaluate(sol.R, sub, theta)
            R_out[idx], res[idx] = sol.R, sol.residual_Nm
            state[idx] = ev.state_out if ev.state_out is not None else 0.0
            lengths[idx] = ev.lengths_m
            it = max(it, sol.iterations)
        return kin.PoseSolution(R_out, res, it)


def _kept(a) -> np.ndarray:
    """``a`` as a cache key: the array itself when it owns read-only floats (it cannot change), else a copy."""
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and not a.flags.writeable and a.base is None:
        return a
    return np.array(a, float)


def _same(key: np.ndarray, a) -> bool:
    """Whether ``a`` equals the cache key ``key`` value for value (the same object: at once)."""
    return key is a or (np.shape(a) == key.shape and bool((key == a).all()))


def _cable_tangents(ev: Evaluation, lengths: np.ndarray, eta: np.ndarray, d_A: np.ndarray,
                    d_B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangents of the cable lengths (n, m, P) and of J (n, m, 3, P) under pose and hole tangents.

    The cable platform's pose ``R exp(hat(eta))`` (``eta`` (n, 3, P)), the holes ``d_A``, ``d_B`` (m, 3, P).

    With ``v_i = R^T b_i - a_i`` (:func:`csjm_opt.model.cable_terms.geometry`), ``c = |v|``, ``u = v / c``,
    ``j = a x u``: ``dv = R^T db + (R^T b) x eta - da``, ``dc = u . dv``, ``du = (dv - u dc) / c``,
    ``dj = da x u + a x du``.
    """
    R, A, B = ev.R_cable, np.asarray(ev.A_m, float), np.asarray(ev.B_m, float)
    n, m = lengths.shape
    P = eta.shape[-1]
    Rb = B @ R                                              # rows R^T b_i (n, m, 3)
    u = (Rb - A) / lengths[..., None]
    dv = np.broadcast_to(-d_A, (n, m, 3, P)).copy()
    if np.any(d_B):
        dv += np.swapaxes(R, 1, 2)[:, None] @ d_B
    if np.any(eta):
        dv += _cross2(Rb[..., None], eta[:, None])
    dc = (u[:, :, None, :] @ dv)[:, :, 0, :]
    du = (dv - u[..., None] * dc[:, :, None, :]) / lengths[..., None, None]
    dJ = _cross2(np.broadcast_to(A, u.shape)[..., None], du)
    if np.any(d_A):
        dJ += _cross2(d_A, u[..., None])
    return dc, dJ


def _cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along axis -2 (the vectors' axis; the last axis holds the tangent columns), broadcast."""
    a0, a1, a2 = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    b0, b1, b2 = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-2)


def with_entry(model: "AugmentedModel", rows: Rows, R_meas: np.ndarray, theta: np.ndarray) -> Rows:
    """``rows`` with the path state the measured history leaves before each cycle (for prediction).

    The model is evaluated at the measured poses over the whole log (in log order); a cycle's
    first row gets the state and cable lengths of the log's previous row. Predicting a cycle
    then uses the measured past, never the cycle's own measurements.
    """
    if not model.path_dependent or any(getattr(e, "memory", "carried") in ("reset", "settled") for e in model.effects):
        return rows
    _, ev = model.evaluate(R_meas, rows, theta)
    n, m = np.shape(rows.rest_lengths_m)
    state, lengths = np.full((n, m), np.nan), np.full((n, m), np.nan)
    rest, tau, R = np.full((n, m), np.nan), np.full((n, 3), np.nan), np.full((n, 3, 3), np.nan)
    first = np.flatnonzero(np.r_[False, rows.cycle[1:] != rows.cycle[:-1]])
    if ev.lengths_m is not None:         # a model without a state of its own (joint friction) starts at 0
        state[first] = 0.0 if ev.state_out is None else ev.state_out[first - 1]
        lengths[first] = ev.lengths_m[first - 1]
        rest[first], tau[first] = rows.rest_lengths_m[first - 1], rows.tau_meas_A_Nm[first - 1]
        R[first] = R_meas[first - 1]
    return dataclasses.replace(rows, entry_state=state, entry_lengths_m=lengths, entry_rest_m=rest,
                               entry_tau_A_Nm=tau, entry_R=R)


def log_steps(lengths_m: np.ndarray) -> np.ndarray:
    """Change of each length since the previous row of the log (0 on the first row)."""
    d = np.zeros_like(lengths_m)
    d[1:] = lengths_m[1:] - lengths_m[:-1]
    return d


def cable_steps(cycle: np.ndarray, cable_lengths_m: np.ndarray) -> np.ndarray:
    """Length change of each cable since the previous row of the same cycle (0 on first rows)."""
    d = np.zeros_like(cable_lengths_m)
    same = cycle[1:] == cycle[:-1]
    d[1:][same] = (cable_lengths_m[1:] - cable_lengths_m[:-1])[same]
    return d
