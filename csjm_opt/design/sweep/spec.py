"""The sweep description (TOML): what to vary, how to sample, which loads to hold.

Format (every section optional except ``[parameters]``; units in key names)::

    [sweep]
    method = "grid"            # "grid" (all combinations), "random" or "lhs" (Latin hypercube)
    designs = 64               # random / lhs: number of designs
    seed = 0                   # random / lhs: generator seed

    [base]                     # fixed design parameters (csjm_opt.design.PARAMETERS);
    oo_a_m = 0.08              # anything not given takes the paper's value

    [parameters.platform_d23_m]        # one table per swept (scalar) parameter
    values = [0.07, 0.095, 0.12]       # grid: explicit values; or
    # min = 0.06; max = 0.13; num = 8  # grid: linspace(min, max, num)
    # min = 0.06; max = 0.13           # random / lhs: range (log = true: log-uniform)

    [sampling]                 # orientations per design (csjm_opt.design.OrientationSampling)
    orientations = 1000
    max_tilt_deg = 45.0
    max_torsion_deg = 30.0
    seed = 0
    method = "halton"          # or "random"

    [loads]                    # external moments to hold, N m in {A}, weight excluded;
    tau_ext = [[0, 0, 0], [2, 0, 0]]   # the first row is the stiffness load

    [metrics]
    shaping_poses = 16         # poses where the shaping range is computed (0: skip)
    feasibility_tol_Nm = 1e-9
    min_hole_spacing_m = 0.001
    min_cable_clearance_m = 0.005
    # optional interference rule over feasible poses (a design breaking it is "invalid"):
    # min_cable_distance_m = 0.002; min_link_clearance_m = 0.002; max_exit_angle_deg = 75.0

Errors name the file and the dotted key (:class:`~csjm_opt.errors.DesignError`).
Sizes are bounded before anything is allocated: at most :data:`MAX_DESIGNS`
designs (grid product or ``sweep.designs``), :data:`MAX_ORIENTATIONS`
orientations and :data:`MAX_SHAPING_POSES` shaping poses per design,
:data:`MAX_LOADS` load rows; numbers are finite and within ``+-MAX_VALUE``,
moments within the bound of :mod:`csjm_opt._limits`.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import qmc

from ..._fileio import read_text
from ...errors import DesignError
from .._value_checks import (
    MAX_DESIGNS,
    MAX_LOADS,
    MAX_ORIENTATIONS,
    MAX_SEED,
    MAX_SHAPING_POSES,
    MAX_VALUE,
    _check_base_value,
    _int,
)
from ..evaluation_settings import EvaluationSettings, _settings
from ..geometry import PARAMETERS, SCALAR_PARAMETERS, design_rig
from .axes import ParameterAxis, _axis, _axis_size

__all__ = ["EvaluationSettings", "MAX_DESIGNS", "MAX_LOADS", "MAX_ORIENTATIONS", "MAX_SEED", "MAX_SHAPING_POSES",
           "MAX_VALUE", "METHODS", "ParameterAxis", "SweepSpec"]

METHODS = ("grid", "random", "lhs")
_SECTIONS = {
    "sweep": {"method", "designs", "seed"},
    "base": set(PARAMETERS),
    "parameters": set(SCALAR_PARAMETERS),
    "sampling": {"orientations", "max_tilt_deg", "max_torsion_deg", "seed", "method"},
    "loads": {"tau_ext"},
    "metrics": {"shaping_poses", "feasibility_tol_Nm", "min_hole_spacing_m", "min_cable_clearance_m",
                "min_cable_distance_m", "min_link_clearance_m", "max_exit_angle_deg"},
    "optimise": set(),  # read by csjm_opt.design.optimisation.settings; a sweep ignores it
}


@dataclasses.dataclass(frozen=True, eq=False)
class SweepSpec:
    """A parsed, validated sweep description."""

    method: str
    axes: tuple[ParameterAxis, ...]
    settings: EvaluationSettings
    designs_requested: int = 0
    seed: int = 0
    path: str | None = None

    def designs(self) -> list[dict[str, float]]:
        """The swept parameter values of every design, in sweep order.

        Returns
        -------
        list of dict of str to float
        """
        names = [a.name for a in self.axes]
        if self.method == "grid":
            return [dict(zip(names, combo)) for combo in itertools.product(*(a.values for a in self.axes))]
        d, n = len(self.axes), self.designs_requested
        if self.method == "lhs":
            u = qmc.LatinHypercube(d=d, seed=np.random.default_rng(self.seed)).random(n)
        else:
            u = np.random.default_rng(self.seed).random((n, d))
        out = []
        for row in u:
            out.append({a.name: a.value_at(x) for a, x in zip(self.axes, row)})
        return out

    @classmethod
    def from_toml(cls, path: str | Path) -> "SweepSpec":
        """Read a sweep description (format in docs/guide/design.md).

        Parameters
        ----------
        path : str or Path
            The TOML file.

        Returns
        -------
        SweepSpec
            The validated sweep: method, base design, swept parameters, sampling, loads, metrics.

        Raises
        ------
        DesignError
            If the file cannot be read, is not TOML, or a section or key is unknown or invalid (naming
            the key and file).
        """
        return cls.from_dict(read_sweep_toml(path), str(path))

    @classmethod
    def from_dict(cls, data: dict[str, Any], path: str | None = None) -> "SweepSpec":
        """Build a sweep from the nested TOML layout (see :meth:`from_toml`).

        Parameters
        ----------
        data : dict
            Sections ``sweep``, ``base``, ``parameters``, ``sampling``, ``loads``, ``metrics``.
        path : str, optional
            File the data came from, named in errors.

        Returns
        -------
        SweepSpec
            The validated sweep.

        Raises
        ------
        DesignError
            If a section or key is unknown or a value is invalid (naming the key).
        """
        def fail(message: str, key: str) -> DesignError:
            return DesignError(message, key, path)

        for section, table in data.items():
            if section not in _SECTIONS:
                raise fail(f"unknown section (expected one of {sorted(_SECTIONS)})", section)
            if not isinstance(table, dict):
                raise fail("expected a table", section)
            for key in table if section != "optimise" else ():
                if key not in _SECTIONS[section]:
                    hint = "see csjm_opt.design.PARAMETERS" if section in ("base", "parameters") \
                        else f"expected one of {sorted(_SECTIONS[section])}"
                    raise fail(f"unknown key ({hint})", f"{section}.{key}")
        sweep = data.get("sweep", {})
        method = sweep.get("method", "grid")
        if method not in METHODS:
            raise fail(f"expected one of {METHODS}, got {method!r}", "sweep.method")
        seed = _int(sweep.get("seed", 0), "sweep.seed", fail, minimum=0, maximum=MAX_SEED)
        n = 0
        if method != "grid":
            if "designs" not in sweep:
                raise fail(f"missing key (required for method = {method!r})", "sweep.designs")
            n = _int(sweep["designs"], "sweep.designs", fail, minimum=1, maximum=MAX_DESIGNS)
        elif "designs" in sweep:
            raise fail("only for method = 'random' or 'lhs' (a grid has one design per combination)",
                       "sweep.designs")
        params = data.get("parameters")
        if not params:
            raise fail("missing or empty: give at least one swept parameter", "parameters")
        if not isinstance(params, dict):
            raise fail("expected a table of parameter tables", "parameters")
        if method == "grid":
            sizes = [_axis_size(name, spec, fail) for name, spec in params.items()]
            if math.prod(sizes) > MAX_DESIGNS:
                raise fail(f"grid has {math.prod(sizes):.3g} designs, more than MAX_DESIGNS = {MAX_DESIGNS:,}",
                           "parameters")
        axes = tuple(_axis(name, spec, method, fail) for name, spec in params.items())
        base = dict(data.get("base", {}))
        for key, value in base.items():
            _check_base_value(value, f"base.{key}", fail)
        for name in params:
            if name in base:
                raise fail("parameter is both fixed in [base] and swept", f"base.{name}")
        settings = _settings(data, base, fail)
        spec = cls(method=method, axes=axes, settings=settings, designs_requested=n, seed=seed, path=path)
        _check_typical_design(spec, fail)
        return spec


def _check_typical_design(spec: "SweepSpec", fail: Any) -> None:
    """Build one design (first grid values, or range midpoints): catches misspelt or clashing keys early.

    Single designs of the sweep may still be invalid (holes too close...): those are recorded
    with ``status = "invalid"``, not fatal.
    """
    params = {a.name: a.values[0] if a.values else 0.5 * (a.low + a.high) for a in spec.axes}
    try:
        design_rig({**spec.settings.base, **params}, spec.settings.limits)
    except DesignError as exc:
        if exc.key in params:
            section = "parameters"
        elif exc.key in spec.settings.base:
            section = "base"
        else:
            return  # a property of this one design (e.g. holes too close), not of the file
        raise fail(str(exc).split("] ", 1)[-1], f"{section}.{exc.key}") from exc


def read_sweep_toml(path: str | Path) -> dict[str, Any]:
    """The tables of a sweep file, as TOML reads them (nothing checked yet).

    Parameters
    ----------
    path : str or Path
        The sweep file.

    Returns
    -------
    dict
        Its tables and keys.

    Raises
    ------
    DesignError
        If the file cannot be read or is not TOML (naming the file).
    """
    path = Path(path)
    text = read_text(path, lambda msg: DesignError(msg, path=str(path)), "sweep file")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError(f"not valid TOML: {exc}", path=str(path)) from exc
