"""What an optimisation asks for: the optional ``[optimise]`` section of a sweep file, with its defaults.

A sweep file (:mod:`csjm_opt.design.sweep.spec`) works as it stands; the
section only changes the defaults::

    [optimise]
    objective = "range"            # "stiffness", "tension_margin", "range", "size" or "shaping"
    pareto_with = "stiffness"      # second objective of an epsilon-constraint front ("" = none)
    pareto_points = 4              # designs on the front
    variables = ["platform_gamma_deg", "base_gamma_deg"]   # default: the swept parameters,
                                   # between their min and max (or smallest and largest value);
                                   # the cable count n_cables is fixed (in [base]), never a variable
    max_tilt_deg = 45.0            # the required orientation set (default: [sampling]);
    max_torsion_deg = 30.0         #   "range" scales both by s <= 1
    range_scale = 1.0              # required scale s when the objective is not "range"
    min_stiffness_Nm_per_rad = 1.0 # smallest eigenvalue of K at every required orientation
    tension_margin_N = 0.0         # tensions within [t_min + margin, t_max - margin]
    min_cable_distance_m = 0.002   # between any two cables (twice a 1 mm cable radius)
    min_link_clearance_m = 0.002   # between a cable and the link (rod and ball)
    max_exit_angle_deg = 75.0      # cable against its hole's axis
    orientations = 48              # orientations the optimiser starts with (Halton, seed)
    certify_orientations = 10000   # dense certification set (another Halton sequence)
    starts = 4                     # multi-start: space-filling designs in the variable box
    max_rounds = 6                 # certification rounds (solve, check, add failures)
    seed = 0

The loads are the sweep's ``[loads]`` (row 0 the stiffness load), the hole
spacing its ``[metrics] min_hole_spacing_m``, the link the rig's (the
default of :mod:`csjm_opt.model.link`).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import DesignError
from ...model.link import DEFAULT_LINK, Link
from ...model.rig import STANDARD_GRAVITY_B
from ..geometry import SCALAR_PARAMETERS
from ..sweep.axes import INTEGER_PARAMETERS
from ..sweep.spec import SweepSpec, read_sweep_toml

#: Objectives (each maximised, except "size", minimised). "shaping" is the smallest shaping range
#: (N m/rad) over the required orientations and the axes x, y, z (:mod:`.shaping`).
OBJECTIVES = ("stiffness", "tension_margin", "range", "size", "shaping")
_DEFAULTS: dict[str, Any] = {
    "objective": "range", "pareto_with": "stiffness", "pareto_points": 4, "range_scale": 1.0,
    "min_stiffness_Nm_per_rad": 1.0, "tension_margin_N": 0.0, "min_cable_distance_m": 0.002,
    "min_link_clearance_m": 0.002, "max_exit_angle_deg": 75.0, "orientations": 48,
    "certify_orientations": 10000, "starts": 4, "max_rounds": 6, "seed": 0,
}
KEYS = frozenset(_DEFAULTS) | {"variables", "max_tilt_deg", "max_torsion_deg"}
#: Largest orientation sets (optimiser, certification) and counts.
MAX_OPT_ORIENTATIONS = 2000
MAX_CERTIFY_ORIENTATIONS = 1_000_000
MAX_STARTS = 256


@dataclasses.dataclass(frozen=True, eq=False)
class Requirements:
    """What every returned design must hold (certified on the dense set)."""

    max_tilt_deg: float
    max_torsion_deg: float
    loads: np.ndarray                    # (m, 3) N m in {A}, weight excluded; row 0 the stiffness load
    range_scale: float = 1.0
    min_stiffness_Nm_per_rad: float = 1.0
    tension_margin_N: float = 0.0
    min_cable_distance_m: float = 0.002
    min_link_clearance_m: float = 0.002
    max_exit_angle_deg: float = 75.0
    min_hole_spacing_m: float = 0.001

    def as_dict(self) -> dict[str, Any]:
        """JSON-able requirements.

        Returns
        -------
        dict
        """
        d = dataclasses.asdict(self)
        d["loads"] = np.asarray(self.loads).tolist()
        return d


@dataclasses.dataclass(frozen=True, eq=False)
class OptimiseSettings:
    """Variables, fixed parameters, requirements, objective and effort of an optimisation."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    base: dict[str, Any]
    requirements: Requirements
    objective: str = "range"
    pareto_with: str = "stiffness"
    pareto_points: int = 4
    orientations: int = 48
    certify_orientations: int = 10000
    starts: int = 4
    max_rounds: int = 6
    seed: int = 0
    link: Link = DEFAULT_LINK
    gravity_B_m_per_s2: tuple[float, float, float] = STANDARD_GRAVITY_B
    path: str | None = None

    def replace(self, **changes: Any) -> "OptimiseSettings":
        """A copy with some fields changed.

        Parameters
        ----------
        **changes
            Field values.

        Returns
        -------
        OptimiseSettings
        """
        return dataclasses.replace(self, **changes)


def read_optimise_file(path: str | Path) -> tuple[SweepSpec, OptimiseSettings]:
    """Read a sweep file and its optional ``[optimise]`` section.

    Parameters
    ----------
    path : str or Path
        The sweep file.

    Returns
    -------
    spec : SweepSpec
        The sweep (its ``[optimise]`` section ignored).
    settings : OptimiseSettings
        The optimisation (defaults from the sweep where the section is silent).

    Raises
    ------
    DesignError
        If the file cannot be read or a key is unknown or invalid (naming the dotted key and the file).
    """
    data = read_sweep_toml(path)
    section = data.pop("optimise", {})
    spec = SweepSpec.from_dict(data, str(path))
    return spec, settings_from(spec, section, str(path))


