"""Diagnosis effects sized by the rig's cable count m (notes/shapes.md): parameter counts, names, hole offsets."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.diagnose.effects import EFFECTS, make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows
from csjm_opt.model.rig import Rig

RIGS = Path(__file__).resolve().parents[3] / "rigs"

#: Parameters per cable of the per-cable effects (written out from the effects' physics, not their code):
#: three platform and three base coordinates per hole pair, one friction band, one drive offset.
PER_CABLE = {"hole_offsets": 6, "friction": 1, "drive_offsets": 1}


@pytest.fixture(scope="module")
def rigs():
    return {r.n_cables: r for r in (Rig.from_toml(RIGS / "eight_cable.toml"), Rig.from_toml(RIGS / "four_cable.toml"),
                                    Rig.from_toml(RIGS / "paper.toml"))}


@pytest.mark.parametrize("name", list(EFFECTS))
def test_parameter_count_scales_with_the_cable_count(rigs, name):
    six = make_effect(name, rigs[6])
    for m in (4, 8):
        e = make_effect(name, rigs[m])
        assert e.n_cables == m
        per = PER_CABLE.get(name, 0)
        assert e.n_params == six.n_params + per * (m - 6)
        assert len(e.scales) == len(e.x0()) == len(e.lower_bounds) == len(e.upper_bounds) == e.n_params
        assert list(e.ranges()) == list(e.param_names) and len(set(e.param_names)) == e.n_params
        if e.prior_sd is not None:
            assert len(e.prior_sd) == e.n_params


def test_per_cable_names_index_the_cables_from_one(rigs):
    for m in (4, 6, 8):
        rig = rigs[m]
        assert make_effect("hole_offsets", rig).param_names == tuple(
            [f"dA{i}_{a}_m" for i in range(1, m + 1) for a in "xyz"]
            + [f"dB{i}_{a}_m" for i in range(1, m + 1) for a in "xyz"])
        assert make_effect("drive_offsets", rig).param_names == tuple(f"drive_offset{i}_m" for i in range(1, m + 1))
        assert make_effect("friction", rig).param_names == (
            tuple(f"mu_beta_{i}" for i in range(1, m + 1)) + ("stick_travel_factor", "first_row_state"))
        assert make_effect("friction", rig, law="coulomb").param_names[:m] == tuple(f"F_{i}_N" for i in range(1, m + 1))


def test_six_cable_names_are_unchanged():
    """Without a rig (and on the paper rig) the effects keep the six-cable names of before."""
    assert make_effect("hole_offsets").param_names[:4] == ("dA1_x_m", "dA1_y_m", "dA1_z_m", "dA2_x_m")
    assert make_effect("hole_offsets").param_names[-1] == "dB6_z_m" and make_effect("hole_offsets").n_params == 36
    assert make_effect("friction").n_params == 8 and make_effect("drive_offsets").n_params == 6


def test_hole_offsets_move_the_holes_they_name_on_an_eight_cable_rig(rigs):
    rig = rigs[8]
    e = make_effect("hole_offsets", rig)
    p = np.zeros(e.n_params)
    names = list(e.param_names)
    p[names.index("dA3_y_m")] = 1.5e-3          # platform hole 3 (row 2), y
    p[names.index("dA8_x_m")] = -0.7e-3         # platform hole 8 (row 7), x
    p[names.index("dB7_z_m")] = 2.0e-3          # base hole 7 (row 6), z
    A0, B0 = np.asarray(rig.platform_holes_A_m, float), np.asarray(rig.base_holes_B_m, float)
    ev = SimpleNamespace(A_m=A0.copy(), B_m=B0.copy())
    e.adjust_geometry(ev, p)
    dA, dB = np.zeros((8, 3)), np.zeros((8, 3))
    dA[2, 1], dA[7, 0], dB[6, 2] = 1.5e-3, -0.7e-3, 2.0e-3
    np.testing.assert_array_equal(ev.A_m, A0 + dA)
    np.testing.assert_array_equal(ev.B_m, B0 + dB)
    d = e.describe(p)
    np.testing.assert_allclose(d["platform_hole_offset_mm"], [0, 0, 1.5, 0, 0, 0, 0, 0.7], atol=1e-12)
    np.testing.assert_allclose(d["base_hole_offset_mm"], [0, 0, 0, 0, 0, 0, 2.0, 0], atol=1e-12)

    # the augmented model's balance with the offsets equals the nominal balance of the rig with those holes moved
    rng = np.random.default_rng(3)
    n = 5
    R = so3.exp(rng.uniform(-0.1, 0.1, (n, 3)))
    rest = np.linalg.norm(np.einsum("nij,kj->nki", R, A0) - B0, axis=2) - 2e-3
    rows = Rows(rest, rng.normal(0, 0.05, (n, 3)), np.arange(n), np.zeros((n, 8)))
    aug = AugmentedModel(rig, [e])
    theta = aug.x0()
    theta[-e.n_params:] = p
    moved = AugmentedModel(rig.replace(platform_holes_A_m=A0 + dA, base_holes_B_m=B0 + dB))
    np.testing.assert_allclose(aug.balance(R, rows, theta), moved.balance(R, rows, moved.x0()), rtol=0, atol=1e-12)


@pytest.mark.parametrize("m", [4, 8])
@pytest.mark.parametrize("name", ["friction", "drive_offsets"])
def test_per_cable_effects_evaluate_on_m_cables(rigs, m, name):
    """The balance of a per-cable effect runs on m cables and nests the nominal model at x0."""
    rig = rigs[m]
    A0, B0 = np.asarray(rig.platform_holes_A_m, float), np.asarray(rig.base_holes_B_m, float)
    rng = np.random.default_rng(m)
    n = 4
    R = so3.exp(rng.uniform(-0.1, 0.1, (n, 3)))
    rest = np.linalg.norm(np.einsum("nij,kj->nki", R, A0) - B0, axis=2) - 2e-3
    rows = Rows(rest, np.zeros((n, 3)), np.zeros(n, int), np.zeros((n, m)))
    aug, nominal = AugmentedModel(rig, [make_effect(name, rig)]), AugmentedModel(rig)
    np.testing.assert_allclose(aug.balance(R, rows, aug.x0()), nominal.balance(R, rows, nominal.x0()), atol=1e-12)


@pytest.mark.parametrize("m", [4, 8])
def test_drive_offsets_change_the_rest_lengths_of_the_cables_they_name(rigs, m):
    """Offset d_i on drive i is the nominal model with rest length l_i + d_i (one offset per cable)."""
    rig = rigs[m]
    A0, B0 = np.asarray(rig.platform_holes_A_m, float), np.asarray(rig.base_holes_B_m, float)
    rng = np.random.default_rng(10 + m)
    n = 4
    R = so3.exp(rng.uniform(-0.1, 0.1, (n, 3)))
    rest = np.linalg.norm(np.einsum("nij,kj->nki", R, A0) - B0, axis=2) - 2e-3
    d = rng.uniform(-1e-3, 1e-3, m)
    aug, nominal = AugmentedModel(rig, [make_effect("drive_offsets", rig)]), AugmentedModel(rig)
    theta = aug.x0()
    theta[-m:] = d
    rows = Rows(rest, np.zeros((n, 3)), np.zeros(n, int), np.zeros((n, m)))
    shifted = Rows(rest + d[None, :], np.zeros((n, 3)), np.zeros(n, int), np.zeros((n, m)))
    np.testing.assert_allclose(aug.balance(R, rows, theta), nominal.balance(R, shifted, nominal.x0()),
                               rtol=0, atol=1e-12)
    assert np.abs(aug.balance(R, rows, theta) - aug.balance(R, rows, aug.x0())).max() > 1e-3
