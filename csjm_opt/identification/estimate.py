"""The stiffness identified at one reference pose, with its intervals and self-checks."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .. import so3
from ..errors import InvalidInput
from .cramer_rao import SYM_NAMES, sym_to_full
from .refusal import MAX_CONDITION, MAX_RELATIVE_HALF_WIDTH


def relative_half_width(half: np.ndarray, K: np.ndarray) -> float:
    """Largest interval half-width of an entry of ``K`` over ``||K||_2`` (inf when undetermined).

    Parameters
    ----------
    half : array
        Half-widths of K's entries (N m/rad).
    K : (3, 3) array
        The estimate (N m/rad).

    Returns
    -------
    float
        The ratio; ``inf`` when ``K`` is zero or a half-width is not finite.
    """
    scale = float(np.linalg.norm(K, 2))
    return float(np.max(half) / scale) if scale > 0 and np.all(np.isfinite(half)) else float("inf")


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
    # ---- the default estimator: maximum likelihood (csjm_opt.identification.ml_estimator)
    K_ml: np.ndarray = dataclasses.field(default_factory=lambda: np.full((3, 3), np.nan))
    crlb6: np.ndarray = dataclasses.field(default_factory=lambda: np.full((6, 6), np.nan))  # bound, SYM_NAMES
    cov6_ml: np.ndarray = dataclasses.field(default_factory=lambda: np.full((6, 6), np.nan))  # sandwich
    ml_quantile: float = float("nan")  # half-width = quantile * sqrt(crlb)
    curvature: str = "none"         # "model": second-order term from the rig model; "none"
    noise_estimated: bool = True    # the noise of the bound was estimated from the residuals
    estimator: str = "K_ml"

    @property
    def K_ml_std(self) -> np.ndarray:
        """(3, 3) standard errors of K_ml (square roots of the bound)."""
        return np.sqrt(np.diag(sym_to_full(self.crlb6))).reshape(3, 3)

    @property
    def K_ml_ci(self) -> np.ndarray:
        """(2, 3, 3) interval of K_ml at ``ci_level`` (from the information at the estimate)."""
        h = self.ml_quantile * self.K_ml_std
        return np.stack([self.K_ml - h, self.K_ml + h])

    @property
    def efficiency(self) -> float:
        """``trace(bound) / trace(own covariance)`` of K_ml's six entries (about 1 when the models hold)."""
        t = float(np.trace(self.cov6_ml))
        return float(np.trace(self.crlb6) / t) if t > 0 else float("nan")

    @property
    def relative_half_width(self) -> float:
        """Largest CI half-width of an entry of K over ``||K||_2``, the better of the linear fit and K_ml.

        The precision rule's measure (:data:`MAX_RELATIVE_HALF_WIDTH`): K is determined when either
        estimate determines it.
        """
        return min(relative_half_width(self.ci_quantile * self.K_std, self.K),
                   relative_half_width(self.ml_quantile * self.K_ml_std, self.K_ml))

    # ----------------------------------------------------------- self-checks
    @property
    def K_std(self) -> np.ndarray:
        """(3, 3) standard errors of K (N m/rad, from the diagonal of ``cov_K``)."""
        return np.sqrt(np.diag(self.cov_K)).reshape(3, 3)

    @property
    def K_sym_std(self) -> np.ndarray:
        """(3, 3) standard errors of K_sym (N m/rad, from the diagonal of ``cov_K_sym``)."""
        return np.sqrt(np.diag(self.cov_K_sym)).reshape(3, 3)

    @property
    def K_ci(self) -> np.ndarray:
        """(2, 3, 3) analytic interval of K at ``ci_level``."""
        h = self.ci_quantile * self.K_std
        return np.stack([self.K - h, self.K + h])

    @property
    def K_sym_ci(self) -> np.ndarray:
        """(2, 3, 3) analytic interval of K_sym at ``ci_level``."""
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
        """Whether the confidence interval of each entry contains the true value (for simulation studies).

        Parameters
        ----------
        K_true : array_like, shape (3, 3)
            The true stiffness (N m/rad).
        which : {"K", "K_sym", "K_ml", "bootstrap"}, optional
            Which interval: of the affine estimate, the symmetric one, the maximum-likelihood one,
            or the pairs bootstrap.

        Returns
        -------
        ndarray of bool, shape (3, 3)
            True where the interval contains ``K_true``.

        Raises
        ------
        InvalidInput
            If ``which`` is not one of the names above, or is ``"bootstrap"`` but the estimate was
            made without bootstrap resamples.
        """
        intervals = {"K": self.K_ci, "K_sym": self.K_sym_ci, "K_ml": self.K_ml_ci, "bootstrap": self.bootstrap_K_ci}
        if which not in intervals:
            raise InvalidInput(f"which must be one of {sorted(intervals)}, got {which!r}", "which")
        interval = intervals[which]
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
        if np.isfinite(self.efficiency) and self.efficiency < 0.5:
            out.append(f"K_ml scatters {1 / self.efficiency:.1f}x more than its bound: the noise statement "
                       "or the rig model's curvature does not hold")
        if np.any(np.linalg.eigvalsh(self.K_sym) <= 0):
            out.append("K_sym is not positive definite: the reference pose looks unstable")
        return out

    def as_dict(self) -> dict[str, Any]:
        """The estimate as a JSON-able dict (the per-cycle entry of ``csjm identify --json``).

        Returns
        -------
        dict
            ``estimator`` (``"K_ml"``, the default estimate) with ``K_ml``, ``K_ml_ci`` ([lower, upper]),
            ``crlb_std`` (bound of K11, K22, K33, K12, K13, K23), ``K_ml_cov`` (its own covariance),
            ``efficiency``; ``cycle``, ``K_D``, ``K_L``, ``K``, ``K_sym``, ``K_paper``, intervals, condition numbers,
            symmetry, residuals and ``problems`` (keys in docs/conventions.md).
        """
        d = {"cycle": self.cycle, "n_rows": self.n_rows, "order": self.order,
             "estimator": self.estimator, "K_ml": self.K_ml, "K_ml_ci": self.K_ml_ci, "K_ml_std": self.K_ml_std,
             "crlb_std": np.sqrt(np.diag(self.crlb6)), "crlb_entries": list(SYM_NAMES), "crlb_cov": self.crlb6,
             "K_ml_cov": self.cov6_ml, "efficiency": self.efficiency, "curvature": self.curvature,
             "noise": "estimated" if self.noise_estimated else "stated",
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
