"""The friction law is chosen by the evidence of the training fits: the injected law wins on noisy logs."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.selection.decision import _Context, _variant
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import simulate_experiment


@pytest.mark.parametrize("plant_effect, law", [("coulomb_friction", "coulomb"), ("friction", "capstan")])
def test_evidence_chooses_the_injected_friction_law(rig, plant_effect, law):
    """Injected ground truth: a constant friction force (Coulomb) or one proportional to the tension
    (capstan), cycles starting where the previous one settled, paper instrument noise."""
    log = simulate_experiment(rig, 5, np.random.default_rng(31), effect=plant_effect, severity=4.0,
                              noise=InstrumentNoise.paper(), steps=3)
    ctx = _Context(rig, compute_residuals(rig, log), None)
    chosen = _variant(ctx, rig, "friction", None)
    assert chosen == {"law": law, "memory": "carried"}
