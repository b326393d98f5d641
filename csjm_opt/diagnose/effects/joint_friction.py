"""``joint_friction``: Coulomb friction in the passive spherical joint.

The ball joint at O resists the platform's rotation with a dry-friction moment bounded per
axis of {A}, ``|tau_f,j| <= M`` (a box, as MuJoCo's ball-joint ``frictionloss``; one parameter
``M``, N m). Where the platform slides, the moment opposes the motion; the balance on the cable
platform becomes::

    J^T T + tau_load - M s = 0,    s_j = tanh(dzeta_j / SLIP_TRAVEL_RAD)

``dzeta`` is the platform's rotation (body frame) since the previous row of the log, recovered
from the cables' length changes (``dc = -J dzeta``, least squares over the m cables): from the
measured poses when fitting, from the model's own predicted poses (row after row, along the
ramp of the inputs) when predicting held-out cycles. ``SLIP_TRAVEL_RAD`` rounds the sign over a
rotation a few times the tracker's noise: a row that hardly moved feels a fraction of the bound
(its joint stuck somewhere inside the box).

Limitation (stated, not hidden): the state is the last step's direction, not a play operator
with memory of its own: an axis that stops moving between two rows is taken as unloaded by
friction instead of holding the moment it had. On logs of load steps (every row moves) the two
agree; on logs with rows that repeat a pose they do not.

Settled variant (``memory="settled"``): where each load is hung at once and the platform comes to
rest under its own dynamics, the joint sticks wherever the motion dies out, anywhere its moment
stays in the box; the row is explained when *some* moment in the box balances it (no direction of
motion needed): the stick condition of :mod:`csjm_opt.diagnose.fitting.friction_stick`, with three
generators ``M e_k`` (the box's axes, the same for every cable geometry) where cable friction has
one generator per cable, ``F_j J_j`` (shaped by the cables' Jacobian at each pose).

Prior: half-normal on ``M >= 0`` over ``(0, RANGE_NM)``.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot

#: Plausible friction moment of a ball joint (N m): a dry, preloaded joint of this size stays below it.
RANGE_NM = 0.3
#: Rotation (rad) over which the friction moment turns from one side of the box to the other.
SLIP_TRAVEL_RAD = 1e-3


def rotation_steps(J: np.ndarray, dc_m: np.ndarray) -> np.ndarray:
    """The platform's rotation (n, 3) rad that explains cable length changes ``dc_m`` (n, m): ``dc = -J dzeta``.

    Parameters
    ----------
    J : numpy.ndarray
        Cable Jacobian (n, m, 3) (:func:`csjm_opt.model.kinematics.cable_terms`).
    dc_m : numpy.ndarray
        Length changes (n, m); non-finite entries count as no change.

    Returns
    -------
    numpy.ndarray
        Least-squares rotation steps (body frame).
    """
    dc = np.nan_to_num(np.asarray(dc_m, float))
    JtJ = np.einsum("nki,nkj->nij", J, J)
    return -np.linalg.solve(JtJ, np.einsum("nki,nk->ni", J, dc)[..., None])[..., 0]


class JointFriction(Effect):
    """Coulomb friction moment of the ball joint, ``|tau_f,j| <= M`` per axis of {A}."""

    #: from M = 0 along the loading path, a pair's fit reached up to 47 % of the evidence gap the step predicted
    #: (``studies/pair_screen``, 400 pairs on the 47 validation logs)
    step_from_nominal = "loose"
    name = "joint_friction"
    description = ("Coulomb friction in the spherical joint: a moment |tau_f,j| <= M per axis of {A} "
                   "opposing the platform's rotation")
    #: Variants: ``"step"`` (the moment opposes each row's rotation) or ``"settled"`` (any moment in the box).
    MEMORIES = ("step", "settled")

    def __init__(self, n_cables: int = 6, memory: str = "step"):
        super().__init__(n_cables=n_cables)
        if memory not in self.MEMORIES:
            raise ValueError(f"memory must be one of {self.MEMORIES}")
        self.memory = memory
        self.settled = memory == "settled"

    @property
    def path_dependent(self) -> bool:  # type: ignore[override]
        """Whether the moment follows the rows' motion (not for the settled variant)."""
        return not self.settled

    def stick_columns(self, ev) -> tuple[np.ndarray, np.ndarray]:
        """Generators of the settled variant's stick set in the balance: the box's axes.

        Parameters
        ----------
        ev : Evaluation

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            ``(n, 3, 3)`` moments (N m) per unit of the bound, and the parameter each column's bound
            is (all three: ``M``).
        """
        n = len(ev.rows)
        return np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), np.zeros(3, int)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``("joint_friction_Nm",)``: the bound ``M`` (N m).
        """
        return ("joint_friction_Nm",)

    @property
    def scales(self):
        """Typical parameter magnitude (optimiser scaling).

        Returns
        -------
        numpy.ndarray
            ``[0.03]`` N m.
        """
        return np.array([0.03])

    @property
    def lower_bounds(self):
        """``M >= 0``.

        Returns
        -------
        numpy.ndarray
        """
        return np.zeros(1)

    def default_ranges(self):
        """Up to :data:`RANGE_NM`."""
        return {"joint_friction_Nm": (0.0, RANGE_NM)}

    def slide_direction(self, ev) -> np.ndarray:
        """``s`` (n, 3) in [-1, 1]: the direction of each row's rotation since the previous row, rounded.

        Parameters
        ----------
        ev : Evaluation
            With ``lengths_m`` and ``cable_jacobian`` set.

        Returns
        -------
        numpy.ndarray
        """
        rows = ev.rows
        # the direction depends on J, the lengths and the rows alone: the model hands back the same (read-only)
        # J and lengths while the poses and holes stay (a fit's steps in the other parameters): the last one kept
        last = self.__dict__.get("_last")
        if last is not None and last[0] is ev.cable_jacobian and last[1] is ev.lengths_m and last[2] is rows:
            return last[3]
        if rows.lengths_prev_m is None:          # the whole log at the given poses, in order
            dc, _ = rows.steps_since_previous
        else:                                    # one row of a sequential prediction (NaN: no history)
            dc = ev.lengths_m - rows.lengths_prev_m
        s = np.tanh(rotation_steps(ev.cable_jacobian, dc) / SLIP_TRAVEL_RAD)
        if ev.cable_jacobian is not None and not ev.cable_jacobian.flags.writeable:   # a remembered geometry
            s.setflags(write=False)
            self._last = (ev.cable_jacobian, ev.lengths_m, rows, s)
        return s

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_last", None)          # a cache, not state: not pickled
        return state

    def adjust_balance(self, ev, g_Nm, p):
        """Add the friction moment ``-M s`` (n, 3) N m on the platform.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`).
        g_Nm : numpy.ndarray
            The balance so far (n, 3).
        p : numpy.ndarray
            ``[M]`` (N m).

        Returns
        -------
        numpy.ndarray
        """
        if self.settled:                 # the moment is latent per row (:meth:`stick_columns`)
            return g_Nm
        return g_Nm - p[0] * self.slide_direction(ev)

    def tangent_ok(self, rows) -> bool:
        """The tangent is taken over the whole log at given poses (not a sequential prediction's rows)."""
        return self.settled or rows.lengths_prev_m is None

    def d_adjust_balance(self, ev, d_g, p, cols):
        """Tangent of :meth:`adjust_balance`: ``-s`` on the moment's column, ``-M ds`` where J moves (holes, link).

        With ``x = -(J^T J)^-1 J^T dc`` (:func:`rotation_steps`): ``dx = -(J^T J)^-1 (dJ^T dc + d(J^T J) x)``.
        """
        if self.settled:
            return d_g
        s = self.slide_direction(ev)
        out = d_g - s[..., None] * one_hot(cols, d_g.shape[-1])[0]
        dJ = ev.d_cable_jacobian
        if dJ is not None:
            J = ev.cable_jacobian
            dc = np.nan_to_num(np.asarray(ev.rows.steps_since_previous[0], float))
            x = rotation_steps(J, dc)
            JtJ = np.einsum("nki,nkj->nij", J, J)
            dJtJ = np.einsum("nkip,nkj->nijp", dJ, J)
            rhs = np.einsum("nkip,nk->nip", dJ, dc) + np.einsum("nijp,nj->nip", dJtJ + np.swapaxes(dJtJ, 1, 2), x)
            dx = -np.linalg.solve(JtJ[:, None], np.moveaxis(rhs, 2, 1)[..., None])[..., 0]     # (n, P, 3)
            out = out - p[0] * (1.0 - s ** 2)[..., None] * np.moveaxis(dx, 1, 2) / SLIP_TRAVEL_RAD
        return out

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``friction_moment_Nm``: the bound ``M``.
        """
        return {"friction_moment_Nm": float(p[0])}
