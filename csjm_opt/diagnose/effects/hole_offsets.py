"""``hole_offsets``: position errors of the platform and base holes.

6 m parameters (36 on a six-cable rig, m its cable count), ``dA_i`` (in {A}) and ``dB_i`` (in {B}),
m. Several directions
are weakly determined by moment data (e.g. moving a hole along its cable),
so the fit carries the prior range as a proper zero-mean Gaussian prior (``prior_sd``: the
+-4 mm range is +-2 sd), and the selection prices only the subspace the log identifies
(:mod:`csjm_opt.diagnose.fitting.evidence`).
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot

#: Plausible hole position error per coordinate (m).
RANGE_M = 4e-3


class HoleOffsets(Effect):
    """Offsets of the m platform holes and m base holes (m)."""

    name = "hole_offsets"
    description = "hole position errors dA_i (in {A}), dB_i (in {B}), m"

    def __init__(self, n_cables: int = 6, prior_sd_m: float = RANGE_M / 2):
        self.n_cables = int(n_cables)
        self.prior_sd_m = float(prior_sd_m)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``dA{i}_{x,y,z}_m`` (platform holes, in {A}) then ``dB{i}_{x,y,z}_m`` (base holes, in {B}),
            ``i = 1..m``: 6 m names (m).
        """
        return tuple(f"d{s}{i + 1}_{a}_m" for s in "AB" for i in range(self.n_cables) for a in "xyz")

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            1e-3 m for each of the 6 m coordinates.
        """
        return np.full(6 * self.n_cables, 1e-3)

    @property
    def prior_sd(self):
        """Standard deviation of the zero-mean Gaussian prior on every offset.

        Returns
        -------
        numpy.ndarray
            ``prior_sd_m`` (m) for each of the 6 m coordinates.
        """
        return np.full(6 * self.n_cables, self.prior_sd_m)

    def default_ranges(self):
        """A few mm per coordinate: beyond that the rig was built to another drawing."""
        return {n: (-RANGE_M, RANGE_M) for n in self.param_names}

    def adjust_geometry(self, ev, p):
        """Shift the platform holes ``ev.A_m`` (in {A}) and base holes ``ev.B_m`` (in {B}) by the offsets.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            Offsets (m): the first 3 m the platform holes, the last 3 m the base holes, row-major (m, 3).
        """
        m = self.n_cables
        ev.A_m = ev.A_m + p[:3 * m].reshape(m, 3)
        ev.B_m = ev.B_m + p[3 * m:].reshape(m, 3)

    def d_adjust_geometry(self, ev, p, cols, d_A, d_B):
        """Tangents of :meth:`adjust_geometry`: each coordinate moves by one on its own column."""
        m, P = self.n_cables, d_A.shape[-1]
        hot = one_hot(cols, P)
        return d_A + hot[:3 * m].reshape(m, 3, P), d_B + hot[3 * m:].reshape(m, 3, P)

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``platform_hole_offset_mm`` and ``base_hole_offset_mm``: the offset length of each hole (mm).
        """
        m = self.n_cables
        d = np.linalg.norm(np.asarray(p).reshape(2 * m, 3), axis=1)
        return {"platform_hole_offset_mm": (1e3 * d[:m]).tolist(), "base_hole_offset_mm": (1e3 * d[m:]).tolist()}
