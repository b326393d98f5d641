"""Rig: paper geometry, TOML round trip, and one clear error per bad input."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt._validate import as_rotation
from csjm_opt.model.rig import Rig
from tests.conftest import R0_CORRECTED, TAU0_TABLE3

ROOT = Path(__file__).resolve().parents[2]


def _chord(P, i, j):
    return np.linalg.norm(P[i - 1] - P[j - 1])


def test_paper_geometry_matches_section_IV_A(rig):
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    for i, j in ((1, 2), (3, 4), (5, 6)):
        assert _chord(A, i, j) == pytest.approx(0.010, abs=1e-12)
        assert _chord(B, i, j) == pytest.approx(0.128, abs=1e-12)
    for i, j in ((2, 3), (4, 5), (6, 1)):
        assert _chord(A, i, j) == pytest.approx(0.095, abs=1e-12)
        assert _chord(B, i, j) == pytest.approx(0.005, abs=1e-12)
    # O_A and O_B 0.08 m from O along z; hole circles centred on the axis
    assert np.allclose(A[:, 2], 0.08) and np.allclose(B[:, 2], -0.08)
    assert np.allclose(A.mean(axis=0)[:2], 0.0, atol=1e-12)
    assert np.allclose(B.mean(axis=0)[:2], 0.0, atol=1e-12)
    assert rig.platform_mass_kg * 9.81 == pytest.approx(4.82, abs=5e-3)
    assert np.allclose(rig.com_A_m, [0, 0, 0.081])


def test_shipped_rig_file_is_the_builtin_rig(rig):
    shipped = Rig.from_toml(ROOT / "rigs" / "paper.toml")
    assert shipped.as_dict() == rig.as_dict()


def test_toml_round_trip_and_no_clobber(tmp_path, rig):
    path = tmp_path / "r.toml"
    rig.to_toml(path)
    assert Rig.from_toml(path).as_dict() == rig.as_dict()
    before = path.read_text()
    with pytest.raises(co.InvalidInput, match="refusing to overwrite"):
        rig.to_toml(path)
    assert path.read_text() == before


def test_rig_is_immutable(rig):
    with pytest.raises(dataclasses.FrozenInstanceError):
        rig.t_min_N = 1.0
    with pytest.raises(ValueError):
        rig.platform_holes_A_m[0, 0] = 1.0


def test_paper_rig_stiffness_near_table3(rig, model):
    """The default cable stiffness puts the model's K at R0 in the range of Table 3's K_D."""
    KD_table3 = np.array([[29.39, 0.75, 1.67], [-2.53, 29.96, -1.07], [-4.49, -1.42, 6.99]])
    R0 = as_rotation(R0_CORRECTED)
    tau_ext = TAU0_TABLE3 - model.weight_moment(R0)
    plan = co.plan_tensions(rig, R0, tau_ext, model=model)
    eig = np.linalg.eigvalsh(co.stiffness(rig, R0, plan.tensions_N, model=model))
    eig_KD = np.linalg.eigvalsh(0.5 * (KD_table3 + KD_table3.T))
    assert eig.min() > 0                                   # stable
    assert eig_KD.min() <= eig.min() and eig.max() <= 1.1 * eig_KD.max()
    bending = np.sort(eig)[1:]
    assert np.all(np.abs(bending - 29.5) < 4.0)            # Table 3: 29.4, 30.0


def _data(rig):
    return rig.as_dict()


@pytest.mark.parametrize("mutate, key, message", [
    (lambda d: d.__setitem__("extra", {}), "extra", "unknown section"),
    (lambda d: d["cables"].__setitem__("colour", 1), "cables.colour", "unknown key"),
    (lambda d: d.pop("platform"), "platform", "missing section"),
    (lambda d: d["cables"].pop("t_max"), "cables.t_max", "missing key"),
    (lambda d: d["geometry"].__setitem__("platform_holes", [[0, 0, 1]] * 3), "geometry.platform_holes",
     "fewer than 4"),
    (lambda d: d["geometry"].__setitem__("platform_holes", [[0, 0, 1]] * 5), "geometry.base_holes",
     "one per cable"),
    (lambda d: d["geometry"].__setitem__("base_holes", [[0, 0, 1]] * 5 + [[1, 2]]), "geometry.base_holes", "ragged"),
    (lambda d: d["cables"].__setitem__("stiffness", [1.0] * 5 + [float("nan")]), "cables.stiffness", "finite"),
    (lambda d: d["cables"].__setitem__("stiffness", [1.0] * 5 + [0.0]), "cables.stiffness", "positive"),
    (lambda d: d["cables"].__setitem__("t_min", 200.0), "cables.t_max", "t_min must be < t_max"),
    (lambda d: d["cables"].__setitem__("t_min", "5"), "cables.t_min", "expected numbers"),
    (lambda d: d["cables"].__setitem__("t_min", -1.0), "cables.t_min", ">= 0"),
    (lambda d: d["platform"].__setitem__("mass", -0.1), "platform.mass", ">= 0"),
    (lambda d: d["platform"].__setitem__("com", [0.0, float("inf"), 0.0]), "platform.com", "finite"),
])
def test_each_bad_rig_input_names_its_key(rig, mutate, key, message):
    data = _data(rig)
    mutate(data)
    with pytest.raises(co.RigFileError, match=message) as info:
        Rig.from_dict(data, path="bad.toml")
    assert info.value.key == key
    assert f"[{key}]" in str(info.value) and "bad.toml" in str(info.value)


def test_bad_toml_and_missing_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[cables\nstiffness = 1\n")
    with pytest.raises(co.RigFileError, match="not valid TOML.*line 1"):
        Rig.from_toml(bad)
    with pytest.raises(co.RigFileError, match="cannot read"):
        Rig.from_toml(tmp_path / "absent.toml")
