"""``guide_radius``: base guides of finite radius (an eyelet, a hole's rounded edge, a ring).

The rig file puts each cable's base end at a point ``B_i``. A real guide is a ring of radius
``r`` around that point, in the base plane (normal ``n``, :func:`guide_axis`). The cable reaches
the ring from the drive side along the guide's axis and bears on the ring where the rest of its
path is shortest; with a frictionless contact it leaves the ring there, straight to the platform
hole ``p_i = R a_i``.

Geometry. Let the drive side reach the axis at ``D = B - L n`` (any ``L > 0``). For a point ``X``
on the ring, ``|D - X| = sqrt(L^2 + r^2)`` whatever ``X`` is, so the cable's length
``|D - X| + |X - p|`` is least where ``|X - p|`` is: at the ring's point nearest ``p``,

    X_i = B_i + r h_i / |h_i|,   h_i = (I - n n^T)(p_i - B_i)

(the rim, on the side towards the platform hole; ``h`` is the cable's direction projected on
the base plane). The cable length is ``|p_i - X_i|`` plus the constant ``sqrt(L^2 + r^2) - L``
(the same for every cable of one guide design: the common rest-length offset of the null
model takes it). Because ``X`` minimises the length over the ring, the length's derivative in
``p`` is the unit vector of the free segment (envelope theorem): the cable pulls the platform
along its straight segment from ``X``, so the model's cable terms with per-row base points
``X_i`` (:func:`csjm_opt.model.kinematics.cable_terms`) are both the geometry and the statics.
``r = 0`` is the nominal model exactly.

One parameter, ``guide_radius_m`` (the same for every guide: guides are made alike), with a
half-normal prior from 0: a radius is not negative. The exit point moves by ``r`` as the cable's
horizontal direction turns, which hole offsets can only copy with a fixed shift per hole: on
short tilts of a load experiment 36 hole coordinates mimic it, on longer logs they do not.
"""

from __future__ import annotations

import numpy as np

from .base import Effect

#: Plausible guide radius (m): an eyelet or a hole's rounded edge on a rig of this size.
RANGE_M = 1e-2
#: A start of the fit inside the range (m; see :meth:`GuideRadius.extra_starts`).
START_M = 1e-3
#: Largest radius the optimiser may try (m).
BOUND_M = 5e-2
#: Horizontal cable-direction length (m) below which the exit point stays at the ring's centre.
_TINY_M = 1e-12


def guide_axis(B_m: np.ndarray) -> np.ndarray:
    """Unit normal of the base plane, pointing from the base holes towards the joint centre O.

    Parameters
    ----------
    B_m : numpy.ndarray
        Base holes in {B} (m), shape (m, 3).

    Returns
    -------
    numpy.ndarray
        The normal ``n`` in {B}, shape (3,): the direction of least spread of the holes (the
        normal of their least-squares plane), signed so that ``n . (O - mean(B)) >= 0``.
    """
    B = np.asarray(B_m, float)
    centre = B.mean(axis=0)
    n = np.linalg.svd(B - centre)[2][-1]
    return -n if float(n @ -centre) < 0 else n


def ring_exit_points(R: np.ndarray, A_m: np.ndarray, B_m: np.ndarray, radius_m: float,
                     axis_B: np.ndarray) -> np.ndarray:
    """Where each cable leaves its guide ring: ``B_i + r h_i / |h_i|`` (module docstring).

    Parameters
    ----------
    R : numpy.ndarray
        Orientations of {A} in {B}, shape (n, 3, 3).
    A_m : numpy.ndarray
        Platform holes in {A} (m), shape (m, 3) or (n, m, 3).
    B_m : numpy.ndarray
        Ring centres (the rig's base holes) in {B} (m), shape (m, 3) or (n, m, 3).
    radius_m : float
        Ring radius ``r`` (m).
    axis_B : numpy.ndarray
        Unit normal of the base plane in {B}, shape (3,).

    Returns
    -------
    numpy.ndarray
        Exit points in {B} (m), shape (n, m, 3).
    """
    R = np.asarray(R, float)
    p = np.einsum("nij,...kj->nki", R, np.asarray(A_m, float))        # platform holes in {B}
    B = np.broadcast_to(np.asarray(B_m, float), p.shape)
    n = np.asarray(axis_B, float)
    h = p - B
    h = h - np.einsum("nki,i->nk", h, n)[..., None] * n
    norm = np.linalg.norm(h, axis=-1, keepdims=True)
    unit = np.where(norm > _TINY_M, h / np.maximum(norm, _TINY_M), 0.0)
    return B + float(radius_m) * unit


class GuideRadius(Effect):
    """Base guides are rings of radius ``r`` (m): each cable leaves its ring on the side of its platform hole."""

    name = "guide_radius"
    description = "base guides of radius r (m): the cable leaves the ring's rim towards its platform hole"

    def __init__(self, axis_B: np.ndarray | None = None, n_cables: int = 6):
        self.n_cables = int(n_cables)
        self.axis_B = None if axis_B is None else np.asarray(axis_B, float) / np.linalg.norm(axis_B)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``("guide_radius_m",)``: the radius of every base guide (m).
        """
        return ("guide_radius_m",)

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            ``[1e-3]`` (m).
        """
        return np.array([1e-3])

    @property
    def lower_bounds(self):
        """A radius is not negative.

        Returns
        -------
        numpy.ndarray
            ``[0.0]`` (m).
        """
        return np.array([0.0])

    @property
    def upper_bounds(self):
        """Largest radius the optimiser tries.

        Returns
        -------
        numpy.ndarray
            ``[BOUND_M]`` (m).
        """
        return np.array([BOUND_M])

    def extra_starts(self):
        """A further start inside the range, at ``START_M``.

        The optimiser (``least_squares``, trust region) sizes its first step by the start's own
        size; from the nominal start alone (``r = 0``, on the bound, moved inside by about 1e-10)
        its steps stayed that small and it stopped there (``ftol``), leaving a 2.7 mm eyelet at
        ``r = 0``. The nominal start stays (it costs two evaluations when it stops at once).

        Returns
        -------
        list of numpy.ndarray
            ``[[START_M]]`` (m).
        """
        return [np.array([START_M])]

    def default_ranges(self):
        """Up to 10 mm: an eyelet or the rounded edge of a guide hole on a rig of this size."""
        return {"guide_radius_m": (0.0, RANGE_M)}

    def adjust_geometry(self, ev, p):
        """Move each base hole to where its cable leaves the ring (per row).

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in
            place: ``ev.B_m`` becomes per-row, shape (n, m, 3).
        p : numpy.ndarray
            ``[guide_radius_m]`` (m).
        """
        if p[0] == 0.0:
            return
        axis = guide_axis(self._nominal_base(ev)) if self.axis_B is None else self.axis_B
        ev.B_m = ring_exit_points(ev.R_cable, ev.A_m, ev.B_m, p[0], axis)

    @staticmethod
    def _nominal_base(ev) -> np.ndarray:
        B = np.asarray(ev.B_m, float)
        return B if B.ndim == 2 else B[0]

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``guide_radius_mm``: the guides' radius (mm).
        """
        return {"guide_radius_mm": 1e3 * float(p[0])}
