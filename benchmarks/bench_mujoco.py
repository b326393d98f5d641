"""Benchmark: a 1 kHz closed loop on the MuJoCo plant, as a real-time factor.

Run: ``python benchmarks/bench_mujoco.py [--seconds S] [--repeats N] [--json PATH]``.

For each controller (inverse-dynamics feedforward, SO(3) PID feedback,
stiffness shaping) the paper rig follows a 10 deg / 15 deg tilt-and-torsion
reference at 0.5 Hz for ``--seconds`` simulated seconds: a 1 kHz control loop,
MuJoCo steps of 0.5 ms (RK4, two per period). Reported: the median over
``--repeats`` runs of the real-time factor (simulated time / wall time; >= 5
is the target) and of the per-period thread CPU time (read + control +
command + engine), and, measured in the same run as baselines, the MuJoCo
engine alone (two ``mj_step`` per period, no Python around them) and the
same loop on the quasi-static plant. Timings on a shared machine are noisy:
compare the ratios.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

from csjm_opt import so3  # noqa: E402
from csjm_opt.control import simulate  # noqa: E402
from csjm_opt.control.controllers import (  # noqa: E402
    InverseDynamicsController,
    SO3FeedbackController,
    StiffnessShapingController,
)
from csjm_opt.control.controllers.reference import reference_rates  # noqa: E402
from csjm_opt.control.load_profiles import Step  # noqa: E402
from csjm_opt.control.plants import MujocoPlant, QuasiStaticPlant  # noqa: E402
from csjm_opt.model.rig import paper_rig  # noqa: E402


def reference(t: float) -> np.ndarray:
    s = np.sin(np.pi * t)
    return so3.exp([np.radians(10) * s, 0.0, np.radians(15) * s])


def controllers(rig):
    K = np.diag([20.0, 20.0, 25.0])
    return {"inverse_dynamics": lambda: InverseDynamicsController(rig, reference),
            # gentle gains: on the quasi-static plant feedback is a one-step algebraic loop (kp < K)
            "so3_pid": lambda: SO3FeedbackController(rig, reference, kp=5.0, kd=0.0, ki=50.0),
            "stiffness_shaping": lambda: StiffnessShapingController(rig, reference, K)}


def run(make_plant, make_ctrl, rig, seconds: float) -> tuple[float, float]:
    load = Step(0.5 * seconds, [0.2, -0.1, 0.05])
    w0 = reference_rates(reference, 0.0)[1]
    plant = make_plant()
    omega0 = w0 if isinstance(plant, MujocoPlant) else None
    t0 = time.perf_counter()
    log = simulate(rig, make_ctrl(), load, seconds, plant=plant, omega_init_A_rad_s=omega0)
    wall = time.perf_counter() - t0
    return seconds / wall, float(np.median(log.step_cpu_s[1:]))


def engine_alone(rig, seconds: float) -> float:
    plant = MujocoPlant(rig)
    plant.reset(np.eye(3))
    m, d = plant.model, plant.data
    n = int(round(seconds / m.opt.timestep))
    t0 = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(m, d)
    return seconds / (time.perf_counter() - t0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    rig = paper_rig()
    results: dict = {"seconds": args.seconds, "repeats": args.repeats, "controllers": {}}
    for name, make_ctrl in controllers(rig).items():
        run(lambda: MujocoPlant(rig), make_ctrl, rig, 0.05)               # compile / warm up
        mj = [run(lambda: MujocoPlant(rig), make_ctrl, rig, args.seconds) for _ in range(args.repeats)]
        qs = [run(lambda: QuasiStaticPlant(rig), make_ctrl, rig, args.seconds) for _ in range(args.repeats)]
        entry = {"mujoco_realtime_factor": float(np.median([r for r, _ in mj])),
                 "mujoco_step_cpu_us": 1e6 * float(np.median([c for _, c in mj])),
                 "quasi_static_realtime_factor": float(np.median([r for r, _ in qs])),
                 "quasi_static_step_cpu_us": 1e6 * float(np.median([c for _, c in qs]))}
        results["controllers"][name] = entry
        entry["mujoco_cpu_realtime_factor"] = 1e3 / entry["mujoco_step_cpu_us"]
        print(f"{name:18s} MuJoCo: {entry['mujoco_realtime_factor']:6.1f}x real time wall, "
              f"{entry['mujoco_cpu_realtime_factor']:5.1f}x by CPU time "
              f"({entry['mujoco_step_cpu_us']:6.1f} us CPU/step); quasi-static plant: "
              f"{entry['quasi_static_realtime_factor']:6.1f}x ({entry['quasi_static_step_cpu_us']:6.1f} us)")
    engine = float(np.median([engine_alone(rig, args.seconds) for _ in range(args.repeats)]))
    results["engine_alone_realtime_factor"] = engine
    worst = min(e["mujoco_realtime_factor"] for e in results["controllers"].values())
    worst_cpu = min(e["mujoco_cpu_realtime_factor"] for e in results["controllers"].values())
    results["meets_5x_realtime"] = worst >= 5.0
    results["meets_5x_realtime_cpu"] = worst_cpu >= 5.0
    print(f"MuJoCo engine alone (0.5 ms RK4 steps): {engine:.1f}x real time")
    print(f"slowest controller on MuJoCo: {worst:.1f}x real time by wall clock "
          f"({'meets' if worst >= 5 else 'misses'} the 5x target), {worst_cpu:.1f}x by thread CPU time "
          f"(wall time includes waiting for the CPU on a loaded machine)")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
