"""Statics on a MuJoCo engine's net generalised force (the testbed plant's settling).

:class:`NetForceStatics` is the part of :class:`~csjm_opt.testbed.mujoco.engine.Engine`
that works on the frictionless net force at rest (``Engine.net``: MuJoCo's ``qfrc_smooth``
plus the run-time forces): its Jacobian by central differences under ``mj_integratePos``,
the tangent stiffness, the quasi-static travel left, stability, and Newton's method.
:func:`tendon_jacobian` reads MuJoCo's tendon Jacobian densely (MuJoCo 4 stores it sparse).
"""

from __future__ import annotations

import mujoco
import numpy as np


def tendon_jacobian(m: mujoco.MjModel, d: mujoco.MjData) -> np.ndarray:
    """Dense tendon Jacobian ``(ntendon, nv)`` at the data's kinematics.

    MuJoCo 4 stores ``ten_J`` sparse (rows by ``MjModel.ten_J_rownnz/rowadr/colind``); MuJoCo 3 stored it
    dense for small models. A tendon that does not span every dof (the tool's link) makes the two differ.

    Parameters
    ----------
    m : mujoco.MjModel
    d : mujoco.MjData

    Returns
    -------
    (ntendon, nv) array
    """
    J = np.asarray(d.ten_J, float).ravel()
    if J.size == m.ntendon * m.nv and not hasattr(m, "ten_J_rownnz"):
        return J.reshape(m.ntendon, m.nv).copy()
    dense = np.zeros((m.ntendon, m.nv))
    mujoco.mju_sparse2dense(dense, J, np.asarray(m.ten_J_rownnz, np.int32), np.asarray(m.ten_J_rowadr, np.int32),
                            np.asarray(m.ten_J_colind, np.int32))
    return dense



class NetForceStatics:
    """Mixin: statics on ``self.net`` (see the module doc); the engine provides ``m``, ``d``, ``nv``, ``net``."""

    m: mujoco.MjModel
    d: mujoco.MjData
    nv: int
    _scratch: mujoco.MjData

    def net(self, qpos: np.ndarray) -> np.ndarray:
        """Frictionless generalised net force at rest at ``qpos`` (provided by the engine).

        Parameters
        ----------
        qpos : (nq,) array

        Returns
        -------
        (nv,) array
        """
        raise NotImplementedError

    def _moved(self, q: np.ndarray, dofs: np.ndarray, z_sub: np.ndarray) -> np.ndarray:
        z = np.zeros(self.nv)
        z[dofs] = z_sub
        out = q.copy()
        mujoco.mj_integratePos(self.m, out, z, 1.0)
        return out

    def net_jacobian(self, q: np.ndarray, dofs: np.ndarray, h: float = 1e-7) -> np.ndarray:
        """``d net / d z`` over ``dofs`` at ``qpos = q`` (central differences under ``mj_integratePos``).

        Parameters
        ----------
        q : (nq,) array
        dofs : int array
        h : float, optional
            Step (rad).

        Returns
        -------
        (len(dofs), len(dofs)) array
        """
        E = np.eye(len(dofs))
        return np.column_stack([(self.net(self._moved(q, dofs, h * e))[dofs]
                                 - self.net(self._moved(q, dofs, -h * e))[dofs]) / (2 * h) for e in E])

    def remaining_travel(self) -> float:
        """Quasi-static distance (rad) still to travel: ``|K^-1 (c v)|``.

        ``c v`` is the joints' damping force at the current speed, ``K = -d net / d z`` the
        frictionless tangent stiffness. Near rest an overdamped motion carries the force imbalance
        by its damping; it stops after about that force over the stiffness. Stuck friction elements
        only stiffen the plant, so the frictionless ``K`` bounds the travel from above (``inf``
        where ``K`` is not positive definite). MuJoCo's soft friction keeps creeping far beyond
        this (a regularisation, not physics).

        Returns
        -------
        float
        """
        K = self.stiffness()
        if np.linalg.eigvalsh(K).min() <= 0:
            return float("inf")
        return float(np.linalg.norm(np.linalg.solve(K, np.asarray(self.m.dof_damping) * np.asarray(self.d.qvel))))

    def stiffness(self) -> np.ndarray:
        """Frictionless tangent stiffness ``-d net / d z`` (symmetric part) at the current pose, all dofs.

        Computed on a copy of the engine data (the run's state is not touched).

        Returns
        -------
        (nv, nv) array
        """
        mujoco.mj_copyData(self._scratch, self.m, self.d)
        d, self.d = self.d, self._scratch
        try:
            K = -self.net_jacobian(d.qpos.copy(), np.arange(self.nv))
        finally:
            self.d = d
        return 0.5 * (K + K.T)

    def _stable(self) -> bool:
        """Whether the frictionless tangent stiffness at the current pose is positive definite."""
        return bool(np.linalg.eigvalsh(self.stiffness()).min() > 0)

    def polish(self, dofs: np.ndarray, max_iter: int = 20, h: float = 1e-7) -> float:
        """Newton's method on :meth:`net` over ``dofs`` (others held); returns the largest net force left."""
        q = self.d.qpos.copy()
        r = self.net(q)[dofs]
        for _ in range(max_iter):
            if np.abs(r).max() < 1e-12:
                break
            step = -np.linalg.solve(self.net_jacobian(q, dofs, h), r)
            for _ in range(8):              # backtracking: a step that does not reduce the net force is halved
                q_new = self._moved(q, dofs, step)
                r_new = self.net(q_new)[dofs]
                if np.abs(r_new).max() < np.abs(r).max():
                    break
                step = 0.5 * step
            q, r = q_new, r_new
        self.d.qpos[:] = q
        self.d.qvel[:] = 0.0
        self.d.qfrc_applied[:] = 0.0
        mujoco.mj_forward(self.m, self.d)
        return float(np.abs(r).max())
