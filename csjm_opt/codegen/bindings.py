"""ctypes bindings of a generated C planner: ``load(DIR)`` gives a drop-in for the Python API.

``lib = load(DIR)`` compiles the folder if needed (:func:`csjm_opt.codegen.build.build_shared`)
and returns a :class:`CPlanner` whose :meth:`CPlanner.plan_tensions` returns the same
:class:`~csjm_opt.planning.TensionPlan` as :func:`csjm_opt.plan_tensions` and raises the same
errors (:class:`~csjm_opt.errors.InfeasibleLoad` with the distance, :class:`~csjm_opt.errors.NotARotation`,
:class:`~csjm_opt.errors.InvalidInput`), and whose :meth:`CPlanner.stiffness` gives K as
:func:`csjm_opt.stiffness` does. The work is done in C; Python only checks shapes and wraps.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_array, as_rotation, as_vector3
from ..errors import InconsistentTensions, InfeasibleLoad, InvalidInput, SolverError
from ..planning import TensionPlan
from .build import build_shared

__all__ = ["BAD_INPUT", "CPlanBatch", "CPlanner", "INFEASIBLE", "ITERATION_CAP", "NO_FALLBACK", "SOLVED", "load"]

#: Status codes of csjm.h.
SOLVED, INFEASIBLE, ITERATION_CAP, BAD_INPUT = 0, 1, 2, 3
#: Flag added to ``max_iter``: no exhaustive fallback (csjm.h ``CSJM_NO_FALLBACK``).
NO_FALLBACK = 1024

_D = ctypes.POINTER(ctypes.c_double)
_I = ctypes.POINTER(ctypes.c_int)


@functools.cache
def _structs(m: int) -> tuple[type[ctypes.Structure], type[ctypes.Structure]]:
    """The ``csjm_plan`` and ``csjm_warm_start`` structs of csjm.h for ``m`` cables."""

    class _Plan(ctypes.Structure):
        _fields_ = [("tensions_N", ctypes.c_double * m), ("rest_lengths_m", ctypes.c_double * m),
                    ("cable_lengths_m", ctypes.c_double * m), ("J", ctypes.c_double * (3 * m)),
                    ("tau_weight_A_Nm", ctypes.c_double * 3), ("R", ctypes.c_double * 9),
                    ("distance_Nm", ctypes.c_double), ("iterations", ctypes.c_int), ("fallback", ctypes.c_int)]

    class _Warm(ctypes.Structure):
        _fields_ = [("lower", ctypes.c_ubyte * m), ("upper", ctypes.c_ubyte * m)]

    return _Plan, _Warm


@dataclasses.dataclass(frozen=True, eq=False)
class CPlanBatch:
    """Results of :meth:`CPlanner.plan_many`: arrays with a leading axis ``n`` (no exceptions raised)."""

    tensions_N: np.ndarray      # (n, m)
    rest_lengths_m: np.ndarray  # (n, m)
    distance_Nm: np.ndarray     # (n,) > 0 where infeasible
    status: np.ndarray          # (n,) SOLVED, INFEASIBLE, ITERATION_CAP or BAD_INPUT
    iterations: np.ndarray      # (n,) active-set iterations
    fallback: np.ndarray        # (n,) 0 active set, 1 exhaustive search, 2 nearest boundary point


def _ptr(a: np.ndarray, kind=_D):
    return a.ctypes.data_as(kind)


def _f64(x: ArrayLike, shape: tuple[int, ...]) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(shape))


class CPlanner:
    """A loaded C planner (see :func:`load`).

    Parameters
    ----------
    path : str or Path
        The shared library (built by :func:`csjm_opt.codegen.build_shared`).
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._lib = lib = ctypes.CDLL(str(self.path))
        lib.csjm_n_cables.restype = ctypes.c_int
        #: m, the number of cables of the rig compiled in.
        self.n_cables = m = int(lib.csjm_n_cables())
        _Plan, _Warm = _structs(m)
        self._Warm = _Warm
        lib.csjm_plan_tensions_R.argtypes = [_D, _D, _D, ctypes.c_int, ctypes.POINTER(_Warm), ctypes.POINTER(_Plan)]
        lib.csjm_plan_tensions_q.argtypes = lib.csjm_plan_tensions_R.argtypes
        lib.csjm_stiffness_R.argtypes = [_D, _D, _D]
        lib.csjm_stiffness_q.argtypes = [_D, _D, _D]
        lib.csjm_pose_terms_R.argtypes = [_D, _D, _D, _D]
        lib.csjm_rest_lengths_R.argtypes = [_D, _D, _D]
        lib.csjm_rotation_from_quaternion.argtypes = [_D, _D]
        lib.csjm_t_min_N.restype = lib.csjm_t_max_N.restype = ctypes.c_double
        lib.csjm_host_plan_batch.argtypes = [ctypes.c_int, _D, _D, _D, ctypes.c_int, ctypes.c_int,
                                             _D, _D, _D, _I, _I, _I]
        lib.csjm_host_plan_batch.restype = None
        lib.csjm_host_stiffness_batch.argtypes = [ctypes.c_int, _D, _D, _D, _I]
        lib.csjm_host_stiffness_batch.restype = None
        lib.csjm_host_time_plan.argtypes = [ctypes.c_int, _D, _D, ctypes.c_int, ctypes.c_int, _D, _D]
        lib.csjm_rig_sha256.restype = ctypes.c_char_p
        #: SHA-256 of the rig the library was generated from (:func:`csjm_opt.codegen.rig_fingerprint`).
        self.rig_sha256 = lib.csjm_rig_sha256().decode()
        self.t_min_N = float(lib.csjm_t_min_N())
        self.t_max_N = float(lib.csjm_t_max_N())
        self._warm = _Warm()
        self._plan = _Plan()

    # ------------------------------------------------------------------ one pose
    def reset_warm_start(self) -> None:
        """Forget the active set kept for ``warm_start=True`` calls."""
        self._warm = self._Warm()

    def plan_tensions(self, R: ArrayLike, tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0),
                      t_ref_N: ArrayLike | None = None, warm_start: bool = False,
                      max_iter: int = 0) -> TensionPlan:
        """Tensions that hold ``tau_ext`` at ``R`` (as :func:`csjm_opt.plan_tensions`), solved in C.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Orientation of {A} in {B}.
        tau_ext_A_Nm : array_like, shape (3,), optional
            External moment in {A}, weight excluded (N m).
        t_ref_N : float or array_like, shape (m,), optional
            Reference tensions (N); default mid-range.
        warm_start : bool, optional
            Start from the previous warm-started call's active set.
        max_iter : int, optional
            Active-set iteration cap (0: the C default), optionally ``+ NO_FALLBACK``.

        Returns
        -------
        TensionPlan
            With ``solver="c"``.

        Raises
        ------
        InvalidInput
            Bad shapes or non-finite numbers.
        NotARotation
            ``R`` is not a rotation.
        InfeasibleLoad
            The load lies more than 1e-8 N m outside the wrench-feasible set.
        SolverError
            The iteration cap was reached (only with ``NO_FALLBACK``, or at a degenerate load).
        """
        R_arr = np.ascontiguousarray(np.asarray(R, dtype=np.float64))
        tau = np.ascontiguousarray(np.asarray(tau_ext_A_Nm, dtype=np.float64))
        if R_arr.shape != (3, 3) or tau.shape != (3,):
            R_arr, tau = as_rotation(R), as_vector3(tau_ext_A_Nm, "tau_ext")
        t_ref = None if t_ref_N is None else self._t_ref(t_ref_N)
        plan = self._plan
        status = self._lib.csjm_plan_tensions_R(_ptr(R_arr), _ptr(tau), None if t_ref is None else _ptr(t_ref),
                                                int(max_iter), ctypes.byref(self._warm) if warm_start else None,
                                                ctypes.byref(plan))
        if status == BAD_INPUT:
            as_rotation(R_arr), as_vector3(tau, "tau_ext")   # raise the package's error, if it sees one
            raise InvalidInput(f"the C planner refused R={R_arr.tolist()}, tau_ext={tau.tolist()}", "R")
        R_used = np.array(plan.R).reshape(3, 3)
        if status == INFEASIBLE:
            raise InfeasibleLoad(
                f"load tau_ext={np.round(tau, 4).tolist()} N m cannot be held at this pose with "
                f"{self.t_min_N:g} N <= t <= {self.t_max_N:g} N: it lies {plan.distance_Nm:.3g} N m "
                f"outside the wrench-feasible set", R_used, tau, plan.distance_Nm)
        if status != SOLVED:
            raise SolverError(f"C planner: {plan.iterations} active-set iterations did not settle "
                              f"(status {status})", "c")
        t_ref_out = np.full(self.n_cables, 0.5 * (self.t_min_N + self.t_max_N)) if t_ref is None else t_ref
        return TensionPlan(np.array(plan.tensions_N), R_used, tau.copy(), np.array(plan.tau_weight_A_Nm),
                           np.array(plan.J).reshape(self.n_cables, 3), self.t_min_N, self.t_max_N, t_ref_out, "c",
                           np.array(plan.cable_lengths_m), np.array(plan.rest_lengths_m))

    def plan_tensions_q(self, q_wxyz: ArrayLike, tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0)) -> TensionPlan:
        """:meth:`plan_tensions` from a unit quaternion ``(w, x, y, z)``.

        Parameters
        ----------
        q_wxyz : array_like, shape (4,)
            Quaternion of {A} in {B}, norm 1 within 1e-6.
        tau_ext_A_Nm : array_like, shape (3,), optional
            External moment in {A}, weight excluded (N m).

        Returns
        -------
        TensionPlan
            With ``solver="c"``.

        Raises
        ------
        InvalidInput
            Not finite, or not of unit norm.
        InfeasibleLoad
            As in :meth:`plan_tensions`.
        SolverError
            As in :meth:`plan_tensions`.
        """
        q = _f64(as_array(q_wxyz, (4,), "q_wxyz"), (4,))
        R = np.empty(9)
        if self._lib.csjm_rotation_from_quaternion(_ptr(q), _ptr(R)) != SOLVED:
            raise InvalidInput(f"q_wxyz: expected a unit quaternion, got norm {np.linalg.norm(q):.6g}", "q_wxyz")
        return self.plan_tensions(R.reshape(3, 3), tau_ext_A_Nm)

    def stiffness(self, R: ArrayLike, tensions_N: ArrayLike, check_bounds: bool = True,
                  bound_tol_N: float = 1e-6) -> np.ndarray:
        """K (3, 3) at ``R`` for ``tensions_N`` (as :func:`csjm_opt.stiffness`), computed in C.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Orientation of {A} in {B}.
        tensions_N : array_like, shape (m,)
            Cable tensions (N); ``t_i <= 0`` marks cable i slack.
        check_bounds : bool, optional
            Refuse taut cables outside ``[t_min, t_max]`` (within ``bound_tol_N``).
        bound_tol_N : float, optional
            Tolerance of that check (N).

        Returns
        -------
        K : ndarray, shape (3, 3)
            Stiffness in {A} (N m/rad), symmetric.

        Raises
        ------
        InvalidInput
            Bad shapes or non-finite numbers.
        NotARotation
            ``R`` is not a rotation.
        InconsistentTensions
            A taut cable outside the bounds.
        """
        R_arr = _f64(as_array(R, (3, 3), "R"), (3, 3))
        T = _f64(as_array(tensions_N, (self.n_cables,), "tensions"), (self.n_cables,))
        if check_bounds:
            taut = T > 0
            bad = taut & ((T < self.t_min_N - bound_tol_N) | (T > self.t_max_N + bound_tol_N))
            if np.any(bad):
                viol = np.maximum(self.t_min_N - T, T - self.t_max_N)
                i = int(np.argmax(np.where(bad, viol, -np.inf)))
                raise InconsistentTensions(f"tensions[{i}] {T[i]:.6g} N leave [{self.t_min_N:g}, {self.t_max_N:g}] N "
                                           f"by {viol[i]:.3g} N (pass check_bounds=False for states outside the "
                                           "planner's bounds)", "bounds", float(viol[i]))
        K = np.empty(9)
        if self._lib.csjm_stiffness_R(_ptr(R_arr), _ptr(T), _ptr(K)) != SOLVED:
            as_rotation(R_arr)
            raise InvalidInput("the C stiffness refused its input", "R")
        return K.reshape(3, 3)

    def pose_terms(self, R: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cable lengths (m,), J (m, 3) and weight moment (3,) at ``R``, computed in C.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Orientation of {A} in {B}.

        Returns
        -------
        c : ndarray, shape (m,)
            Cable lengths (m).
        J : ndarray, shape (m, 3)
            Jacobian of the cable lengths (m/rad).
        tau_weight_A_Nm : ndarray, shape (3,)
            Moment of the platform's weight about O, in {A} (N m).

        Raises
        ------
        InvalidInput
            Bad shape, or the C code refused ``R``.
        NotARotation
            ``R`` is not a rotation.
        """
        R_arr = _f64(as_array(R, (3, 3), "R"), (3, 3))
        c, J, w = np.empty(self.n_cables), np.empty(3 * self.n_cables), np.empty(3)
        if self._lib.csjm_pose_terms_R(_ptr(R_arr), _ptr(c), _ptr(J), _ptr(w)) != SOLVED:
            as_rotation(R_arr)
            raise InvalidInput("the C pose terms refused R", "R")
        return c, J.reshape(self.n_cables, 3), w

    # ------------------------------------------------------------------ many poses
    def plan_many(self, Rs: ArrayLike, taus_A_Nm: ArrayLike, warm_start: bool = False, max_iter: int = 0,
                  t_ref_N: ArrayLike | None = None) -> CPlanBatch:
        """Plan ``n`` poses in one C loop, warm-started along the rows if asked; never raises per row.

        Parameters
        ----------
        Rs : array_like, shape (n, 3, 3)
            Orientations of {A} in {B}.
        taus_A_Nm : array_like, shape (n, 3)
            External moments in {A}, weight excluded (N m).
        warm_start : bool, optional
            Warm-start each row from the previous one's active set.
        max_iter : int, optional
            As in :meth:`plan_tensions`.
        t_ref_N : array_like, shape (n, m), optional
            Reference tensions (N); default mid-range.

        Returns
        -------
        CPlanBatch
            One row per pose, with its status code.

        Raises
        ------
        InvalidInput
            Bad shapes.
        """
        Rs_a = _f64(as_array(Rs, (None, 3, 3), "Rs"), (-1, 9))
        n = Rs_a.shape[0]
        taus = _f64(as_array(taus_A_Nm, (n, 3), "taus"), (n, 3))
        t_ref = None if t_ref_N is None else _f64(as_array(t_ref_N, (n, self.n_cables), "t_ref"), (n, self.n_cables))
        T, rest, dist = np.empty((n, self.n_cables)), np.empty((n, self.n_cables)), np.empty(n)
        status, iters, fb = np.empty(n, np.intc), np.empty(n, np.intc), np.empty(n, np.intc)
        self._lib.csjm_host_plan_batch(n, _ptr(Rs_a), _ptr(taus), None if t_ref is None else _ptr(t_ref),
                                       int(max_iter), int(bool(warm_start)), _ptr(T), _ptr(rest), _ptr(dist),
                                       _ptr(status, _I), _ptr(iters, _I), _ptr(fb, _I))
        return CPlanBatch(T, rest, dist, status.astype(np.int64), iters.astype(np.int64), fb.astype(np.int64))

    def stiffness_many(self, Rs: ArrayLike, tensions_N: ArrayLike) -> np.ndarray:
        """K for ``n`` poses and tensions (no bound check), (n, 3, 3); NaN where C refused the row.

        Parameters
        ----------
        Rs : array_like, shape (n, 3, 3)
            Orientations of {A} in {B}.
        tensions_N : array_like, shape (n, m)
            Cable tensions (N).

        Returns
        -------
        ndarray, shape (n, 3, 3)
            Stiffness in {A} (N m/rad); NaN rows where C refused the input.

        Raises
        ------
        InvalidInput
            Bad shapes.
        """
        Rs_a = _f64(as_array(Rs, (None, 3, 3), "Rs"), (-1, 9))
        n = Rs_a.shape[0]
        T = _f64(as_array(tensions_N, (n, self.n_cables), "tensions"), (n, self.n_cables))
        K, status = np.empty((n, 9)), np.empty(n, np.intc)
        self._lib.csjm_host_stiffness_batch(n, _ptr(Rs_a), _ptr(T), _ptr(K), _ptr(status, _I))
        K[status != SOLVED] = np.nan
        return K.reshape(n, 3, 3)

    def time_plan_calls(self, Rs: ArrayLike, taus_A_Nm: ArrayLike, warm_start: bool = False,
                        max_iter: int = 0) -> tuple[np.ndarray, float, int]:
        """Time each plan call inside C (``clock_gettime``), in ns.

        Parameters
        ----------
        Rs, taus_A_Nm, warm_start, max_iter
            As in :meth:`plan_many`.

        Returns
        -------
        ns_per_call : ndarray, shape (n,)
            Time of each call (ns).
        clock_overhead_ns : float
            Mean cost of a pair of clock readings (ns).
        n_failed : int
            Calls not solved.

        Raises
        ------
        InvalidInput
            Bad shapes.
        """
        Rs_a = _f64(as_array(Rs, (None, 3, 3), "Rs"), (-1, 9))
        n = Rs_a.shape[0]
        taus = _f64(as_array(taus_A_Nm, (n, 3), "taus"), (n, 3))
        ns, overhead = np.empty(n), np.empty(1)
        failed = self._lib.csjm_host_time_plan(n, _ptr(Rs_a), _ptr(taus), int(max_iter), int(bool(warm_start)),
                                               _ptr(ns), _ptr(overhead))
        return ns, float(overhead[0]), int(failed)

    def _t_ref(self, t_ref_N: ArrayLike) -> np.ndarray:
        t = np.asarray(t_ref_N, dtype=np.float64)
        if t.shape == ():
            t = np.full(self.n_cables, float(t))
        return _f64(as_array(t, (self.n_cables,), "t_ref"), (self.n_cables,))


def load(out_dir: str | Path, extra_cflags: Sequence[str] = ()) -> CPlanner:
    """Build (if needed) and load the C planner in ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        A folder written by :func:`csjm_opt.codegen.generate_c`.
    extra_cflags : sequence of str, optional
        Extra compiler flags.

    Returns
    -------
    CPlanner

    Raises
    ------
    InvalidInput
        Not a generated folder.
    SolverError
        No C compiler, or it failed.
    """
    return CPlanner(build_shared(out_dir, extra_cflags))
