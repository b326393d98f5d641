"""Friction however the rig came to rest: the stick condition per row, without a loading path.

A rig whose cables rub at their guides comes to rest wherever the motion stops: a load hung at
once swings the platform past the place a slow ramp would leave it, and the cables stick where
the swing dies out. The rest pose is then a *static Coulomb equilibrium*: the friction force
``f_j`` of every cable lies within its band ``|f_j| <= F_j`` and, with the elastic tensions, the
load and the weight, balances the platform::

    g_i(R) + J_i(R)^T f = 0,   |f_j| <= F_j                              (stick condition)

Which equilibrium of that set the rig took depends on its dynamics (inertia, damping, the order
in which cables stick), not on anything a log records; the play operator of
:mod:`csjm_opt.diagnose.effects.friction` predicts the one a slow ramp reaches.

Linearised at the measured pose (whitened pose residual ``a_i = W_i G_i^-1 g_i``, the
diagnosis's residual, :mod:`csjm_opt.diagnose.fitting.gauss_newton`), the poses that satisfy the stick condition
form a zonotope ``S_i = {a : a = -B_i f, |f| <= F}`` with generators ``F_j b_ij``
(``B_i = W_i G_i^-1 J_i^T``, 3 x m): the measured pose is explained when it lies within the
noise of ``S_i``. The residual of a row is its distance to the set,
``d_i = min_{|f| <= F} |a_i + B_i f|`` (a bounded least-squares problem per row,
:func:`stick_residual`).

Noise and friction are told apart by a likelihood, not by the distance alone (a band wide
enough holds every row, noise included): the rest pose is anywhere in ``S_i``, the measurement
adds noise of scale ``s``, and the density of the whitened residual is::

    p(a_i) = exp(-d_i^2 / (2 s^2)) / Z_i,   Z_i = V + A s sqrt(pi/2) + 2 M s^2 + (2 pi)^(3/2) s^3

``Z_i`` integrates the numerator over space exactly (Steiner's formula for the parallel body of
a convex set; :func:`log_normaliser`): ``V``, ``A`` and ``M / pi`` are the volume, surface
area and summed edge lengths of ``S_i``. With ``F = 0`` this is the Gaussian of every other
model; a wider band explains more rows but pays ``log Z_i`` on every row, so the band and the
noise scale are both estimated by maximum likelihood (:func:`fit_stick`), and the noise scale
is not inflated by friction (the within-cycle regression of :mod:`csjm_opt.diagnose.data.noise`
takes the scatter of stick positions for noise).

The noise scale, though, is not identified where the band is much wider than the noise (noise
inside the band looks like a stick position): the likelihood is flat below the true scale, and a
joint fit drifts to a band that holds every row and no noise. The diagnosis therefore fits the band
at a few noise scales and keeps the largest one the *held-out* rows do not reject
(:func:`settled_score`). Models are compared on held-out rows by their densities at that noise
scale: ``-2 s^2 log p`` per row less the Gaussian's constant, the squared distance plus the band's
price ``2 s^2 log(Z_i / Z0_i)``, which is a point model's squared error
(:func:`csjm_opt.diagnose.selection.scoring.equivalent_mse`).
"""

from __future__ import annotations

import itertools
from typing import Sequence

import numpy as np
from numba import njit
from scipy.optimize import minimize

from .gauss_newton import _safe_inv

#: Iterations of the accelerated projected gradient per row (the fallback of :func:`_project_row`).
MAX_ITER = 5000
#: The fallback stops when the squared step (in N^2, relative to the band) falls below this.
STEP_TOL = 1e-24
#: Relative size below which a generator, a facet normal or a volume counts as degenerate.
DEGENERATE = 1e-9
#: Iterations of a stick fit's L-BFGS-B (:meth:`SettledModel.fit_on`): beside 36 hole offsets a fit takes hundreds
#: where most take under 100; in raw units and at 150 such fits ended up to 740 nats short of their optimum.
MAX_FIT_ITER = 500
#: Relative decrease of the likelihood below which a stick fit ends (1e-9 ended some fits after a short step,
#: tens of nats short of where they went on).
FIT_FTOL = 1e-13
SQRT_HALF_PI = float(np.sqrt(np.pi / 2.0))
GAUSS3 = float((2.0 * np.pi) ** 1.5)


@njit(cache=True)
def _fista_row(a: np.ndarray, Bi: np.ndarray, F: np.ndarray, f0: np.ndarray,
               max_iter: int, tol: float) -> np.ndarray:   # pragma: no cover (compiled)
    """``argmin_{|f_j| <= F_j} |a + B f|`` of one row by FISTA with restarts, from ``f0`` (the fallback)."""
    m = Bi.shape[1]
    H = Bi.T @ Bi
    q = Bi.T @ a
    v = np.ones(m)
    L = 0.0
    for _ in range(30):                      # largest eigenvalue of H (power iteration)
        w = H @ v
        nw = np.sqrt(np.dot(w, w))
        if nw <= 0.0:
            break
        L = nw / np.sqrt(np.dot(v, v))
        v = w / nw
    L *= 1.05
    f = np.minimum(np.maximum(f0, -F), F)
    if L <= 0.0:
        return f
    y = f.copy()
    t = 1.0
    for _ in range(max_iter):
        grad = H @ y + q
        fn = np.minimum(np.maximum(y - grad / L, -F), F)
        step = fn - f
        if np.dot(step, H @ step) > 0 and np.dot(H @ fn + q, step) > 0:   # restart on a rise
            t = 1.0
            y = f.copy()
            continue
        tn = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
        y = fn + ((t - 1.0) / tn) * step
        f, t = fn, tn
        if np.dot(step, step) <= tol * (1.0 + np.dot(F, F)):
            break
    return f


