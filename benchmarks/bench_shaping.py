"""Benchmark: one stiffness-shaping solve and one closed-loop step, against SLSQP in the same run.

Run: ``python benchmarks/bench_shaping.py [--repeats N] [--json PATH]``.

Shaping problem: the paper rig at a loaded, tilted pose, a Frobenius target
that is not reachable (so bounds and the full objective matter). Timed:

* ``shape_stiffness`` (public API: validation, OSQP through qpsolvers, exact
  active-set polish, CasADi check of the result);
* ``Shaper.solve`` (loop form: no qpsolvers round trip, basis reused while the
  pose is unchanged, active set warm-started), new load each call, and with a
  new pose each call (basis recomputed);
* SLSQP (scipy) on the same QP (same basis, analytic gradient), the baseline;
* one closed-loop step = read (noisy pose and load) + shape + command (rest
  lengths) + simulate (forward statics, warm-started Newton), under a
  sinusoidal load so that every step has new work; the controller part alone
  (read + shape + command) is reported too; and the same loop with the SLSQP
  shaper in place of the exact active-set QP.

Prints medians (and 99th percentiles of the loop) and the ratios; says
whether a 1 kHz loop on one core is supported and with what margin.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from _common import median_time  # noqa: E402
from scipy.optimize import minimize

from csjm_opt import so3
from csjm_opt.control.closed_loop import simulate
from csjm_opt.control.controllers import StiffnessShapingController
from csjm_opt.control.load_profiles import Constant, Sinusoid
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.rig import paper_rig
from csjm_opt.shaping.shaper import Shaper, make_objective, qp_matrices, shape_stiffness

R_POSE = so3.exp(np.array([0.1, -0.05, 0.02]))
TAU = np.array([0.3, -0.2, 0.1])
K_TARGET = np.diag([30.0, 12.0, 25.0])


def _median_us(fn, repeats: int) -> float:
    return 1e6 * median_time(fn, repeats, warmup=1)


def slsqp_solve(shaper: Shaper, R: np.ndarray, tau: np.ndarray, objective, x0: np.ndarray) -> np.ndarray:
    """The same QP as the shaper's, solved by SLSQP (analytic gradient, warm start ``x0``)."""
    rig = shaper.rig
    P, q, A, b = qp_matrices(shaper.basis(R), tau, objective, rig.t_mid_N, shaper.regularization)
    res = minimize(lambda x: 0.5 * x @ P @ x + q @ x, x0, jac=lambda x: P @ x + q, method="SLSQP",
                   bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                   constraints=[{"type": "eq", "fun": lambda x: A @ x - b, "jac": lambda x: A}],
                   options={"ftol": 1e-12, "maxiter": 200})
    return res.x


class SLSQPShapingController(StiffnessShapingController):
    """The shaping controller with SLSQP in place of the exact active-set QP (baseline)."""

    def tensions(self, R_cmd, observation):
        K_target = self.target(observation.time_s)
        obj = self._objective(K_target)
        x0 = self._last_T if self._last_T is not None else self.rig.t_mid_N
        T = slsqp_solve(self._shaper, R_cmd, observation.tau_ext_A_Nm, obj, x0)
        self._last_T = T
        return T, K_target, self._shaper.basis(R_cmd).K(T)