def settings_from(spec: SweepSpec, section: Any, path: str | None = None) -> OptimiseSettings:
    """The optimisation settings of a sweep and an ``[optimise]`` table.

    Parameters
    ----------
    spec : SweepSpec
        The sweep (variables, bounds, base design, sampling, loads, hole spacing).
    section : dict
        The ``[optimise]`` table (may be empty).
    path : str, optional
        File named in errors.

    Returns
    -------
    OptimiseSettings

    Raises
    ------
    DesignError
        If a key is unknown or a value is invalid (naming ``optimise.<key>``).
    """
    def fail(message: str, key: str) -> DesignError:
        return DesignError(message, f"optimise.{key}", path)

    if not isinstance(section, dict):
        raise DesignError("expected a table", "optimise", path)
    for key in section:
        if key not in KEYS:
            raise fail(f"unknown key (expected one of {sorted(KEYS)})", key)
    o: dict[str, Any] = {**_DEFAULTS, **section}
    for key in ("objective", "pareto_with"):
        if not isinstance(o[key], str) or (o[key] not in OBJECTIVES and not (key == "pareto_with" and o[key] == "")):
            extra = " or an empty string" if key == "pareto_with" else ""
            raise fail(f"expected one of {list(OBJECTIVES)}{extra}, got {o[key]!r}", key)
    if o["pareto_with"] == o["objective"]:
        raise fail("the second objective of the front must differ from the objective", "pareto_with")
    ints = {"pareto_points": (1, 64), "orientations": (1, MAX_OPT_ORIENTATIONS),
            "certify_orientations": (1, MAX_CERTIFY_ORIENTATIONS), "starts": (1, MAX_STARTS),
            "max_rounds": (1, 100), "seed": (0, 2 ** 32 - 1)}
    for key, (low, high) in ints.items():
        v = o[key]
        if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
            raise fail(f"expected an integer in [{low}, {high}], got {v!r}", key)
    floats = {"range_scale": (1e-3, 1.0), "min_stiffness_Nm_per_rad": (-1e6, 1e6), "tension_margin_N": (0.0, 1e6),
              "min_cable_distance_m": (0.0, 10.0), "min_link_clearance_m": (-10.0, 10.0),
              "max_exit_angle_deg": (0.0, 180.0), "max_tilt_deg": (1e-6, 180.0), "max_torsion_deg": (0.0, 180.0)}
    s = spec.settings
    o.setdefault("max_tilt_deg", s.sampling.max_tilt_deg)
    o.setdefault("max_torsion_deg", s.sampling.max_torsion_deg)
    for key, (f_low, f_high) in floats.items():
        v = o[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or not f_low <= v <= f_high:
            raise fail(f"expected a number in [{f_low:g}, {f_high:g}], got {v!r}", key)
        o[key] = float(v)
    axes = {a.name: a for a in spec.axes}
    names = o.get("variables", list(axes))
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise fail("expected a non-empty list of swept parameter names", "variables")
    for n in names:
        if n in INTEGER_PARAMETERS:
            raise fail(f"{n!r} takes integer values and cannot be optimised: fix it in [base] (one optimisation "
                       "per cable count) and name the continuous parameters in optimise.variables", "variables")
        if n not in axes:
            hint = "not a design parameter" if n not in SCALAR_PARAMETERS else "not swept in [parameters]"
            raise fail(f"{n!r} is {hint} (the optimiser uses the sweep's parameters and bounds)", "variables")
        if n.endswith(("_d12_m", "_d23_m")):
            raise fail(f"{n!r}: chords cannot be optimised, sweep the radius and gamma instead", "variables")
    lower = tuple(float(axes[n].low if not axes[n].values else min(axes[n].values)) for n in names)
    upper = tuple(float(axes[n].high if not axes[n].values else max(axes[n].values)) for n in names)
    for n, lo_, hi_ in zip(names, lower, upper):
        if not hi_ > lo_:
            raise DesignError(f"needs a range (min < max) to be optimised, got [{lo_}, {hi_}]",
                              f"parameters.{n}", path)
    req = Requirements(max_tilt_deg=o["max_tilt_deg"], max_torsion_deg=o["max_torsion_deg"],
                       loads=np.asarray(s.loads.taus_ext_A_Nm, float), range_scale=o["range_scale"],
                       min_stiffness_Nm_per_rad=o["min_stiffness_Nm_per_rad"],
                       tension_margin_N=o["tension_margin_N"], min_cable_distance_m=o["min_cable_distance_m"],
                       min_link_clearance_m=o["min_link_clearance_m"],
                       max_exit_angle_deg=o["max_exit_angle_deg"],
                       min_hole_spacing_m=s.limits.min_hole_spacing_m)
    return OptimiseSettings(names=tuple(names), lower=lower, upper=upper, base=dict(s.base), requirements=req,
                            objective=o["objective"], pareto_with=o["pareto_with"],
                            pareto_points=o["pareto_points"], orientations=o["orientations"],
                            certify_orientations=o["certify_orientations"], starts=o["starts"],
                            max_rounds=o["max_rounds"], seed=o["seed"], path=path)
