"""Stiffness identification at a pose from measured loads and displacements (Section III).

For one load cycle (rows in time order, the first row is the reference)::

    dzeta_i = log(R_ref^T R_i)                        body frame, (46)
    tau_load_i = tau_ext_i + tau_weight(R_i)          total load (55)-(56), in {A}
    K_D ~ dtau_load / dzeta                           (48a), estimated by (49)
    K = K_D + K_L,  K_L = -1/2 hat(tau_load_ref)      (47), corrected (errata 1-2)

Three estimates are returned together in :class:`StiffnessEstimate`:

* ``K_D_paper`` / ``K_paper``: the paper's literal ``Psi Omega^+`` on
  differences to the reference row (49)-(50), with the corrected ``K_L``.
* ``K_D`` / ``K``: affine least squares ``tau_load_i = c + K_D dzeta_i
  [+ terms of degree 2..order]`` over all rows, so the reference row's noise
  is not copied into every difference; ``K_L`` uses the fitted ``c``. With an
  :class:`~csjm_opt.measurement.instruments.InstrumentNoise`, the normal matrix is
  corrected for the known orientation noise in ``dzeta`` (errors-in-variables,
  corrected least squares) and the covariance uses the instrument model.
* ``K_sym``: the symmetric-constrained estimate. K is symmetric (37), so
  ``K_D - K_D^T = hat(tau0)`` with ``tau0`` the load at the reference; with
  ``K_D = S + 1/2 hat(tau0)`` the model ``tau_load_i = (I - 1/2 hat(dzeta_i))
  tau0 + S dzeta_i`` is linear in ``(tau0, S)`` and ``K_sym = S`` is fitted by
  generalised least squares, weighted by the row covariance
  ``Sigma_tau + sigma_angle^2 K_D K_D^T`` (effective variance).

Confidence intervals are analytic (Student t on the residual covariance, or
normal on the instrument covariance) and optionally a pairs bootstrap.

Refusal rule (what cannot be identified is not returned): a cycle is refused
with :class:`~csjm_opt.errors.IllConditionedData` when its displacements do
not span three directions (rank < 3 or condition > ``max_condition``), or when
the estimate is not determined to :data:`MAX_RELATIVE_HALF_WIDTH`: the largest
confidence half-width of any entry of K, relative to ``||K||_2`` (the largest
singular value of K), exceeds 0.2. The error carries ``direction``, the
weakest direction of the centred load moments in {A} (smallest right singular
vector): loads with a moment component along it supply what is missing.
``allow_ill_conditioned=True`` returns the estimate anyway (rank 3 needed),
marked ``ill_conditioned``.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np
from scipy import stats

from .. import so3
from ..errors import IllConditionedData, InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from ..model.rig import Rig
from .stiffness_fits import (
    affine_fit,
    bootstrap_interval,
    n_parameters,
    paper_estimate,
    symmetric_fit,
)
from .._limits import MAX_BOOTSTRAP
from .._validate import as_array, as_rotations

#: Default largest accepted condition number of the (centred) excitation. A
#: load cycle along one direction gives 100-500 with the paper's noise (its
#: weakest "direction" is noise), a designed multi-direction cycle 1.5-4.
MAX_CONDITION = 100.0
#: Smallest singular value of the excitation, in units of the orientation noise, to call it determined.
NOISE_FLOOR_FACTOR = 3.0
#: Stated precision: largest accepted confidence half-width of an entry of K relative to ||K||_2.
MAX_RELATIVE_HALF_WIDTH = 0.2


@dataclasses.dataclass(frozen=True, eq=False)
class StiffnessEstimate:
    """Stiffness identified at one reference pose; matrices in N m/rad, {A}."""

    cycle: int | None
    n_rows: int
    order: int
    R_ref: np.ndarray               # (3, 3) measured reference orientation
    tau_load_ref_A_Nm: np.ndarray   # (3,) fitted total load at the reference
    K_D: np.ndarray                 # affine (EIV-corrected) estimate of dtau_load/dzeta
    K_L: np.ndarray                 # -1/2 hat(tau_load_ref)
    K: np.ndarray                   # K_D + K_L
    K_sym: np.ndarray               # symmetric-constrained GLS estimate
    K_D_paper: np.ndarray           # Psi Omega^+ (49)
    K_paper: np.ndarray             # (50) with the corrected K_L
    cov_K: np.ndarray               # (9, 9) covariance of K.ravel()
    cov_K_sym: np.ndarray           # (9, 9) covariance of K_sym.ravel()
    ci_level: float
    ci_quantile: float              # half-width = quantile * standard error
    condition: float                # condition number of the centred excitation
    singular_values_rad: np.ndarray  # (3,)
    residual_rms_Nm: float
    chi2_per_dof: float             # residuals against the instrument model (nan without one)
    bootstrap_K_ci: np.ndarray | None = None  # (2, 3, 3) percentile interval of K, or None
    design_condition: float = float("nan")  # condition of the column-scaled design (with higher terms)
    weakest_load_direction_A: np.ndarray = dataclasses.field(default_factory=lambda: np.full(3, np.nan))
    ill_conditioned: bool = False   # returned although refused by the rule (allow_ill_conditioned=True)

    @property
    def relative_half_width(self) -> float:
        """Largest CI half-width of an entry of K over ``||K||_2`` (the precision rule's measure)."""
        scale = float(np.linalg.norm(self.K, 2))
        return float(np.max(self.ci_quantile * self.K_std) / scale) if scale > 0 else float("inf")

    # ----------------------------------------------------------- self-checks
    @property
    def K_std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov_K)).reshape(3, 3)

    @property
    def K_sym_std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov_K_sym)).reshape(3, 3)

    @property
    def K_ci(self) -> np.ndarray:
        """(2, 3, 3) analytic interval of K at ``ci_level``."""
        h = self.ci_quantile * self.K_std
        return np.stack([self.K - h, self.K + h])

    @property
    def K_sym_ci(self) -> np.ndarray:
        h = self.ci_quantile * self.K_sym_std
        return np.stack([self.K_sym - h, self.K_sym + h])

    @property
    def symmetry_error(self) -> float:
        """``||K - K^T||_F / ||K||_F`` of the unconstrained estimate (0 for a perfect one)."""
        return float(np.linalg.norm(self.K - self.K.T) / np.linalg.norm(self.K))

    @property
    def symmetry_z(self) -> np.ndarray:
        """Asymmetry ``K_ij - K_ji`` (i<j) in standard errors: |z| >> 2 flags unmodelled effects."""
        out = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            a, b = 3 * i + j, 3 * j + i
            var = self.cov_K[a, a] + self.cov_K[b, b] - 2 * self.cov_K[a, b]
            out.append((self.K[i, j] - self.K[j, i]) / np.sqrt(max(var, 1e-300)))
        return np.asarray(out)

    def covers(self, K_true: np.ndarray, which: str = "K") -> np.ndarray:
        """Does the confidence interval of each entry contain the true value? (For simulation studies.)

        Parameters
        ----------
        K_true : array_like, shape (3, 3)
            The true stiffness (N m/rad).
        which : {"K", "K_sym", "bootstrap"}, optional
            Which interval: of the affine estimate, the symmetric one, or the pairs bootstrap.

        Returns
        -------
        ndarray of bool, shape (3, 3)
            True where the interval contains ``K_true``.

        Raises
        ------
        InvalidInput
            If ``which="bootstrap"`` but the estimate was made without bootstrap resamples.
        """
        interval = {"K": self.K_ci, "K_sym": self.K_sym_ci, "bootstrap": self.bootstrap_K_ci}[which]
        if interval is None:
            raise InvalidInput("no bootstrap interval: identify with bootstrap > 0", "which")
        lo, hi = interval
        return (lo <= K_true) & (K_true <= hi)

    def is_well_conditioned(self, max_condition: float = MAX_CONDITION) -> bool:
        """Whether the excitation determines K: condition number at most ``max_condition``.

        Parameters
        ----------
        max_condition : float, optional
            Largest accepted condition number of the excitation.

        Returns
        -------
        bool
        """
        return bool(np.isfinite(self.condition) and self.condition <= max_condition)

    def problems(self, max_condition: float = MAX_CONDITION, max_symmetry_z: float = 3.0,
                 max_chi2: float = 2.0) -> list[str]:
        """What the estimate itself says is doubtful (an empty list: nothing).

        Parameters
        ----------
        max_condition : float, optional
            Largest accepted condition number of the excitation.
        max_symmetry_z : float, optional
            Largest accepted z-score of the asymmetry of K (K is symmetric in theory).
        max_chi2 : float, optional
            Largest accepted chi^2 per degree of freedom against the instrument model.

        Returns
        -------
        list of str
            One sentence per problem found.
        """
        out = []
        if self.ill_conditioned or self.relative_half_width > MAX_RELATIVE_HALF_WIDTH:
            out.append(f"ill-conditioned: K determined only to {self.relative_half_width:.0%} of ||K|| "
                       f"(rule: {MAX_RELATIVE_HALF_WIDTH:.0%}); weakest load direction "
                       f"{np.round(self.weakest_load_direction_A, 3).tolist()} in {{A}}")
        if not self.is_well_conditioned(max_condition):
            out.append(f"excitation condition {self.condition:.3g} > {max_condition:g}")
        z = np.max(np.abs(self.symmetry_z))
        if z > max_symmetry_z:
            out.append(f"K is significantly asymmetric ({z:.1f} standard errors): unmodelled effects "
                       "(friction, link compliance) or a wrong weight/reference")
        if self.design_condition > max_condition:
            out.append(f"design condition {self.design_condition:.3g}: curvature terms are poorly separated "
                       "from the linear ones (vary load magnitudes as well as directions, or lower the order)")
        if np.isfinite(self.chi2_per_dof) and self.chi2_per_dof > max_chi2:
            out.append(f"residuals {self.chi2_per_dof:.2f}x the instrument variance: model or noise "
                       "assumptions do not hold")
        if np.any(np.linalg.eigvalsh(self.K_sym) <= 0):
            out.append("K_sym is not positive definite: the reference pose looks unstable")
        return out

    def as_dict(self) -> dict[str, Any]:
        """The estimate as a JSON-able dict (the per-cycle entry of ``csjm identify --json``).

        Returns
        -------
        dict
            ``cycle``, ``K_D``, ``K_L``, ``K``, ``K_sym``, ``K_paper``, intervals, condition numbers,
            symmetry, residuals and ``problems`` (keys in docs/conventions.md).
        """
        d = {"cycle": self.cycle, "n_rows": self.n_rows, "order": self.order,
             "K_D": self.K_D, "K_L": self.K_L, "K": self.K, "K_sym": self.K_sym,
             "K_D_paper": self.K_D_paper, "K_paper": self.K_paper,
             "K_std": self.K_std, "K_sym_std": self.K_sym_std,
             "ci_level": self.ci_level, "K_ci": self.K_ci, "K_sym_ci": self.K_sym_ci,
             "condition": self.condition, "design_condition": self.design_condition,
             "singular_values_rad": self.singular_values_rad,
             "symmetry_error": self.symmetry_error, "symmetry_z": self.symmetry_z,
             "tau_load_ref_A_Nm": self.tau_load_ref_A_Nm, "rotvec_ref": so3.log(self.R_ref),
             "residual_rms_Nm": self.residual_rms_Nm,
             "relative_half_width": self.relative_half_width, "ill_conditioned": self.ill_conditioned,
             "weakest_load_direction_A": self.weakest_load_direction_A,
             "chi2_per_dof": None if not np.isfinite(self.chi2_per_dof) else self.chi2_per_dof,
             "det_K": float(np.linalg.det(self.K)), "eig_K_sym": np.linalg.eigvalsh(self.K_sym),
             "problems": self.problems()}
        if self.bootstrap_K_ci is not None:
            d["bootstrap_K_ci"] = self.bootstrap_K_ci
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()}