def run(repeats: int = 300, steps: int = 1000) -> dict:
    rig = paper_rig()
    obj = make_objective(K_TARGET)
    shaper = Shaper(rig)
    rng = np.random.default_rng(0)
    loads = TAU + 0.05 * rng.standard_normal((repeats + 1, 3))
    poses = R_POSE @ so3.exp(0.01 * rng.standard_normal((repeats + 1, 3)))
    it = iter(range(10**9))

    x_exact = shaper.solve(R_POSE, TAU, obj)[0]
    x_slsqp = slsqp_solve(shaper, R_POSE, TAU, obj, rig.t_mid_N)
    P, q, _, _ = qp_matrices(shaper.basis(R_POSE), TAU, obj, rig.t_mid_N, shaper.regularization)
    f = lambda x: 0.5 * x @ P @ x + q @ x                                       # noqa: E731
    results = {
        "shape_stiffness_us": _median_us(lambda: shape_stiffness(rig, R_POSE, TAU, K_TARGET), max(20, repeats // 10)),
        "shaper_solve_us": _median_us(lambda: shaper.solve(R_POSE, loads[next(it) % repeats], obj), repeats),
        "shaper_solve_new_pose_us": _median_us(
            lambda: shaper.solve(poses[next(it) % repeats], loads[next(it) % repeats], obj), repeats),
        "slsqp_solve_us": _median_us(
            lambda: slsqp_solve(shaper, R_POSE, loads[next(it) % repeats], obj, rig.t_mid_N), repeats),
        "objective_exact_minus_slsqp": float(f(x_exact) - f(x_slsqp)),
    }
    results["ratio_slsqp_over_shaper"] = results["slsqp_solve_us"] / results["shaper_solve_us"]

    load = Constant(TAU) + Sinusoid([0.2, 0.15, 0.05], 3.0)
    noise = InstrumentNoise.paper()
    ctrl = StiffnessShapingController(rig, R_POSE, K_TARGET)
    log = simulate(rig, ctrl, load, steps * 1e-3, 1e-3, noise=noise)
    step = log.step_time_s[1:]
    # controller part alone: read (noise) + shape + command, on the logged observations
    ctrl.reset()
    from csjm_opt.control.controllers import Observation

    def control_only(k=[0]):  # noqa: B006 - counter
        k[0] = (k[0] + 1) % steps
        R_meas = log.R[k[0]] @ so3.exp(noise.angle_sigma_rad * rng.standard_normal(3))
        tau_meas = log.tau_ext_A_Nm[k[0]] + np.asarray(noise.tau_sigma_Nm) * rng.standard_normal(3)
        ctrl(Observation(k[0] * 1e-3, R_meas, tau_meas))

    results["control_only_us"] = _median_us(control_only, repeats)
    results["loop_step_median_us"] = 1e6 * float(np.median(step))
    results["loop_step_p99_us"] = 1e6 * float(np.percentile(step, 99))
    cpu = log.step_cpu_s[1:]
    results["loop_step_cpu_median_us"] = 1e6 * float(np.median(cpu))
    results["loop_step_cpu_p99_us"] = 1e6 * float(np.percentile(cpu, 99))
    slsqp_log = simulate(rig, SLSQPShapingController(rig, R_POSE, K_TARGET), load, min(steps, 300) * 1e-3, 1e-3,
                         noise=noise)
    results["loop_step_slsqp_median_us"] = 1e6 * float(np.median(slsqp_log.step_time_s[1:]))
    results["loop_ratio_slsqp_over_exact"] = results["loop_step_slsqp_median_us"] / results["loop_step_median_us"]
    results["margin_at_1kHz"] = 1000.0 / results["loop_step_median_us"]
    results["margin_at_1kHz_cpu_p99"] = 1000.0 / results["loop_step_cpu_p99_us"]
    # supported with margin: median wall time and 99th percentile of CPU time both under half the period
    results["supports_1kHz"] = bool(results["loop_step_median_us"] < 500.0 and results["loop_step_cpu_p99_us"] < 500.0)
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=300)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--json", help="write the results as JSON to this path")
    args = ap.parse_args(argv)
    r = run(args.repeats, args.steps)
    print("stiffness shaping (paper rig, loaded tilted pose, unreachable Frobenius target)")
    print(f"  shape_stiffness (qpsolvers OSQP + exact polish)  median {r['shape_stiffness_us']:8.1f} us")
    print(f"  Shaper.solve, new load                           median {r['shaper_solve_us']:8.1f} us")
    print(f"  Shaper.solve, new pose and load                  median {r['shaper_solve_new_pose_us']:8.1f} us")
    print(f"  SLSQP on the same QP (baseline)                  median {r['slsqp_solve_us']:8.1f} us")
    print(f"  SLSQP / Shaper                                   x{r['ratio_slsqp_over_shaper']:.1f}"
          f"   (objective exact - SLSQP = {r['objective_exact_minus_slsqp']:.2e})")
    print("closed-loop step (read + shape + command + simulate), sinusoidal load, paper noise")
    print(f"  controller only (read + shape + command)          median {r['control_only_us']:8.1f} us")
    print(f"  full step, wall time                             median {r['loop_step_median_us']:8.1f} us, "
          f"p99 {r['loop_step_p99_us']:.1f} us")
    print(f"  full step, thread CPU time                       median {r['loop_step_cpu_median_us']:8.1f} us, "
          f"p99 {r['loop_step_cpu_p99_us']:.1f} us")
    print(f"  full step with SLSQP shaping                     median {r['loop_step_slsqp_median_us']:8.1f} us"
          f"  (x{r['loop_ratio_slsqp_over_exact']:.1f})")
    verdict = "yes" if r["supports_1kHz"] else "NO"
    print(f"1 kHz on one core: {verdict} (margin x{r['margin_at_1kHz']:.1f} at the median wall time, "
          f"x{r['margin_at_1kHz_cpu_p99']:.1f} at the p99 CPU time; wall-time p99 includes preemption "
          f"by other processes)")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(r, fh, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
