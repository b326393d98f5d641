"""A fit that starts on a bound leaves it: a pair fits its log at least as well as its own single.

A nested model's least misfit is at most its sub-model's (the sub-model is the pair with the second effect at
its nominal value), so a pair's fit that ends above its single's fit is the optimiser's failure, not the model's.
Joint friction starts on its bound (a band of 0); where its gradient points out of the band, the optimiser's first
step was cut to the start's offset from the bound and the fit ended where it began, the other effect unfitted.
"""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.testbed import simulate_experiment


@pytest.mark.parametrize("injected", ["cable_hardening", "stiffness_scale"])
def test_a_pair_with_joint_friction_fits_as_well_as_its_single(rig, injected):
    log = simulate_experiment(rig, 4, np.random.default_rng(3), effect=injected, severity=2.0, steps=3)
    t = compute_residuals(rig, log)
    single = fit_model(AugmentedModel(rig, [make_effect(injected, rig)]), t)
    pair = fit_model(AugmentedModel(rig, [make_effect(injected, rig),
                                          make_effect("joint_friction", rig, None, memory="step")]), t)
    null = fit_model(AugmentedModel(rig), t)
    assert single.rss < 0.5 * null.rss                   # the injected effect explains the log
    assert pair.rss <= single.rss * (1 + 1e-3) + 0.1     # and the pair, which holds it, as well