# ------------------------------------------------------------------ design
def excitation(dzeta: np.ndarray, noise: InstrumentNoise | None = None,
               max_condition: float = MAX_CONDITION) -> tuple[float, np.ndarray]:
    """Condition number and singular values of the centred displacements.

    Raises :class:`IllConditionedData` when they do not span three directions:
    rank below 3, condition above ``max_condition``, or (with a noise model) a
    smallest singular value within ``NOISE_FLOOR_FACTOR`` of the orientation noise.
    """
    Z = dzeta - dzeta.mean(axis=0)
    s = np.linalg.svd(Z, compute_uv=False) if len(Z) else np.zeros(0)
    s = np.concatenate([s, np.zeros(3 - len(s))])[:3]
    rank = int(np.sum(s > s[0] * 1e-10)) if s[0] > 0 else 0
    cond = float(s[0] / s[2]) if s[2] > 0 else float("inf")
    floor = 0.0 if noise is None else NOISE_FLOOR_FACTOR * noise.angle_sigma_rad * np.sqrt(2 * len(Z))
    if rank < 3 or cond > max_condition or s[2] <= floor:
        raise IllConditionedData(
            f"displacements do not span three directions: singular values "
            f"{np.array2string(s, precision=3)} rad, condition {cond:.3g} (limit {max_condition:g})"
            + (f", noise floor {floor:.2g} rad" if floor else ""), cond, rank)
    return cond, s