@njit(cache=True)
def _box2(d0: float, d1: float, d2: float, G: np.ndarray, j: int, k: int) -> tuple:   # pragma: no cover
    """``argmin_{|u|, |v| <= 1} |d - u g_j - v g_k|^2`` exactly: ``(squared distance, u, v)`` (rows of ``G``)."""
    a11 = G[j, 0] * G[j, 0] + G[j, 1] * G[j, 1] + G[j, 2] * G[j, 2]
    a22 = G[k, 0] * G[k, 0] + G[k, 1] * G[k, 1] + G[k, 2] * G[k, 2]
    a12 = G[j, 0] * G[k, 0] + G[j, 1] * G[k, 1] + G[j, 2] * G[k, 2]
    b1 = G[j, 0] * d0 + G[j, 1] * d1 + G[j, 2] * d2
    b2 = G[k, 0] * d0 + G[k, 1] * d1 + G[k, 2] * d2
    dd = d0 * d0 + d1 * d1 + d2 * d2
    det = a11 * a22 - a12 * a12
    if det > 0.0:
        u = (a22 * b1 - a12 * b2) / det
        v = (a11 * b2 - a12 * b1) / det
        if abs(u) <= 1.0 and abs(v) <= 1.0:
            return max(dd - 2.0 * (u * b1 + v * b2) + u * u * a11 + 2.0 * u * v * a12 + v * v * a22, 0.0), u, v
    best, bu, bv = np.inf, 0.0, 0.0
    for side in (-1.0, 1.0):     # the optimum lies on an edge: one coordinate at a bound, the other clamped
        u, v = side, 0.0
        if a22 > 0.0:
            v = min(max((b2 - u * a12) / a22, -1.0), 1.0)
        e = dd - 2.0 * (u * b1 + v * b2) + u * u * a11 + 2.0 * u * v * a12 + v * v * a22
        if e < best:
            best, bu, bv = e, u, v
        u, v = 0.0, side
        if a11 > 0.0:
            u = min(max((b1 - v * a12) / a11, -1.0), 1.0)
        e = dd - 2.0 * (u * b1 + v * b2) + u * u * a11 + 2.0 * u * v * a12 + v * v * a22
        if e < best:
            best, bu, bv = e, u, v
    return max(best, 0.0), bu, bv


@njit(cache=True)
def _facet_signs(G: np.ndarray, act: np.ndarray, j: int, k: int, n0: float, n1: float, n2: float,
                 u: np.ndarray) -> tuple:   # pragma: no cover (compiled)
    """Set ``u_l = sign(n . g_l)`` for the generators other than ``j, k``; the facet's centre ``sum u_l g_l``."""
    c0 = c1 = c2 = 0.0
    for l in act:
        if l != j and l != k:
            t = n0 * G[l, 0] + n1 * G[l, 1] + n2 * G[l, 2]
            sl = 1.0 if t > 0.0 else (-1.0 if t < 0.0 else 0.0)
            u[l] = sl
            c0 += sl * G[l, 0]
            c1 += sl * G[l, 1]
            c2 += sl * G[l, 2]
    return c0, c1, c2


