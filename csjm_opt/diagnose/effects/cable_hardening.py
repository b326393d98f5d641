"""``cable_hardening``: tension grows faster than linearly with stretch.

``T = k e (1 + h e)`` for a taut cable with stretch ``e = c - l`` (m); the
tangent stiffness ``k (1 + 2 h e)`` grows with tension. One shared ``h``
(1/m); the nominal stiffness scale fitted alongside absorbs a mean stiffening.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot


class CableHardening(Effect):
    """Quadratic hardening coefficient ``h`` (1/m), shared by the cables."""

    name = "cable_hardening"
    description = "T = k e (1 + h e): stiffness rising with stretch (h in 1/m)"

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``("hardening_per_m",)``: the hardening coefficient ``h`` (1/m).
        """
        return ("hardening_per_m",)

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            ``[10.0]`` (1/m).
        """
        return np.array([10.0])

    def default_ranges(self):
        """Up to 300 /m (stiffness x7 at 10 mm stretch); mild softening (-20 /m) allowed."""
        return {"hardening_per_m": (-20.0, 300.0)}

    def adjust_tension(self, ev, stretch_m, T_N, p):
        """Hardened tensions ``T (1 + h max(e, 0))``, i.e. ``k e (1 + h e)`` for taut cables.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`).
        stretch_m : numpy.ndarray
            Cable stretch ``e = c - l`` (m), shape (n, m).
        T_N : numpy.ndarray
            Tensions from the tension law so far (N), shape (n, m).
        p : numpy.ndarray
            ``[h]``, the hardening coefficient (1/m).

        Returns
        -------
        numpy.ndarray
            The changed tensions (N), shape (n, m).
        """
        return T_N * (1.0 + p[0] * np.maximum(stretch_m, 0.0))

    def d_adjust_tension(self, ev, stretch_m, d_stretch, T_N, d_T, T_out_N, p, cols):
        """Tangent of :meth:`adjust_tension`: ``dT (1 + h e+) + T h [e > 0] de + T e+ dh``."""
        e_pos = np.maximum(stretch_m, 0.0)
        return (d_T * (1.0 + p[0] * e_pos)[..., None] + (T_N * p[0] * (stretch_m > 0))[..., None] * d_stretch
                + (T_N * e_pos)[..., None] * one_hot(cols, d_T.shape[-1])[0])

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``stiffness_gain_at_20mm_stretch``: the tangent-stiffness factor ``1 + 2 h e`` at ``e = 20 mm``.
        """
        return {"stiffness_gain_at_20mm_stretch": float(1 + 2 * p[0] * 0.02)}