def _check_rows(n: int, p: int) -> None:
    if n < p + 1:
        raise IllConditionedData(f"{n} rows cannot determine {p} parameters per axis "
                                 f"(need at least {p + 1})", float("inf"), n)


# --------------------------------------------------------------- estimators
@functools.lru_cache(maxsize=256)
def _quantile(ci_level: float, dof: int) -> float:
    """Two-sided quantile: Student t with ``dof`` degrees of freedom, normal for ``dof = 0`` (cached)."""
    a = 0.5 + ci_level / 2
    return float(stats.norm.ppf(a) if dof == 0 else stats.t.ppf(a, dof))


def weakest_load_direction(tau_load_A_Nm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit direction in {A} along which the centred load moments vary least, and their singular values (N m).

    The sign is fixed so that the largest component is positive.
    """
    T = tau_load_A_Nm - tau_load_A_Nm.mean(axis=0)
    _, s, Vt = np.linalg.svd(T, full_matrices=True)
    u = Vt[-1]
    u = u if u[np.argmax(np.abs(u))] >= 0 else -u
    return u, np.concatenate([s, np.zeros(3 - len(s))])[:3]


def _missing(u: np.ndarray) -> str:
    v = np.round(u, 2) + 0.0
    return (f"the load moments barely vary along [{v[0]:.2f}, {v[1]:.2f}, {v[2]:.2f}] in {{A}}; add loads "
            "with a moment component along that direction (or pass allow_ill_conditioned / "
            "--allow-ill-conditioned)")


def identify_stiffness(R: np.ndarray, tau_ext_A_Nm: np.ndarray, model: Model | None = None,
                       tau_weight_A_Nm: np.ndarray | None = None, *, noise: InstrumentNoise | None = None,
                       order: int = 1, ci_level: float = 0.95, bootstrap: int = 0,
                       rng: np.random.Generator | None = None, max_condition: float = MAX_CONDITION,
                       cycle: int | None = None, allow_ill_conditioned: bool = False) -> StiffnessEstimate:
    """Identify K at ``R[0]`` from one cycle's orientations (n, 3, 3) and external moments (n, 3).

    Parameters
    ----------
    R : array (n, 3, 3)
        Measured orientations of {A} in {B}; row 0 is the reference.
    tau_ext_A_Nm : array (n, 3)
        External moments about O in {A} (N m), platform weight excluded.
    model : Model, optional
        Gives the weight moment at each measured pose when ``tau_weight_A_Nm`` is not given.
    tau_weight_A_Nm : array (n, 3), optional
        Weight moments (zeros for a weightless platform).
    noise : InstrumentNoise, optional
        Instrument model: errors-in-variables correction and normal intervals.
    order : {1, 2, 3}
        Degree of the fit in dzeta.
    ci_level : float
        Confidence level in (0, 1).
    bootstrap : int
        Pairs-bootstrap resamples, 0 to :data:`~csjm_opt._limits.MAX_BOOTSTRAP`.
    rng : numpy.random.Generator, optional
        Bootstrap generator.
    max_condition : float
        Largest accepted condition number of the displacements (>= 1; ``inf``: no limit).
    cycle : int, optional
        Cycle id stored in the result.
    allow_ill_conditioned : bool
        Return an estimate that fails the precision rule (or the condition
        limit) anyway, marked ``ill_conditioned``; rank-deficient data still raise.

    Returns
    -------
    StiffnessEstimate

    Raises
    ------
    InvalidInput
        Bad shapes, values or options.
    IllConditionedData
        The cycle does not determine K (module docstring: rank, condition,
        relative precision); ``direction`` is the weakest load direction in {A}.
    """
    R = as_rotations(R, "R")
    n = R.shape[0]
    tau_ext = as_array(tau_ext_A_Nm, (n, 3), "tau_ext")
    if tau_weight_A_Nm is None:
        if model is None:
            raise InvalidInput("give a model (for the weight moment) or tau_weight_A_Nm", "model")
        tau_weight_A_Nm = model.weight_moment(R)
    if order not in (1, 2, 3):
        raise InvalidInput(f"order: expected 1, 2 or 3, got {order!r}", "order")
    if isinstance(bootstrap, bool) or not isinstance(bootstrap, (int, np.integer)) \
            or not 0 <= bootstrap <= MAX_BOOTSTRAP:
        raise InvalidInput(f"bootstrap: expected an integer in [0, {MAX_BOOTSTRAP}], got {bootstrap!r}", "bootstrap")
    if not (isinstance(ci_level, (int, float)) and 0 < ci_level < 1):
        raise InvalidInput(f"ci_level: expected a number in (0, 1), got {ci_level!r}", "ci_level")
    if not (isinstance(max_condition, (int, float)) and 1 <= max_condition):
        raise InvalidInput(f"max_condition: expected a number >= 1 (inf: no limit), got {max_condition!r}",
                           "max_condition")
    tau_load = tau_ext + as_array(tau_weight_A_Nm, (n, 3), "tau_weight")
    dzeta = so3.log(np.swapaxes(R[0], -1, -2)[None] @ R)
    p = n_parameters(order)
    _check_rows(n, p)
    u, _ = weakest_load_direction(tau_load)
    ill = False
    try:
        cond, s = excitation(dzeta, noise, max_condition)
    except IllConditionedData as exc:
        if not allow_ill_conditioned or exc.rank is None or exc.rank < 3:
            raise IllConditionedData(f"{exc}; {_missing(u)}", exc.condition, exc.rank, u) from exc
        cond, ill = exc.condition, True
        s = np.linalg.svd(dzeta - dzeta.mean(axis=0), compute_uv=False)[:3]

    K_D_paper = paper_estimate(dzeta, tau_load)
    fit = affine_fit(dzeta, tau_load, order, noise)
    sym = symmetric_fit(dzeta, tau_load, order, fit["Sigma"])
    if noise is not None:
        q = _quantile(ci_level, 0)
        Y_std = np.sqrt(np.asarray(noise.tau_sigma_Nm) ** 2
                        + noise.angle_sigma_rad ** 2 * np.sum(fit["K_D"] ** 2, axis=1))
        chi2 = float(np.sum((fit["resid"] / Y_std) ** 2) / (3 * (n - p)))
    else:
        q = _quantile(ci_level, n - p)
        chi2 = float("nan")
    half = q * np.sqrt(np.maximum(np.diag(fit["cov_K"]), 0.0))
    scale = float(np.linalg.norm(fit["K"], 2))
    rel = float(half.max() / scale) if scale > 0 else float("inf")
    if not rel <= MAX_RELATIVE_HALF_WIDTH:
        if not allow_ill_conditioned:
            raise IllConditionedData(
                f"K is not determined to {MAX_RELATIVE_HALF_WIDTH:.0%}: {int(round(ci_level * 100))} % "
                f"half-widths up to {half.max():.3g} N m/rad against ||K|| = {scale:.3g} N m/rad "
                f"({rel:.0%}); {_missing(u)}", cond, 3, u)
        ill = True
    boot = None
    if bootstrap:
        boot = bootstrap_interval(dzeta, tau_load, order, noise, bootstrap, ci_level,
                                  rng or np.random.default_rng(0))
    return StiffnessEstimate(
        cycle=cycle, n_rows=n, order=order, R_ref=R[0], tau_load_ref_A_Nm=fit["c"],
        K_D=fit["K_D"], K_L=-0.5 * so3.hat(fit["c"]), K=fit["K"], K_sym=sym["K"],
        K_D_paper=K_D_paper, K_paper=K_D_paper - 0.5 * so3.hat(tau_load[0]),
        cov_K=fit["cov_K"], cov_K_sym=sym["cov_K"], ci_level=ci_level, ci_quantile=q,
        condition=cond, singular_values_rad=s,
        residual_rms_Nm=float(np.sqrt(np.mean(np.sum(fit["resid"] ** 2, axis=1)))),
        chi2_per_dof=chi2, bootstrap_K_ci=boot, design_condition=float(fit["design_condition"]),
        weakest_load_direction_A=u, ill_conditioned=ill)


# ---------------------------------------------------------------- whole logs
def identify_log(log: MeasurementLog, rig: Rig, cycle: int | None = None, model: Model | None = None,
                 progress: Any = None, **options: Any) -> list[StiffnessEstimate]:
    """One :class:`StiffnessEstimate` per cycle of ``log`` (or only ``cycle``).

    Parameters
    ----------
    log : MeasurementLog
    rig : Rig
    cycle : int, optional
        Only this cycle.
    model : Model, optional
        Reused numeric model of ``rig``.
    progress : callable, optional
        Wraps the iterable of cycles (e.g. ``functools.partial(tqdm, ...)``).
    **options
        Passed to :func:`identify_stiffness`.

    Returns
    -------
    list of StiffnessEstimate

    Raises
    ------
    IllConditionedData
        For the first cycle that cannot be identified (message starts with its id).
    """
    model = model or Model(rig)
    cycles = log.cycle_ids if cycle is None else [cycle]
    out = []
    pairs = _cycle_rows(log, cycles)
    R, W = _poses_and_weight(log, np.concatenate([rows for _, rows in pairs]), model)
    for c, rows in (progress(pairs) if progress is not None else pairs):
        try:
            out.append(identify_stiffness(R[rows], log.tau_ext_A_Nm[rows], model, W[rows], cycle=c, **options))
        except IllConditionedData as exc:
            raise IllConditionedData(f"cycle {c}: {exc}", exc.condition, exc.rank, exc.direction) from exc
    return out


def identify_cycles(log: MeasurementLog, rig: Rig, model: Model | None = None, progress: Any = None,
                    **options: Any) -> tuple[list[StiffnessEstimate], list[dict[str, Any]]]:
    """Every cycle that can be identified, and the others with the reason.

    A log may mix identification cycles with cycles that load along one
    direction (hysteresis or diagnosis cycles), which cannot determine K; those
    are returned as ``{"cycle", "reason", "condition", "weakest_load_direction_A"}``
    instead of stopping the whole log. Time is linear in the log length
    (orientations are computed once per cycle's rows).

    Raises
    ------
    IllConditionedData
        The first cycle's error, when no cycle can be identified.
    """
    model = model or Model(rig)
    estimates, skipped, first_error = [], [], None
    pairs = _cycle_rows(log, log.cycle_ids)
    R, W = _poses_and_weight(log, np.arange(len(log)), model)
    for c, rows in (progress(pairs) if progress is not None else pairs):
        try:
            estimates.append(identify_stiffness(R[rows], log.tau_ext_A_Nm[rows], model, W[rows], cycle=c,
                                                **options))
        except IllConditionedData as exc:
            err = IllConditionedData(f"cycle {c}: {exc}", exc.condition, exc.rank, exc.direction)
            first_error = first_error or err
            skipped.append({"cycle": c, "reason": str(exc), "condition": exc.condition,
                            "weakest_load_direction_A": None if exc.direction is None else exc.direction.tolist()})
    if not estimates and first_error is not None:
        raise first_error
    return estimates, skipped


def _cycle_rows(log: MeasurementLog, cycles: list[int]) -> list[tuple[int, np.ndarray]]:
    """(cycle id, row indices) pairs; rows found once for the whole log (no per-cycle scan)."""
    cyc = np.asarray(log.cycle)
    starts = np.flatnonzero(np.r_[True, cyc[1:] != cyc[:-1]])
    ends = np.r_[starts[1:], len(cyc)]
    where = {int(cyc[a]): np.arange(a, b) for a, b in zip(starts, ends)}
    pairs = []
    for c in cycles:
        if c not in where:
            log.cycle_rows(c)  # raises DataFileError naming the cycles
        pairs.append((c, where[c]))
    return pairs


def _poses_and_weight(log: MeasurementLog, rows: np.ndarray, model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Orientations (n, 3, 3) and weight moments (n, 3) of the log, computed once for ``rows``
    (other rows are left zero): one batched call instead of one per cycle."""
    R = np.zeros((len(log), 3, 3))
    W = np.zeros((len(log), 3))
    if len(rows):
        R[rows] = so3.exp(log.rotvec_rad[rows])
        W[rows] = model.weight_moment(R[rows])
    return R, W