@njit(cache=True)
def _project_row(a: np.ndarray, Bi: np.ndarray, F: np.ndarray, f0: np.ndarray, pj: np.ndarray, pk: np.ndarray,
                 pz: np.ndarray, N: np.ndarray, h: np.ndarray) -> np.ndarray:   # pragma: no cover
    """``argmin_{|f_j| <= F_j} |a + B f|``: the nearest point of the zonotope ``{B f}`` to ``p = -a``, exactly.

    A zonotope in space is bounded by parallelograms: the facet with outward normal ``n = +-(g_j x g_k)``
    (``g = F b``) is ``sum_{l != j,k} sign(n . g_l) g_l + [-1, 1] g_j + [-1, 1] g_k``, and its support is
    ``h(n) = sum_l |n . g_l|``. ``p`` is inside when ``n . p <= h(n)`` for every facet (forces within the band
    then balance the row: the ray from the centre through ``p`` leaves through a facet, whose forces scaled
    back hold ``p``); outside, the nearest point lies on a facet that ``p`` lies beyond, and on each such facet
    it is a box-constrained problem in two unknowns (:func:`_box2`). The answer is checked (inside: it
    balances the row; outside: each force is at its bound towards the residual, or the residual is normal
    to its generator); a degenerate set (parallel or coplanar generators) that fails the check falls back
    to FISTA. ``pj, pk, pz`` (integers), ``N`` (., 3) and ``h`` are work space for the ``m (m - 1) / 2``
    facets (the caller's, reused from row to row).
    """
    m = Bi.shape[1]
    p0, p1, p2 = -a[0], -a[1], -a[2]
    G = np.empty((m, 3))
    norms = np.empty(m)
    top = 0.0
    for j in range(m):
        for r in range(3):
            G[j, r] = Bi[r, j] * F[j]
        norms[j] = np.sqrt(G[j, 0] ** 2 + G[j, 1] ** 2 + G[j, 2] ** 2)
        top = max(top, norms[j])
    u = np.zeros(m)
    if top <= 0.0:
        return u
    act = np.where(norms > DEGENERATE * top)[0]
    na = len(act)
    if na == 1:
        j = act[0]
        u[j] = min(max((G[j, 0] * p0 + G[j, 1] * p1 + G[j, 2] * p2) / norms[j] ** 2, -1.0), 1.0)
        return u * F
    # the facet normals g_j x g_k of the non-degenerate pairs and their supports h = sum_l |n . g_l|, once
    nf = 0
    for x in range(na):
        for y in range(x + 1, na):
            j, k = act[x], act[y]
            n0 = G[j, 1] * G[k, 2] - G[j, 2] * G[k, 1]
            n1 = G[j, 2] * G[k, 0] - G[j, 0] * G[k, 2]
            n2 = G[j, 0] * G[k, 1] - G[j, 1] * G[k, 0]
            if np.sqrt(n0 * n0 + n1 * n1 + n2 * n2) <= DEGENERATE * norms[j] * norms[k]:
                continue
            hq = 0.0
            for l in act:
                hq += abs(n0 * G[l, 0] + n1 * G[l, 1] + n2 * G[l, 2])
            pj[nf], pk[nf], pz[nf], h[nf] = j, k, y + 1, hq
            N[nf, 0], N[nf, 1], N[nf, 2] = n0, n1, n2
            nf += 1
    full = False                          # some triple of generators spans space (a degenerate pair never does)
    for q in range(nf):
        j, k = pj[q], pk[q]
        for z in range(pz[q], na):
            l = act[z]
            if abs(N[q, 0] * G[l, 0] + N[q, 1] * G[l, 1] + N[q, 2] * G[l, 2]) > \
                    DEGENERATE * norms[j] * norms[k] * norms[l]:
                full = True
                break
        if full:
            break
    inside = full
    exit_t, ej, ek, e0, e1, e2 = np.inf, -1, -1, 0.0, 0.0, 0.0
    best, bj, bk, b0, b1, b2, bu, bv = np.inf, -1, -1, 0.0, 0.0, 0.0, 0.0, 0.0
    for q in range(nf):
        np_ = N[q, 0] * p0 + N[q, 1] * p1 + N[q, 2] * p2
        if full and abs(np_) > h[q]:
            inside = False
        if full and abs(np_) > 0.0 and h[q] / abs(np_) < exit_t:
            sg = 1.0 if np_ > 0.0 else -1.0
            exit_t, ej, ek, e0, e1, e2 = h[q] / abs(np_), pj[q], pk[q], sg * N[q, 0], sg * N[q, 1], sg * N[q, 2]
    for q in range(nf):
        if inside:
            break
        j, k = pj[q], pk[q]
        np_ = N[q, 0] * p0 + N[q, 1] * p1 + N[q, 2] * p2
        for sgn in (-1.0, 1.0):
            if full and sgn * np_ <= h[q]:
                continue                  # p is not beyond this facet: its nearest point is elsewhere
            n0, n1, n2 = sgn * N[q, 0], sgn * N[q, 1], sgn * N[q, 2]
            c0, c1, c2 = _facet_signs(G, act, j, k, n0, n1, n2, u)
            d2, uu, vv = _box2(p0 - c0, p1 - c1, p2 - c2, G, j, k)
            if d2 < best:
                best, bj, bk, b0, b1, b2, bu, bv = d2, j, k, n0, n1, n2, uu, vv
    if inside:
        if ej < 0:                         # p at the centre
            return u
        c0, c1, c2 = _facet_signs(G, act, ej, ek, e0, e1, e2, u)     # the exit facet's forces, scaled back
        _, uu, vv = _box2(exit_t * p0 - c0, exit_t * p1 - c1, exit_t * p2 - c2, G, ej, ek)
        u[ej], u[ek] = uu, vv
        u /= exit_t
    elif bj >= 0:
        _facet_signs(G, act, bj, bk, b0, b1, b2, u)
        u[bj], u[bk] = bu, bv
    else:
        return _fista_row(a, Bi, F, f0, MAX_ITER, STEP_TOL)
    r0, r1, r2 = p0, p1, p2
    for l in act:
        r0 -= u[l] * G[l, 0]
        r1 -= u[l] * G[l, 1]
        r2 -= u[l] * G[l, 2]
    nr = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    pn = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if inside:
        ok = nr <= 1e-9 * (pn + top)
    else:
        ok = True
        for l in act:                      # optimality: a force short of its bound leaves no pull along it
            pull = r0 * G[l, 0] + r1 * G[l, 1] + r2 * G[l, 2]
            tol = 1e-7 * nr * norms[l] + 1e-14 * top * top
            if (pull > tol and u[l] < 1.0 - 1e-9) or (pull < -tol and u[l] > -1.0 + 1e-9):
                ok = False
    if ok:
        return u * F
    return _fista_row(a, Bi, F, f0, MAX_ITER, STEP_TOL)


@njit(cache=True)
def _bounded_lsq(a: np.ndarray, B: np.ndarray, F: np.ndarray, f0: np.ndarray) -> np.ndarray:   # pragma: no cover
    """``argmin_{|f_j| <= F_j} |a_i + B_i f|`` per row (:func:`_project_row`)."""
    n, _, m = B.shape
    out = np.empty((n, m))
    P = m * (m - 1) // 2
    pj, pk, pz = np.empty(P, np.int64), np.empty(P, np.int64), np.empty(P, np.int64)
    N, h = np.empty((P, 3)), np.empty(P)
    for i in range(n):
        out[i] = _project_row(a[i], B[i], F, f0[i], pj, pk, pz, N, h)
    return out


