"""Benchmark: stiffness identification and parameter fit against plain baselines (same run).

* identify_stiffness (affine LS + CIs + symmetric GLS) vs the paper's bare
  ``Psi Omega^+`` (numpy pinv) on one 85-row cycle;
* fit_parameters (analytic Jacobian) vs scipy least_squares with a
  finite-difference Jacobian on the same residual.

Run: ``python benchmarks/bench_identify.py``; prints medians and ratios.
"""

from __future__ import annotations

import numpy as np
from _common import median_time  # noqa: E402
from scipy.optimize import least_squares

from csjm_opt import paper_rig, so3  # noqa: E402
from csjm_opt.identification.identify_pose import identify_stiffness  # noqa: E402
from csjm_opt.identification.param_fit import fit_parameters  # noqa: E402
from csjm_opt.measurement.instruments import InstrumentNoise  # noqa: E402
from csjm_opt.model.numeric import Model  # noqa: E402
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_log


def main() -> None:
    rig = paper_rig()
    model = Model(rig)
    rng = np.random.default_rng(0)
    inc = load_directions(84, rng) * 3.0 * rng.uniform(0.1, 1, size=(84, 1))
    log, _ = simulate_log(rig, [(np.array([0.1, -0.05, 0.02]), np.array([0.2, -0.5, 0.3]), inc)], model)
    log = add_noise(log, InstrumentNoise.paper(), rng)
    R, tau = log.R, log.tau_ext_A_Nm

    def paper():
        tl = tau + model.weight_moment(R)
        dz = so3.log(R[0].T @ R)
        return (tl[1:] - tl[0]).T @ np.linalg.pinv(dz[1:].T)

    t_base = median_time(paper, 50)
    t_id = median_time(lambda: identify_stiffness(R, tau, model), 50)
    print(f"identify (85 rows): paper pinv {t_base * 1e3:.2f} ms, identify_stiffness {t_id * 1e3:.2f} ms "
          f"(ratio {t_id / t_base:.1f}x, with CIs and symmetric GLS)")

    cycles = [(rng.normal(size=3) * 0.12, rng.normal(size=3) * 0.3, load_directions(10, rng)) for _ in range(6)]
    plog, _ = simulate_log(rig.replace(cable_stiffness_N_per_m=np.linspace(4300, 4900, 6)), cycles)
    x0 = np.r_[np.full(6, 4600.0), np.zeros(6)]

    def finite_difference_fit():
        J, c = model.jacobian(plog.R), model.cable_lengths(plog.R)
        tl = plog.tau_ext_A_Nm + model.weight_moment(plog.R)

        def resid(theta):
            T = theta[:6] * np.maximum(c - plog.rest_lengths_m - theta[6:], 0)
            return (np.einsum("nsi,ns->ni", J, T) + tl).ravel()

        return least_squares(resid, x0, x_scale=np.r_[np.full(6, 4600.0), np.full(6, 1e-3)],
                             xtol=1e-15, ftol=1e-15, gtol=1e-15)

    t_fd = median_time(finite_difference_fit, 10)
    t_fit = median_time(lambda: fit_parameters(plog, rig, model=model), 10)
    print(f"parameter fit ({len(plog)} rows, 12 parameters): scipy finite-difference Jacobian "
          f"{t_fd * 1e3:.1f} ms, fit_parameters {t_fit * 1e3:.1f} ms (ratio {t_fit / t_fd:.2f}, "
          "with covariance and condition check)")


if __name__ == "__main__":
    main()
