"""Fast tension planning for the dynamic controllers (same QP as :func:`csjm_opt.plan_tensions`).

``min ||T - t_ref||^2`` subject to ``J^T T + tau_weight + tau = 0`` and
``t_min <= T <= t_max``, solved by the compiled primal-dual active set of
:mod:`csjm_opt.planning.kernels` with J and the weight moment from the
model layer's kernels (:meth:`csjm_opt.model.Model.pose_terms`; about 15x cheaper per call than the
validated ``plan_tensions``, which is the fallback: it raises
:class:`~csjm_opt.errors.InfeasibleLoad` when no tensions hold the load).
"""

from __future__ import annotations

import numpy as np

from ...model.numeric import model_for
from ...model.rig import Rig
from ...planning import kernels as qp_kernels
from ...planning.planner import plan_tensions


class TensionQP:
    """Plans tensions for one rig, warm-starting the active set from the last call."""

    def __init__(self, rig: Rig, t_ref_N: np.ndarray | None = None):
        self.rig = rig
        self.t_ref = (rig.t_mid_N if t_ref_N is None else np.broadcast_to(np.asarray(t_ref_N, float),
                                                                               (rig.n_cables,))).copy()
        self._model = model_for(rig)
        self._lower = np.zeros(rig.n_cables, np.bool_)
        self._upper = np.zeros(rig.n_cables, np.bool_)

    def __call__(self, R: np.ndarray, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """Tensions (m,) N that hold ``tau_ext_A_Nm`` (plus the weight) at ``R``."""
        R = np.ascontiguousarray(R, dtype=np.float64)
        _, J, tau_w = self._model.pose_terms(R)
        T = np.zeros(self.rig.n_cables)
        b = -(tau_w + np.asarray(tau_ext_A_Nm, float))
        status = qp_kernels.solve_one(J, b, self.t_ref, self.rig.t_min_N, self.rig.t_max_N, self._lower,
                                      self._upper, T, 40)
        if status == qp_kernels.OK:
            return T
        self._lower[:], self._upper[:] = False, False
        return plan_tensions(self.rig, R, tau_ext_A_Nm, self.t_ref).tensions_N
