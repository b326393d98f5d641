"""Reachable stiffness at a pose and load: what shaping the tensions can achieve.

The feasible tensions form the polytope ``F = {T : J^T T + tau_load = 0,
t_min <= T <= t_max}`` (dimension 3 for six cables), and ``K(T) = K0 + sum
T_i G_i`` is affine in T (:mod:`csjm_opt.shaping.shaper`). Methods, by quantity:

* **Directional stiffness** ``u^T K u`` (affine in T): its range over F is a
  pair of LPs, solved exactly (scipy HiGHS).
* **Trace** (affine): exact LPs too.
* **Smallest eigenvalue** ``lambda_1`` is concave in T, so its minimum over
  F is attained at a vertex of F: exact by enumerating the vertices (three
  bounds active, the other three tensions from equilibrium). Its maximum is
  a convex problem, solved by Kelley's cutting planes on
  ``lambda_1 = min_u u^T K u``: each LP gives an upper bound, the eigenvalue
  at the LP's solution a lower bound; stopped when the gap is below ``tol``
  (the reported value is the achieved lower bound, the gap is reported).
* **Largest eigenvalue** ``lambda_3`` is convex: maximum at a vertex (exact),
  minimum by cutting planes (as above, mirrored).
* **Middle eigenvalue** ``lambda_2`` is neither concave nor convex: its range
  is an *inner* estimate from the vertices, ``n_samples`` random points of F
  and the cutting-plane iterates (the true range can be slightly wider).

:func:`csjm_opt.shaping.figures.plot_reachable_set` draws the eigenvalue ranges and
the directional stiffness range for directions in the {A} x-y plane.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import numpy.typing as npt
from scipy.optimize import linprog

from .._validate import as_array, as_rotation, as_vector3
from ..errors import InfeasibleLoad, InvalidInput, SolverError
from ..model.rig import Rig
from .shaper import StiffnessBasis, stiffness_basis


@dataclasses.dataclass(frozen=True, eq=False)
class ReachableSet:
    """Ranges of stiffness over all feasible tensions at one pose and load (N m/rad)."""

    eigen_ranges: np.ndarray      # (3, 2) [min, max] of lambda_1 <= lambda_2 <= lambda_3
    eigen_method: tuple[tuple[str, str], ...]   # per bound: "vertex", "cutting-plane", "sampled"
    cutting_plane_gap: float      # largest remaining upper-lower gap of the cutting planes
    trace_range: tuple[float, float]
    vertices_N: np.ndarray        # (n_v, m) vertices of the feasible tension polytope
    sample_eigenvalues: np.ndarray  # (n_s, 3) eigenvalues at sampled feasible tensions
    basis: StiffnessBasis
    tau_load_A_Nm: np.ndarray

    def directional_range(self, directions: np.ndarray, t_min_N: float, t_max_N: float) -> np.ndarray:
        """Exact range of ``u^T K u`` over the feasible tensions, per direction (two LPs each).

        Parameters
        ----------
        directions : array_like, shape (n, 3)
            Directions ``u`` in {A} (normalised; non-zero).
        t_min_N, t_max_N : float
            Tension bounds (N).

        Returns
        -------
        ndarray, shape (n, 2)
            ``[min, max]`` per direction (N m/rad).
        """
        return directional_range(self.basis, self.tau_load_A_Nm, directions, t_min_N, t_max_N)

    def as_dict(self) -> dict:
        """The reachable set as a JSON-able dict.

        Returns
        -------
        dict
            Eigenvalue ranges with their methods, cutting-plane gap, trace range, vertex count.
        """
        return {"eigen_ranges_Nm_per_rad": self.eigen_ranges.tolist(),
                "eigen_method": [list(m) for m in self.eigen_method],
                "cutting_plane_gap_Nm_per_rad": self.cutting_plane_gap,
                "trace_range_Nm_per_rad": list(self.trace_range), "n_vertices": len(self.vertices_N)}


def feasible_vertices(J: np.ndarray, tau_load: np.ndarray, t_min: float, t_max: float) -> np.ndarray:
    """Vertices of ``{T: J^T T + tau_load = 0, t_min <= T <= t_max}`` (n_v, m), deduplicated.

    A vertex has m - 3 tensions at a bound and 3 free ones solving the equilibrium.
    """
    out = []
    m = J.shape[0]
    for fixed in itertools.combinations(range(m), m - 3):
        free = [i for i in range(m) if i not in fixed]
        Af = J[free].T
        if abs(np.linalg.det(Af)) < 1e-12:
            continue
        for levels in itertools.product((t_min, t_max), repeat=m - 3):
            T = np.empty(m)
            T[list(fixed)] = levels
            T[free] = np.linalg.solve(Af, -tau_load - J[list(fixed)].T @ np.array(levels))
            if np.all(T[free] >= t_min - 1e-9) and np.all(T[free] <= t_max + 1e-9):
                out.append(np.clip(T, t_min, t_max))
    if not out:
        return np.zeros((0, m))
    V = np.array(out)
    _, idx = np.unique(np.round(V, 7), axis=0, return_index=True)
    return V[np.sort(idx)]


def tension_lp(c: np.ndarray, J: np.ndarray, tau_load: np.ndarray, t_min: float, t_max: float,
               A_ub: np.ndarray | None = None, b_ub: np.ndarray | None = None, extra: int = 0) -> np.ndarray:
    """Minimise ``c . x`` over the tension polytope, plus ``extra`` free variables and cuts.

    Parameters
    ----------
    c : (m + extra,) array
        Cost vector.
    J : (m, 3) array
        Structure matrix at the pose (row i is ``cross(A_i, u_i)``).
    tau_load : (3,) array
        Total load moment (N m, in {A}); the tensions satisfy ``J^T T + tau_load = 0``.
    t_min, t_max : float
        Tension bounds (N).
    A_ub, b_ub : array, optional
        Extra inequality cuts ``A_ub x <= b_ub``.
    extra : int
        Number of free variables appended after the six tensions.

    Returns
    -------
    (m + extra,) array
        The minimiser (tensions first, N).

    Raises
    ------
    SolverError
        HiGHS found no solution (empty polytope or numerical failure).
    """
    A_eq = np.hstack([J.T, np.zeros((3, extra))])
    bounds = [(t_min, t_max)] * J.shape[0] + [(None, None)] * extra
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=-tau_load, bounds=bounds, method="highs")
    if res.status != 0:
        raise SolverError(f"reachable-set LP failed: {res.message}", "highs")
    return res.x


def directional_range(basis: StiffnessBasis, tau_load: np.ndarray, directions: np.ndarray,
                      t_min: float, t_max: float) -> np.ndarray:
    """Exact ``[min, max]`` of ``u^T K(T) u`` over feasible T, per direction: (n, 2)."""
    U = np.atleast_2d(np.asarray(directions, float))
    U = U / np.linalg.norm(U, axis=1, keepdims=True)
    out = np.empty((len(U), 2))
    for k, u in enumerate(U):
        g = np.einsum("j,ijk,k->i", u, basis.G, u)
        c0 = float(u @ basis.K0 @ u)
        out[k, 0] = c0 + g @ tension_lp(g, basis.J, tau_load, t_min, t_max)
        out[k, 1] = c0 + g @ tension_lp(-g, basis.J, tau_load, t_min, t_max)
    return out


def directional_stiffness_range(rig: Rig, R: np.ndarray, tau_ext_A_Nm: np.ndarray,
                                directions: np.ndarray) -> np.ndarray:
    """Exact range of the directional stiffness ``u^T K u`` over all tensions that hold the load.

    Parameters
    ----------
    rig : Rig
        The rig.
    R : ndarray, shape (3, 3)
        Orientation of {A} in {B}.
    tau_ext_A_Nm : array_like, shape (3,)
        External moment in {A} (N m), platform weight excluded.
    directions : array_like, shape (n, 3)
        Directions ``u`` in {A} (normalised here; must be non-zero).

    Returns
    -------
    ndarray, shape (n, 2)
        ``[min, max]`` of ``u^T K u`` (N m/rad) per direction, from two LPs each.

    Raises
    ------
    NotARotation
        If ``R`` is not a rotation.
    InvalidInput
        If a direction is zero or a shape is wrong.
    InfeasibleLoad
        If no tensions within the bounds hold the load.
    SolverError
        If an LP fails.
    """
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    U = as_array(np.atleast_2d(directions), (None, 3), "directions")
    if np.any(np.linalg.norm(U, axis=1) < 1e-12):
        raise InvalidInput("directions must be non-zero", "directions")
    basis = stiffness_basis(rig, R)
    tau_load = tau_ext + basis.tau_weight_A_Nm
    if len(feasible_vertices(basis.J, tau_load, rig.t_min_N, rig.t_max_N)) == 0:
        raise InfeasibleLoad(f"no feasible tensions hold tau_ext={np.round(tau_ext, 4).tolist()} N m at this pose",
                             R, tau_ext, float("nan"))
    return directional_range(basis, tau_load, U, rig.t_min_N, rig.t_max_N)


def _cutting_plane(basis: StiffnessBasis, tau_load: np.ndarray, t_min: float, t_max: float, which: str,
                   tol: float, max_iter: int) -> tuple[float, float, list[np.ndarray]]:
    """Cutting-plane bound: max lambda_min (which="max_min") or min lambda_max ("min_max"); (value, gap, iterates)."""
    sign = 1.0 if which == "max_min" else -1.0
    m = basis.G.shape[0]
    Gf = basis.G.reshape(m, 9)
    cuts = [np.eye(3)[i] for i in range(3)]
    iterates: list[np.ndarray] = []
    best, bound = -np.inf, np.inf
    for _ in range(max_iter):
        # maximise s with sign*(u^T K0 u + g_u . T) >= sign*s ... written as sign*s - sign*g.T <= sign*c0
        A_ub = np.array([np.concatenate([-sign * np.einsum("a,b,iab->i", u, u, basis.G), [sign]]) for u in cuts])
        b_ub = np.array([sign * (u @ basis.K0 @ u) for u in cuts])
        x = tension_lp(np.concatenate([np.zeros(m), [-sign]]), basis.J, tau_load, t_min, t_max, A_ub, b_ub, extra=1)
        T, s = x[:m], float(x[m])
        K = basis.K0 + (T @ Gf).reshape(3, 3)
        lam, vec = np.linalg.eigh(0.5 * (K + K.T))
        iterates.append(T)
        achieved = lam[0] if sign > 0 else lam[-1]
        bound = min(bound, sign * s)
        best = max(best, sign * achieved)
        if bound - best <= tol:
            break
        cuts.append(vec[:, 0] if sign > 0 else vec[:, -1])
    return sign * best, bound - best, iterates


def reachable_set(rig: Rig, R: np.ndarray, tau_ext_A_Nm: npt.ArrayLike = (0.0, 0.0, 0.0), n_samples: int = 2000,
                  rng: np.random.Generator | None = None, tol: float = 1e-6,
                  max_cuts: int = 200) -> ReachableSet:
    """Eigenvalue and trace ranges of K over all feasible tensions at ``R`` under ``tau_ext``.

    Parameters
    ----------
    rig : Rig
        The rig (tension bounds from it).
    R : ndarray, shape (3, 3)
        Orientation of {A} in {B}.
    tau_ext_A_Nm : array_like, shape (3,), optional
        External moment in {A} (N m), platform weight excluded.
    n_samples : int, optional
        Random feasible tension vectors sampled for the inner estimate of the middle
        eigenvalue's range (0 for none).
    rng : numpy.random.Generator, optional
        Random generator for the samples (seeded 0 by default: reproducible).
    tol : float, optional
        Gap (N m/rad) at which the cutting planes stop.
    max_cuts : int, optional
        Largest number of cutting planes per bound.

    Returns
    -------
    ReachableSet
        Eigenvalue ranges (with the method of each bound), trace range, the vertices of the
        feasible tension polytope and the sampled eigenvalues.

    Raises
    ------
    NotARotation
        If ``R`` is not a rotation.
    InvalidInput
        If ``tau_ext_A_Nm`` or ``n_samples`` is invalid.
    InfeasibleLoad
        If no tensions within the bounds hold the load.
    SolverError
        If an LP fails.
    """
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    if not (isinstance(n_samples, (int, np.integer)) and n_samples >= 0):
        raise InvalidInput(f"n_samples: expected an integer >= 0, got {n_samples!r}", "n_samples")
    rng = rng or np.random.default_rng(0)
    basis = stiffness_basis(rig, R)
    tau_load = tau_ext + basis.tau_weight_A_Nm
    lo, hi = rig.t_min_N, rig.t_max_N
    V = feasible_vertices(basis.J, tau_load, lo, hi)
    if len(V) == 0:
        raise InfeasibleLoad(f"no feasible tensions hold tau_ext={np.round(tau_ext, 4).tolist()} N m at this pose",
                             R, tau_ext, float("nan"))
    Gf = basis.G.reshape(basis.G.shape[0], 9)
    lam_max1, gap1, it1 = _cutting_plane(basis, tau_load, lo, hi, "max_min", tol, max_cuts)
    lam_min3, gap3, it3 = _cutting_plane(basis, tau_load, lo, hi, "min_max", tol, max_cuts)
    W = rng.dirichlet(np.full(len(V), 0.3), size=n_samples) if n_samples else np.zeros((0, len(V)))
    pts = np.vstack([V, W @ V, np.array(it1 + it3)])
    Ks = basis.K0 + (pts @ Gf).reshape(-1, 3, 3)
    lams = np.linalg.eigvalsh(0.5 * (Ks + Ks.transpose(0, 2, 1)))
    nv = len(V)
    ranges = np.array([[lams[:nv, 0].min(), lam_max1],
                       [lams[:, 1].min(), lams[:, 1].max()],
                       [lam_min3, lams[:nv, 2].max()]])
    tr = np.einsum("iaa->i", basis.G)
    tr0 = float(np.trace(basis.K0))
    trace_range = (tr0 + tr @ tension_lp(tr, basis.J, tau_load, lo, hi),
                   tr0 + tr @ tension_lp(-tr, basis.J, tau_load, lo, hi))
    method = (("vertex", "cutting-plane"), ("sampled", "sampled"), ("cutting-plane", "vertex"))
    return ReachableSet(ranges, method, float(max(gap1, gap3)), trace_range, V, lams[nv:], basis, tau_load)
