"""Figures of the identification: the convergence curve of Figure 5 (det K against N).

``convergence_curve`` re-identifies K from the first N rows of a cycle for
growing N; ``plot_convergence`` draws det K (paper estimate (50), affine and
symmetric-constrained estimates, with the analytic interval of det K by the
delta method) against N.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..errors import IllConditionedData
from .identify import identify_stiffness
from ..model.numeric import Model
from .._plotting import save


@dataclasses.dataclass(frozen=True, eq=False)
class ConvergenceCurve:
    """det K for the first ``n`` rows; NaN where the rows do not determine K."""

    n: np.ndarray               # (m,) number of measurements used
    det_K_paper: np.ndarray     # (m,) (50) with corrected K_L
    det_K: np.ndarray           # (m,) affine estimate
    det_K_sym: np.ndarray       # (m,) symmetric-constrained estimate
    det_K_std: np.ndarray       # (m,) delta-method standard deviation of det K

    @property
    def final_relative_spread(self) -> float:
        """Spread of det K over the last half of the curve, relative to its final value."""
        tail = self.det_K[len(self.det_K) // 2:]
        tail = tail[np.isfinite(tail)]
        return float(np.ptp(tail) / abs(tail[-1])) if tail.size else float("nan")


def convergence_curve(R: np.ndarray, tau_ext_A_Nm: np.ndarray, model: Model, n_min: int = 5,
                      **options) -> ConvergenceCurve:
    """Identify K from rows ``[0, n)`` for ``n = n_min .. len(R)``.

    Short prefixes are imprecise by nature: unless ``allow_ill_conditioned``
    is given, they are identified with ``allow_ill_conditioned=True`` (only
    rank-deficient prefixes are left out, as NaN).
    """
    options.setdefault("allow_ill_conditioned", True)
    ns, dp, da, ds, sd = [], [], [], [], []
    for n in range(max(2, n_min), len(R) + 1):
        ns.append(n)
        try:
            e = identify_stiffness(R[:n], tau_ext_A_Nm[:n], model, **options)
        except IllConditionedData:
            dp.append(np.nan), da.append(np.nan), ds.append(np.nan), sd.append(np.nan)
            continue
        det = np.linalg.det(e.K)
        grad = (det * np.linalg.inv(e.K).T).ravel()   # d det / dK
        dp.append(np.linalg.det(e.K_paper)), da.append(det), ds.append(np.linalg.det(e.K_sym))
        sd.append(float(np.sqrt(max(grad @ e.cov_K @ grad, 0.0))))
    return ConvergenceCurve(*(np.asarray(x, float) for x in (ns, dp, da, ds, sd)))


def plot_convergence(curve: ConvergenceCurve, path: str | Path, title: str = "") -> Path:
    """Figure 5: det K against the number of measurements, saved as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.fill_between(curve.n, curve.det_K - 2 * curve.det_K_std, curve.det_K + 2 * curve.det_K_std,
                    color="C0", alpha=0.2, label="affine, +-2 sd")
    ax.plot(curve.n, curve.det_K, "C0-", label="affine LS")
    ax.plot(curve.n, curve.det_K_sym, "C2--", label="symmetric GLS")
    ax.plot(curve.n, curve.det_K_paper, "C3:", label="paper (49)-(50)")
    ax.set_xlabel("number of measurements")
    ax.set_ylabel(r"det $K$ ((N m/rad)$^3$)")
    ax.set_title(title or "Convergence of the identified stiffness (Figure 5)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save(fig, path)
