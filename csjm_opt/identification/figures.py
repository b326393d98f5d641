"""Figures of the identification: Figure 5's convergence curve and the verification bar chart.

The convergence curve is det K against the number of measurements N; the bar
chart shows E_theta per held-out case.

``convergence_curve`` re-identifies K from the first N rows of a cycle for
growing N; ``plot_convergence`` draws det K (paper estimate (50), affine and
symmetric-constrained estimates, with the analytic interval of det K by the
delta method) against N.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..errors import IllConditionedData
from ..model.numeric import Model
from .identify_pose import identify_stiffness
from .verify import Verification

if TYPE_CHECKING:
    from matplotlib.axes import Axes


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
                      **options: Any) -> ConvergenceCurve:
    """Identify K from the rows ``[0, n)`` for ``n = n_min .. len(R)``.

    Parameters
    ----------
    R : ndarray, shape (n, 3, 3)
        Measured orientations of {A} in {B}, one cycle in time order; row 0 is the reference.
    tau_ext_A_Nm : ndarray, shape (n, 3)
        Measured external moments in {A} (N m), platform weight excluded.
    model : Model
        Numeric model of the rig (supplies the weight moment).
    n_min : int, optional
        Smallest number of rows tried (at least 2).
    **options
        Passed to :func:`~csjm_opt.identification.identify_stiffness` (``order``, ``bootstrap``, ...).

    Returns
    -------
    ConvergenceCurve
        det K per ``n``; NaN where the first ``n`` rows do not determine K.

    Notes
    -----
    Short prefixes are imprecise by nature: unless ``allow_ill_conditioned``
    is given, they are identified with ``allow_ill_conditioned=True`` (only
    rank-deficient prefixes are left out, as NaN).
    """
    options.setdefault("allow_ill_conditioned", True)
    ns: list[float] = []
    dp: list[float] = []
    da: list[float] = []
    ds: list[float] = []
    sd: list[float] = []
    for n in range(max(2, n_min), len(R) + 1):
        ns.append(n)
        try:
            e = identify_stiffness(R[:n], tau_ext_A_Nm[:n], model, **options)
        except IllConditionedData:
            for series in (dp, da, ds, sd):
                series.append(np.nan)
            continue
        det = float(np.linalg.det(e.K))
        grad = (det * np.linalg.inv(e.K).T).ravel()   # d det / dK
        dp.append(float(np.linalg.det(e.K_paper)))
        da.append(det)
        ds.append(float(np.linalg.det(e.K_sym)))
        sd.append(float(np.sqrt(max(grad @ e.cov_K @ grad, 0.0))))
    return ConvergenceCurve(*(np.asarray(x, float) for x in (ns, dp, da, ds, sd)))


def plot_convergence(curve: ConvergenceCurve, *, title: str = "", ax: Axes | None = None) -> Axes:
    """Figure 5 of the paper: det K against the number of measurements.

    Parameters
    ----------
    curve : ConvergenceCurve
        From :func:`convergence_curve`.
    title : str, optional
        Axes title (a default names Figure 5).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure is made when omitted.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on (save with ``ax.figure.savefig(path)``).
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    ax.fill_between(curve.n, curve.det_K - 2 * curve.det_K_std, curve.det_K + 2 * curve.det_K_std,
                    color="C0", alpha=0.2, label="affine, +-2 sd")
    ax.plot(curve.n, curve.det_K, "C0-", label="affine LS")
    ax.plot(curve.n, curve.det_K_sym, "C2--", label="symmetric GLS")
    ax.plot(curve.n, curve.det_K_paper, "C3:", label="paper (49)-(50)")
    ax.set_xlabel("number of measurements")
    ax.set_ylabel(r"det $K$ ((N m/rad)$^3$)")
    ax.set_title(title or "Convergence of the identified stiffness (Figure 5)")
    ax.legend(fontsize=8)
    return ax


def plot_verification(results: Sequence[Verification], *, title: str = "",
                      ax: Axes | None = None) -> Axes:
    """Bar chart of E_theta per held-out case, one series per verification (e.g. K_D and K).

    Parameters
    ----------
    results : sequence of Verification
        From :func:`verify_increments` or :func:`verify_log`, all over the same cases.
    title : str, optional
        Axes title (a default names (63)-(65)).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure is made when omitted.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
    width = 0.8 / max(1, len(results))
    for k, res in enumerate(results):
        x = np.arange(len(res.E_theta_rad)) + k * width
        ax.bar(x, res.E_theta_rad, width, label=f"{res.use} (rms {res.rms_rad:.4f} rad)")
    ax.set_xlabel("held-out case")
    ax.set_ylabel(r"$E_\theta$ (rad)")
    ax.set_title(title or "Verification of the identified stiffness (63)-(65)")
    ax.legend()
    return ax