def stick_residual(a: np.ndarray, B: np.ndarray, F: np.ndarray,
                   f0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Distance vector of each row to its stick set, and the friction forces that leave it.

    The nearest point of each stick set (a zonotope) is found exactly, facet by facet
    (:func:`_project_row`); where the row lies inside the set the forces are one balancing choice.

    Parameters
    ----------
    a : numpy.ndarray
        Residuals (n, 3) without friction (whitened pose, or any linear image of the balance).
    B : numpy.ndarray
        Effect (n, 3, m) of a unit friction force on each cable on the residual.
    F : numpy.ndarray
        Band (m,) of each cable (N, >= 0).
    f0 : numpy.ndarray, optional
        Starting forces (n, m) of the fallback iteration (degenerate sets only).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``r = a + B f*`` (n, 3) (zero where friction within the band balances the row) and ``f*``
        (n, m), ``|f*_j| <= F_j``.
    """
    a = np.ascontiguousarray(a, dtype=np.float64)
    B = np.ascontiguousarray(B, dtype=np.float64)
    F = np.ascontiguousarray(np.maximum(np.asarray(F, float), 0.0))
    f0 = np.zeros((len(a), B.shape[2])) if f0 is None else np.ascontiguousarray(f0, dtype=np.float64)
    f = _bounded_lsq(a, B, F, f0)
    return a + np.einsum("nij,nj->ni", B, f), f


class ZonotopeMeasures:
    """Per-row pieces of the volume, area and edge length of the stick sets ``{B_i f : |f| <= F}``.

    The volume is ``8 sum_{j<k<l} F_j F_k F_l |det(b_j, b_k, b_l)|``, the surface area
    ``8 sum_{j<k} F_j F_k |b_j x b_k|`` and the summed edge length ``M / pi = 2 sum_j F_j |b_j|``
    (a zonotope is a sum of segments ``[-F_j b_j, F_j b_j]``).
    """

    def __init__(self, B: np.ndarray):
        B = np.asarray(B, float)
        m = B.shape[2]
        self.triples = np.array(list(itertools.combinations(range(m), 3)), int).reshape(-1, 3)
        self.pairs = np.array(list(itertools.combinations(range(m), 2)), int).reshape(-1, 2)
        cols = np.swapaxes(B, 1, 2)                                            # (n, m, 3)
        self.det = (np.abs(np.linalg.det(cols[:, self.triples]))               # (n, T)
                    if len(self.triples) else np.zeros((len(B), 0)))
        self.cross = np.linalg.norm(np.cross(cols[:, self.pairs[:, 0]], cols[:, self.pairs[:, 1]]), axis=-1)
        self.norm = np.linalg.norm(cols, axis=-1)                              # (n, m)
        # where each band's derivative of a triple's (a pair's) product lands, and the bands that multiply it
        self._slot3 = (np.arange(len(self.triples))[:, None] * m + self.triples).ravel()
        self._rest3 = self.triples[:, [[1, 2], [0, 2], [0, 1]]].reshape(-1, 2)
        self._slot2 = (np.arange(len(self.pairs))[:, None] * m + self.pairs).ravel()
        self._rest2 = self.pairs[:, ::-1].ravel()

    def parts(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(V, A, M)`` per row for bands ``F``."""
        F = np.asarray(F, float)
        V = 8.0 * (self.det @ np.prod(F[self.triples], axis=1)) if len(self.triples) else 0.0 * self.norm[:, 0]
        A = 8.0 * (self.cross @ np.prod(F[self.pairs], axis=1))
        M = 2.0 * np.pi * (self.norm @ F)
        return V, A, M

    def part_gradients(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(dV/dF, dA/dF, dM/dF)`` per row and band (n, m): each measure is a polynomial in the bands.

        ``dV/dF_j = 8 sum |det(b_j, b_k, b_l)| F_k F_l`` over the triples ``{j, k, l}`` holding ``j``,
        ``dA/dF_j = 8 sum |b_j x b_k| F_k`` over the pairs ``{j, k}`` holding ``j``, ``dM/dF_j = 2 pi |b_j|``.
        """
        F = np.asarray(F, float)
        m = len(F)
        others = np.zeros((len(self.triples), m))             # the product of a triple's other two bands
        others.flat[self._slot3] = F[self._rest3[:, 0]] * F[self._rest3[:, 1]]
        other = np.zeros((len(self.pairs), m))                # a pair's other band
        other.flat[self._slot2] = F[self._rest2]
        return 8.0 * (self.det @ others), 8.0 * (self.cross @ other), 2.0 * np.pi * self.norm


def log_normaliser(meas: ZonotopeMeasures, F: np.ndarray, s: float) -> np.ndarray:
    """``log(Z_i / Z0_i)`` per row: the price of the band (0 for ``F = 0``); see the module doc."""
    V, A, M = meas.parts(F)
    return np.log1p((V + A * s * SQRT_HALF_PI + 2.0 * M * s ** 2) / (GAUSS3 * s ** 3))


def log_normaliser_gradient(meas: ZonotopeMeasures, F: np.ndarray,
                            s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`log_normaliser` per row, its derivative in each band (n, m) and in ``log s`` (n,), in closed form.

    With ``N = V + A s sqrt(pi/2) + 2 M s^2`` and ``Z0 = (2 pi)^(3/2) s^3``, ``log(Z/Z0) = log(1 + N/Z0)``:
    ``d/dF_j = dN/dF_j / (Z0 + N)`` and ``d/dlog s = s (dN/ds + dZ0/ds) / (Z0 + N) - 3``.
    """
    V, A, M = meas.parts(F)
    dV, dA, dM = meas.part_gradients(F)
    Z0 = GAUSS3 * s ** 3
    N = V + A * s * SQRT_HALF_PI + 2.0 * M * s ** 2
    d_F = (dV + dA * (s * SQRT_HALF_PI) + dM * (2.0 * s ** 2)) / (Z0 + N)[:, None]
    d_log_s = s * (A * SQRT_HALF_PI + 4.0 * M * s + 3.0 * GAUSS3 * s ** 2) / (Z0 + N) - 3.0
    return np.log1p(N / Z0), d_F, d_log_s


def expected_sq_distance(meas: ZonotopeMeasures, F: np.ndarray, s: float) -> np.ndarray:
    """``E[d_i^2]`` per row under the density of the module doc (``3 s^2`` for ``F = 0``)."""
    V, A, M = meas.parts(F)
    Z = V + A * s * SQRT_HALF_PI + 2.0 * M * s ** 2 + GAUSS3 * s ** 3
    return (A * s ** 3 * SQRT_HALF_PI + 4.0 * M * s ** 4 + 3.0 * GAUSS3 * s ** 5) / Z


def stick_layout(model) -> tuple[np.ndarray, np.ndarray, list]:
    """``(lin, band, stick)``: indices of ``model``'s point parameters, of its band parameters, its stick effects.

    A *stick effect* (settled cable friction, settled joint friction) has ``settled`` set and
    ``stick_columns``; its parameters are bands. Every other parameter (the nuisance, a partner effect's)
    is a point parameter, linearised about a centre (:class:`StickDesign`).
    """
    offs = np.cumsum([0, model.n_params - sum(e.n_params for e in model.effects)]
                     + [e.n_params for e in model.effects])
    stick: list[int] = []
    band: list[int] = []
    for i, e in enumerate(model.effects):
        if getattr(e, "settled", False) and hasattr(e, "stick_columns"):
            stick.append(i)
            band.extend(range(offs[i + 1], offs[i + 2]))
    lin = np.setdiff1d(np.arange(model.n_params), band)
    return lin, np.asarray(band, int), stick


def stick_design(model, table, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(a, B, tie)``: whitened linearised residuals, stick-set generators, the band of each generator.

    ``a`` (n, 3) of ``model`` at ``theta``, ``B`` (n, 3, c) the generators of its stick sets and ``tie`` (c,)
    the band parameter of each generator (indices into the band parameters).

    The tangent is the model's own at ``theta`` (at the measured pose), as every point model's
    (:func:`csjm_opt.diagnose.fitting.gauss_newton.fit_model`): a partner that stiffens or softens the
    joint (a stiffness scale, hardening, a link) changes how far a balance residual puts the pose. With
    the nominal tangent a stiffness scale of 1.1 read every residual 10 % long, and on a step-loaded
    friction + stiffness-scale log the pair came out 34 nats below friction + sensor gain (which leaves
    the tangent as it is).
    """
    _, band, stick = stick_layout(model)
    g, ev = model.evaluate(table.R_meas, table.rows, theta)
    WGinv = table.whiten @ _safe_inv(model.tangent(table.R_meas, table.rows, theta, g, h=1e-6))
    cols, ties, first = [], [], 0
    for i in stick:
        c, t = model.effects[i].stick_columns(ev)
        cols.append(c)
        ties.append(first + np.asarray(t, int))
        first += model.effects[i].n_params
    C = np.concatenate(cols, axis=2) if cols else np.zeros((len(g), 3, 0))
    tie = np.concatenate(ties) if ties else np.zeros(0, int)
    return np.einsum("nij,nj->ni", WGinv, g), np.einsum("nij,njk->nik", WGinv, C), tie


class StickDesign:
    """A model's stick problem on a table, linearised in its point parameters about ``centre``.

    ``a(x_lin) = a0 + D (x_lin - centre_lin)`` (whitened residual), generators ``B`` (n, 3, c), and
    ``tie`` (c,): the band parameter of each generator.
    """

    def __init__(self, model, table, centre: np.ndarray):
        self.lin, self.band, _ = stick_layout(model)
        self.centre = np.asarray(centre, float).copy()
        self.a0, self.B, self.tie = stick_design(model, table, self.centre)
        self.D = np.empty((len(self.a0), 3, len(self.lin)))
        h = 1e-3 * np.asarray(model.scales, float)[self.lin]
        for j, (k, hj) in enumerate(zip(self.lin, h)):
            th = self.centre.copy()
            th[k] += hj
            self.D[:, :, j] = (stick_design(model, table, th)[0] - self.a0) / hj

    def take(self, idx: np.ndarray) -> "StickDesign":
        """The design of rows ``idx``."""
        out = object.__new__(StickDesign)
        out.lin, out.band, out.centre, out.tie = self.lin, self.band, self.centre, self.tie
        out.a0, out.B, out.D = self.a0[idx], self.B[idx], self.D[idx]
        return out


class StickFit:
    """Maximum-likelihood bands, noise scale and point parameters of the stick model.

    ``x = (point parameters (k), bands (b), log s)``; the residual is ``a0 + D x_point``, the generator
    ``j`` of row ``i`` is ``B_ij`` with band ``x_band[tie_j]``.

    Parameters
    ----------
    a0 : numpy.ndarray
        (n, 3) residuals at zero point parameters.
    da : numpy.ndarray
        (n, 3) or (n, 3, k): their change per unit point parameter.
    B : numpy.ndarray
        (n, 3, c) generators.
    tie : numpy.ndarray, optional
        (c,) band of each generator (default: one band per generator).
    meas : ZonotopeMeasures, optional
        The measures of ``B`` when the caller has them (they depend on ``B`` alone).
    """

    def __init__(self, a0: np.ndarray, da: np.ndarray, B: np.ndarray, tie: np.ndarray | None = None,
                 meas: ZonotopeMeasures | None = None):
        self.a0, self.B = np.asarray(a0, float), np.asarray(B, float)
        D = np.asarray(da, float)
        self.D = D[..., None] if D.ndim == 2 else D
        self.tie = np.arange(self.B.shape[2]) if tie is None else np.asarray(tie, int)
        self.k = self.D.shape[2]
        self.nb = int(self.tie.max(initial=-1)) + 1
        self.meas = ZonotopeMeasures(self.B) if meas is None else meas
        self.f = np.zeros((len(self.a0), self.B.shape[2]))

    def neg_log_lik(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """``-log L`` and its gradient in ``x = (point parameters, bands, log s)``."""
        k, nb = self.k, self.nb
        lin, bands, s = x[:k], np.maximum(x[k:k + nb], 0.0), float(np.exp(x[-1]))
        F = bands[self.tie]
        r, self.f = stick_residual(self.a0 + np.einsum("nij,j->ni", self.D, lin), self.B, F, self.f)
        d2 = np.sum(r ** 2, axis=1)
        lz, dlz_dF, dlz_dlog_s = log_normaliser_gradient(self.meas, F, s)
        val = 0.5 * float(np.sum(d2)) / s ** 2 + float(np.sum(lz))
        grad = np.empty_like(x)
        grad[:k] = np.einsum("ni,nij->j", r, self.D) / s ** 2
        # d(d^2)/dF_j = 2 r . b_j f*_j / F_j (Danskin: the optimal forces scale with the band)
        rb = np.einsum("ni,nij->nj", r, self.B)
        tj = np.divide(self.f, F, out=np.zeros_like(self.f), where=F > 0)
        grad[k:k + nb] = np.bincount(self.tie, np.sum(rb * tj, axis=0), minlength=nb) / s ** 2
        # the band's price: its closed-form derivative, each band the sum over the generators tied to it
        grad[k:k + nb] += np.bincount(self.tie, np.sum(dlz_dF, axis=0), minlength=nb)
        grad[-1] = -float(np.sum(d2)) / s ** 2 + float(np.sum(dlz_dlog_s))
        # d(log Z0)/d(log s) = 3 per row is in the Gaussian constant of every model: counted here explicitly
        val += 3.0 * len(d2) * float(np.log(s))
        grad[-1] += 3.0 * len(d2)
        return val, grad

    def fit(self, F_max: float, starts: tuple = (0.0, 0.3, 1.0), s: float | None = None) -> tuple[np.ndarray, float]:
        """``(x, -log L)`` of the best start; ``F_max`` bounds each band; ``s``: a fixed noise scale.

        With the noise scale free, the likelihood of a few hundred rows tends to a band that holds
        every row and a scale near zero (a set-valued model's degeneracy); the diagnosis fixes the
        scale and chooses it on held-out rows (:func:`settled_score`).
        """
        k, nb = self.k, self.nb
        s0 = float(np.sqrt(np.mean(np.sum(self.a0 ** 2, axis=1)) / 3.0))
        best = None
        for share in starts:
            self.f = np.zeros_like(self.f)
            x0 = np.r_[np.zeros(k), np.full(nb, share * F_max * 0.1), np.log(max(s0 * (1 - share) + 0.3 * share, 1e-3))]
            bounds = [(None, None)] * k + [(0.0, F_max)] * nb + [(np.log(1e-3), np.log(1e3)) if s is None
                                                                 else (np.log(s), np.log(s))]
            if s is not None:
                x0[-1] = np.log(s)
            res = minimize(self.neg_log_lik, x0, jac=True, method="L-BFGS-B", bounds=bounds,
                           options={"maxiter": 400, "ftol": 1e-12, "gtol": 1e-8})
            if best is None or res.fun < best.fun:
                best = res
        assert best is not None
        return best.x, float(best.fun)


#: 95 % quantile of chi^2 with one degree of freedom (held-out likelihood ratio of the noise scale).
CHI2_1_95 = 3.84


class SettledModel:
    """The stick model fitted on a table: point parameters, bands, and what it says of other rows.

    Parameters
    ----------
    model : AugmentedModel
        Nominal model plus effects of which at least one is settled (a stick effect,
        :func:`stick_layout`); the others' parameters (and the nuisance) are point parameters.
    design : StickDesign
        The model's stick problem on the training rows.
    s : float
        Noise scale (whitened units) the bands are fitted at.
    start : SettledModel, optional
        A fit at another noise scale: its parameters and forces start this one.
    """

    def __init__(self, model, design: StickDesign, s: float, start: "SettledModel | None" = None,
                 fit: bool = True):
        self.model, self.design, self.s = model, design, float(s)
        self.k, self.nb = len(design.lin), len(design.band)
        self.m = self.nb
        lo, hi = np.asarray(model.lower_bounds, float), np.asarray(model.upper_bounds, float)
        rng_hi = np.array([_range_top(model, j) for j in design.band])
        c0 = design.centre[design.lin]
        self.bounds = ([(None if not np.isfinite(a) else a - c, None if not np.isfinite(b) else b - c)
                        for a, b, c in zip(lo[design.lin], hi[design.lin], c0)]
                       + [(0.0, float(t)) for t in rng_hi])
        prior = np.asarray(model.prior_sd, float)[design.lin]
        self.ridge = np.where(np.isfinite(prior), prior, np.inf)       # a partner's proper prior (hole offsets)
        # the optimiser's unit of each parameter (its typical magnitude, as the point fits'): a hole offset moves
        # the residual a million times more per unit than a band does, and L-BFGS-B in raw units crawled (a
        # pair's centre fit stopped at its iteration limit up to 740 nats short of its optimum)
        self.unit = np.asarray(model.scales, float)[np.r_[design.lin, design.band]]
        self._f = np.zeros((len(design.a0), design.B.shape[2]))
        self.x = np.r_[np.zeros(self.k), np.full(self.nb, 0.0)]
        if start is not None:
            self.x, self._f = start.x.copy(), start._f.copy()
        if fit:
            self.fit_on(np.arange(len(design.a0)), warm=start is not None)

    def theta(self, x: np.ndarray | None = None) -> np.ndarray:
        """The full parameter vector of ``model`` for ``x`` (point parameters about the design's centre)."""
        x = self.x if x is None else x
        th = self.design.centre.copy()
        th[self.design.lin] += x[:self.k]
        th[self.design.band] = x[self.k:]
        return th

    def _nll(self, idx: np.ndarray, x: np.ndarray, s: float) -> tuple[float, np.ndarray]:
        d = self.design
        key = np.asarray(idx).tobytes()
        known: dict[bytes, StickFit] = self.__dict__.setdefault("_fits", {})
        sf = known.get(key)
        if sf is None:          # the rows' problem and their stick sets' measures: once per row set
            sf = known[key] = StickFit(d.a0[idx], d.D[idx], d.B[idx], d.tie)
        sf.f = self._f[idx]
        val, grad = sf.neg_log_lik(np.r_[x, np.log(s)])
        self._f[idx] = sf.f
        n = len(idx)
        lin = x[:self.k]
        val += 0.5 * float(np.sum((lin / self.ridge) ** 2))
        g = grad[:-1]
        g[:self.k] += lin / self.ridge ** 2
        return val - 3.0 * n * np.log(s), g

    def fit_on(self, idx: np.ndarray, warm: bool = True) -> np.ndarray:
        """Fit ``x`` by maximum likelihood at the fixed noise scale on rows ``idx``.

        ``warm``: start from the current parameters and forces (one path, in the parameters' units); else from
        small bands along two paths, in the parameters' units and with the point parameters decorrelated
        (:meth:`_point_transform`), keeping the better end. The likelihood has local optima a few nats apart (a
        band that holds some rows against a partner's parameter that moves them), and either path alone missed
        the best one on some pairs of a step-loaded log (by up to 12 nats).
        """
        if warm:
            x0, f0 = self.x.copy(), self._f.copy()
            paths = [self._diagonal]
        else:
            x0 = np.r_[np.zeros(self.k), [0.05 * float(b[1] or 0.0) for b in self.bounds[self.k:]]]
            f0 = np.zeros_like(self._f)
            T = self._point_transform(idx)
            paths = [self._diagonal] + ([T] if T is not self._diagonal else [])
        best: tuple[float, np.ndarray, np.ndarray] | None = None
        for T in paths:
            self._f = f0.copy()
            x, val = self._fit_path(idx, x0, T)
            if best is None or val < best[0]:
                best = (val, x, self._f.copy())
        assert best is not None
        _, self.x, self._f = best
        return self.x

    def _fit_path(self, idx: np.ndarray, x0: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, float]:
        """L-BFGS-B from ``x0`` in ``z`` with point parameters ``T z`` and bands in their units: ``(x, -log L)``."""
        u, k = self.unit, self.k

        def to_x(z: np.ndarray) -> np.ndarray:
            return np.r_[T @ z[:k], z[k:] * u[k:]]

        def scaled(z: np.ndarray) -> tuple[float, np.ndarray]:
            val, grad = self._nll(idx, to_x(z), self.s)
            return val, np.r_[T.T @ grad[:k], grad[k:] * u[k:]]

        z0 = np.r_[np.linalg.solve(T, x0[:k]), x0[k:] / u[k:]]
        bounds = ([(None, None)] * k if T is not self._diagonal else
                  [(None if a is None else a / uj, None if b is None else b / uj)
                   for (a, b), uj in zip(self.bounds[:k], u[:k])])
        bounds += [(a / uj, b / uj) for (a, b), uj in zip(self.bounds[k:], u[k:])]
        res = minimize(scaled, z0, jac=True, method="L-BFGS-B", bounds=bounds,
                       options={"maxiter": MAX_FIT_ITER, "ftol": FIT_FTOL, "gtol": 1e-6})
        x = to_x(res.x)
        return x, float(self._nll(idx, x, self.s)[0])

    @property
    def _diagonal(self) -> np.ndarray:
        """The point parameters' units as a diagonal transform (k, k)."""
        return self.__dict__.setdefault("_diag", np.diag(self.unit[:self.k]))

    def _point_transform(self, idx: np.ndarray) -> np.ndarray:
        """``T`` (k, k) with point parameters ``x = T z``: ``z`` sees the point part of the cost as a unit sphere.

        The point part of the likelihood is a least-squares cost, Hessian ``H = sum D_i^T D_i / s^2`` plus the
        ridge; with ``T = H^(-1/2)`` (directions it does not see kept at their unit scale) L-BFGS-B needs a few
        iterations where correlated point parameters (36 hole offsets that share the log's 23 effective
        numbers) took it past its iteration limit. Where a point parameter has a bound, its unit scale alone (a
        transform would turn the box into a slanted one).
        """
        finite = [a is not None or b is not None for a, b in self.bounds[:self.k]]
        if any(finite):
            return self._diagonal
        known: dict[bytes, np.ndarray] = self.__dict__.setdefault("_transforms", {})
        key = np.asarray(idx).tobytes()             # the noise scale is the model's own
        if key not in known:
            u = self.unit[:self.k]
            D = self.design.D[idx] * u                                # per unit scale of each point parameter
            H = np.einsum("nik,nil->kl", D, D) / self.s ** 2
            H[np.diag_indices(self.k)] += np.where(np.isfinite(self.ridge), (u / self.ridge) ** 2, 0.0)
            w, V = np.linalg.eigh(H)
            w = np.maximum(w, 1.0)           # a direction seen less than its unit scale's worth: that scale
            known[key] = u[:, None] * (V / np.sqrt(w))
        return known[key]

    def row_terms(self, design: StickDesign, idx: np.ndarray, x: np.ndarray | None = None,
                  s: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(r, pen, e_d2)`` on rows ``idx`` of ``design``.

        Whitened distance vectors, band price ``2 s^2 log(Z/Z0)``, ``E[d^2]``.
        """
        x = self.x if x is None else x
        s = self.s if s is None else s
        F = np.maximum(x[self.k:], 0.0)[design.tie]
        lin = x[:self.k] + self.design.centre[design.lin] - design.centre[design.lin]
        a = design.a0[idx] + np.einsum("nij,j->ni", design.D[idx], lin)
        r, _ = stick_residual(a, design.B[idx], F)
        meas = ZonotopeMeasures(design.B[idx])
        return r, 2.0 * s ** 2 * log_normaliser(meas, F, s), expected_sq_distance(meas, F, s)

    def log_evidence(self, noise_scale: float) -> float:
        """Laplace log evidence at ``noise_scale`` (convention of :func:`.evidence.log_evidence`).

        Priors as every model's (:func:`.evidence.prior_of`): half-normal bands, Gaussian point parameters.
        """
        from .evidence import _prior
        idx = np.arange(len(self.design.a0))
        s = float(noise_scale)
        x = self.x
        self._f = np.zeros_like(self._f)
        val, g0 = self._nll(idx, x, s)
        val -= 0.5 * float(np.sum((x[:self.k] / self.ridge) ** 2))      # the prior is counted once, below
        mean_all, sd_all, side_all = _prior(_ModelOnly(self.model))  # type: ignore[arg-type]
        order = np.r_[self.design.lin, self.design.band]
        mean = mean_all[order] - np.r_[self.design.centre[self.design.lin], np.zeros(self.nb)]
        sd, side = sd_all[order], side_all[order]
        H = np.empty((len(x), len(x)))
        for j in range(len(x)):
            h = 1e-4 * sd[j]
            xp = x.copy()
            xp[j] += h
            H[:, j] = (self._nll(idx, xp, s)[1] - g0) / h
        H = 0.5 * (H + H.T)
        H[:self.k, :self.k] -= np.diag(np.where(np.isfinite(self.ridge), 1.0 / self.ridge ** 2, 0.0))
        quad = float(np.sum(((x - mean) / sd) ** 2))
        _, logdet = np.linalg.slogdet(np.eye(len(x)) + sd[:, None] * H * sd[None, :])
        return float(-val - 0.5 * quad - 0.5 * logdet + np.count_nonzero(side) * np.log(2.0))


class _ModelOnly:
    """A stand-in with the one attribute :func:`.evidence._prior` reads (``model``)."""

    def __init__(self, model):
        self.model = model


def _range_top(model, j: int) -> float:
    """Upper end of parameter ``j``'s plausible range (a band's bound in the fit)."""
    names = model.param_names
    for e in model.effects:
        rng = e.ranges()
        if names[j] in rng:
            return float(rng[names[j]][1])
    return float("inf")


class _Evidence:
    """``noise_scale -> log evidence`` of a fitted stick model (picklable: fits travel back from workers)."""

    def __init__(self, sm: SettledModel):
        self.sm = sm
        self._memo: dict[float, float] = {}

    def __call__(self, noise_scale: float) -> float:
        key = float(noise_scale)
        if key not in self._memo:
            self._memo[key] = self.sm.log_evidence(key)
        return self._memo[key]


def settled_score(model, train, test, folds, scales: Sequence[float]):
    """The stick model scored like every other model: fitted on training rows, held-out residuals.

    The held-out "residual" of a row is its distance to the stick set in rad (``L_i r_i``,
    ``L_i = W_i^-1``); the band's price per row (``2 s^2 log(Z_i / Z0_i)``, in rad^2 through the
    row's mean noise variance) enters its squared error (:attr:`CandidateScore.heldout_penalty_rad2`),
    so that held-out errors compare ``-2 s^2 log p`` with the other models' squared errors at the
    model's own noise scale. That scale is the one of ``scales`` under which the held-out rows are
    most probable (a band fitted to the training rows at a scale too small holds them all and
    leaves held-out rows outside, at a scale too large it takes stick positions for noise): the
    stick model's noise estimate, which friction does not inflate.

    A partner effect's parameters (a pair: settled friction and a sensor bias) are point parameters,
    linearised about the nominal values and, once fitted, about the fit (one relinearisation).

    Parameters
    ----------
    model : AugmentedModel
        Nominal model + at least one settled effect (+ point effects).
    train, test : ResidualTable
        Training and held-out tables (``test`` None: the folds of ``train``).
    folds : list of numpy.ndarray or None
        Held-out row sets of ``train`` when there is no test table.
    scales : sequence of float
        Candidate noise scales (whitened units).

    Returns
    -------
    CandidateScore
    """
    from ..selection.scoring import CandidateScore, equivalent_mse
    from .gauss_newton import FitResult

    def to_rad(table, idx, r, pen, e_d2):
        """Distance vectors (rad), ``q = d^2 / s^2 + 2 log(Z / Z0)``, ``E[q]``, mean noise variance (rad^2)."""
        L = np.linalg.inv(table.whiten[idx])
        var = np.sum(L ** 2, axis=(1, 2)) / 3.0
        q = (np.sum(r ** 2, axis=1) + pen) / s ** 2
        return np.einsum("nij,nj->ni", L, r), q, (e_d2 + pen) / s ** 2, var

    scales = sorted(scales)
    design = StickDesign(model, train, model.x0())
    if len(design.lin) > 1:         # a partner effect: relinearised about its fit at the middle scale
        first = SettledModel(model, design, scales[len(scales) // 2])
        design = StickDesign(model, train, first.theta())
    all_rows = np.arange(len(train))
    d_test = None if test is None else StickDesign(model, test, design.centre)
    prev = None
    tried: list[tuple] = []
    for s in scales:
        sm = SettledModel(model, design, s, start=prev)
        prev = sm
        if d_test is not None:
            idx = np.arange(len(test))
            r, pen, e = sm.row_terms(d_test, idx, sm.x, s)
            zeta, q, eq, var = to_rad(test, idx, r, pen, e)
            cyc = test.cycle
        else:
            zeta, q, eq, var = np.empty((len(train), 3)), *np.empty((3, len(train)))
            for h in folds or []:
                x = sm.fit_on(np.setdiff1d(all_rows, h))
                r, pen, e = sm.row_terms(design, h, x)
                zeta[h], q[h], eq[h], var[h] = to_rad(train, h, r, pen, e)
            sm.fit_on(all_rows)
            cyc = train.cycle
        nll = float(np.sum(q) + 6 * len(q) * np.log(s))        # held-out -2 log p (whitened, less a constant)
        tried.append((nll, sm, zeta, q, eq, var, cyc))
    # the largest scale the held-out rows do not reject (likelihood ratio, one parameter, 95 %): below the
    # scale of the noise the likelihood is flat (noise inside the band looks like a stick position)
    top = min(t[0] for t in tried)
    _, sm, zeta, q, eq, var, cyc = max((t for t in tried if t[0] <= top + CHI2_1_95), key=lambda t: t[1].s)
    s = sm.s
    r_tr, pen_tr, _ = sm.row_terms(design, all_rows)
    zeta_tr = to_rad(train, all_rows, r_tr, pen_tr, pen_tr)[0]
    theta = sm.theta()
    n = len(train)
    rss = float(np.sum(r_tr ** 2) + np.sum(pen_tr))
    free = np.zeros(model.n_params, bool)
    free[design.lin] = True
    free[design.band] = sm.x[sm.k:] > 1e-9
    fit = FitResult(model, theta, np.zeros((model.n_params, model.n_params)), rss, 3 * n, float(free.sum()),
                    int(free.sum()), 1.0, zeta_tr, None, None, free, train.rows,
                    evidence_fn=_Evidence(sm))
    floor = float(np.sqrt(equivalent_mse(eq, var, s))) / s    # per unit noise scale, as the other models'
    return CandidateScore(model.name, fit, zeta, cyc, zeta_tr, 0, train.instrument_floor_rad,
                          float(s ** 2), floor, (), heldout_density=(q, var, s),
                          heldout_nll=q + 6.0 * np.log(s))
