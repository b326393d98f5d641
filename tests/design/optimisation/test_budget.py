"""--max-evaluations is a hard bound inside an IPOPT solve of the range x stiffness optimiser.

The evaluations are counted independently of the optimiser's own bookkeeping: every solve's IPOPT
statistics (constraint and objective evaluations, line-search trials included) are read by a
wrapper around the solver, and every certification by a wrapper around ``certify``.
"""

from __future__ import annotations

import dataclasses

import pytest

import csjm_opt.design.optimisation.runner as opt_mod
from csjm_opt.design.optimisation.budget import EVALUATIONS_PER_ITERATION, STOPPED
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.errors import DesignError
from tests.design_files import tiny_design_toml

FILE = tiny_design_toml(orientations=100, max_tilt_deg=30.0, max_torsion_deg=15.0,
                        tau_ext=[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], optimise="""
objective = "range"
pareto_with = "stiffness"
pareto_points = 3
orientations = 6
certify_orientations = 300
starts = 2
""")


@pytest.fixture
def counted(tmp_path, monkeypatch):
    path = tmp_path / "range.toml"
    path.write_text(FILE)
    _, settings = read_optimise_file(path)
    log: dict[str, list] = {"solves": [], "statuses": [], "certifications": []}
    build, certify = opt_mod.build_problem, opt_mod.certify

    def counting_build(*args, **kwargs):
        pb = build(*args, **kwargs)
        solver = pb.solver

        class Counting:
            def __call__(self, **kw):
                out = solver(**kw)
                st = solver.stats()
                log["solves"].append(max(int(st["n_call_nlp_g"]), int(st["n_call_nlp_f"])))
                log["statuses"].append(st["return_status"])
                return out

            def stats(self):
                return solver.stats()

        return dataclasses.replace(pb, solver=Counting())

    def counting_certify(*args, **kwargs):
        log["certifications"].append(1)
        return certify(*args, **kwargs)

    monkeypatch.setattr(opt_mod, "build_problem", counting_build)
    monkeypatch.setattr(opt_mod, "certify", counting_certify)
    return settings, log


def test_max_evaluations_bounds_every_solve_and_the_run(counted):
    settings, log = counted
    for limit in (5, 13):
        for v in log.values():
            v.clear()
        res = opt_mod.optimise(settings, max_evaluations=limit, progress=False)
        used = sum(log["solves"]) + len(log["certifications"])
        assert used <= limit
        assert res.evaluations == used
        assert res.designs
        # a solve was ended inside by the iteration callback (not only between solves): the range problem's
        # solves take far more than these budgets (tens of iterations unbounded)
        assert STOPPED in log["statuses"]
        assert all(n <= limit - 1 for n in log["solves"])
    assert EVALUATIONS_PER_ITERATION >= 1


def test_too_small_a_budget_is_refused(counted):
    settings, _ = counted
    with pytest.raises(DesignError, match="max_evaluations"):
        opt_mod.optimise(settings, max_evaluations=3, progress=False)
