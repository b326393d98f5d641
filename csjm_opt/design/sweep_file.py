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

Errors name the file and the dotted key (:class:`~csjm_opt.errors.DesignError`).
Sizes are bounded before anything is allocated: at most :data:`MAX_DESIGNS`
designs (grid product or ``sweep.designs``), :data:`MAX_ORIENTATIONS`
orientations and :data:`MAX_SHAPING_POSES` shaping poses per design,
:data:`MAX_LOADS` load rows; numbers are finite and within ``+-MAX_VALUE``,
moments within the bound of :mod:`csjm_opt._limits`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import qmc

from ..errors import DesignError
from .._fileio import read_text
from .._limits import LIMITS
from .geometry import PARAMETERS, SCALAR_PARAMETERS, GeometryLimits, design_rig
from .metrics import LoadSet, MetricOptions
from .sampling import OrientationSampling

METHODS = ("grid", "random", "lhs")
#: Most designs in one sweep (a 1e6-design sweep takes days on a workstation).
MAX_DESIGNS = 1_000_000
#: Most orientations sampled per design (the metrics hold a few arrays of this length per load).
MAX_ORIENTATIONS = 100_000
#: Most shaping poses per design (each solves a QP family).
MAX_SHAPING_POSES = 10_000
#: Most rows of ``loads.tau_ext``.
MAX_LOADS = 100
#: Largest magnitude of any number in a sweep file (parameters are m, deg, N, N/m, kg).
MAX_VALUE = 1e9
#: Largest seed (numpy's generators take any integer; this keeps it a 63-bit integer).
MAX_SEED = 2 ** 63 - 1
_SECTIONS = {
    "sweep": {"method", "designs", "seed"},
    "base": set(PARAMETERS),
    "parameters": set(SCALAR_PARAMETERS),
    "sampling": {"orientations", "max_tilt_deg", "max_torsion_deg", "seed", "method"},
    "loads": {"tau_ext"},
    "metrics": {"shaping_poses", "feasibility_tol_Nm", "min_hole_spacing_m", "min_cable_clearance_m"},
}


@dataclasses.dataclass(frozen=True)
class ParameterAxis:
    """One swept parameter: explicit ``values`` (grid) or a ``[low, high]`` range."""

    name: str
    values: tuple[float, ...] = ()
    low: float = math.nan
    high: float = math.nan
    log: bool = False


@dataclasses.dataclass(frozen=True, eq=False)
class EvaluationSettings:
    """Everything that decides a design's metrics apart from its swept parameters."""

    base: dict[str, Any]
    sampling: OrientationSampling
    loads: LoadSet
    options: MetricOptions
    limits: GeometryLimits

    def digest(self) -> str:
        """Fingerprint of the settings; a result file made with other settings is refused.

        Returns
        -------
        str
            Hex digest of the base design, sampling, loads and metric options.
        """
        data = {"base": self.base, "sampling": dataclasses.asdict(self.sampling),
                "loads": self.loads.taus_ext_A_Nm.tolist(), "options": dataclasses.asdict(self.options),
                "limits": dataclasses.asdict(self.limits)}
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


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
            design = {}
            for a, x in zip(self.axes, row):
                if a.log:
                    design[a.name] = float(math.exp(math.log(a.low) + x * (math.log(a.high) - math.log(a.low))))
                else:
                    design[a.name] = float(a.low + x * (a.high - a.low))
            out.append(design)
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
        path = Path(path)
        text = read_text(path, lambda msg: DesignError(msg, path=str(path)), "sweep file")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise DesignError(f"not valid TOML: {exc}", path=str(path)) from exc
        return cls.from_dict(data, str(path))

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
            for key in table:
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


def _settings(data: dict[str, Any], base: dict[str, Any], fail: Any) -> EvaluationSettings:
    s = data.get("sampling", {})
    m = data.get("metrics", {})
    for key, value in list(s.items()) + list(m.items()):
        section = "sampling" if key in s else "metrics"
        if key == "method":
            if not isinstance(value, str):
                raise fail(f"expected a string, got {value!r}", "sampling.method")
        elif key in ("orientations", "seed", "shaping_poses"):
            top = {"orientations": MAX_ORIENTATIONS, "seed": MAX_SEED, "shaping_poses": MAX_SHAPING_POSES}[key]
            _int(value, f"{section}.{key}", fail, minimum=1 if key == "orientations" else 0, maximum=top)
        else:
            _float(value, f"{section}.{key}", fail)
    try:
        sampling = OrientationSampling(n=s.get("orientations", 1000), max_tilt_deg=float(s.get("max_tilt_deg", 30.0)),
                                       max_torsion_deg=float(s.get("max_torsion_deg", 30.0)),
                                       seed=s.get("seed", 0), method=s.get("method", "halton"))
    except DesignError as exc:
        raise fail(str(exc).split("] ", 1)[-1], f"sampling.{exc.key}") from exc
    tau_ext = data.get("loads", {}).get("tau_ext", [[0.0, 0.0, 0.0]])
    if isinstance(tau_ext, list) and len(tau_ext) > MAX_LOADS:
        raise fail(f"{len(tau_ext)} load rows, more than MAX_LOADS = {MAX_LOADS}", "loads.tau_ext")
    _check_base_value(tau_ext, "loads.tau_ext", fail)
    moment = LIMITS["moment_Nm"]
    try:
        arr = np.asarray(tau_ext, dtype=float)
    except (ValueError, TypeError) as exc:
        raise fail(f"expected rows of three numbers: {exc}", "loads.tau_ext") from exc
    if arr.size and not moment.contains(arr).all():
        raise fail(f"moments must lie in {moment.describe()}", "loads.tau_ext")
    try:
        loads = LoadSet(arr)
    except (ValueError, TypeError) as exc:
        raise fail(f"expected rows of three numbers: {exc}", "loads.tau_ext") from exc
    except DesignError as exc:
        raise fail(str(exc).split("] ", 1)[-1], "loads.tau_ext") from exc
    try:
        options = MetricOptions(shaping_poses=m.get("shaping_poses", 16),
                                feasibility_tol_Nm=float(m.get("feasibility_tol_Nm", 1e-9)))
        limits = GeometryLimits(float(m.get("min_hole_spacing_m", 1e-3)),
                                float(m.get("min_cable_clearance_m", 5e-3)))
    except DesignError as exc:
        raise fail(str(exc).split("] ", 1)[-1], f"metrics.{exc.key}") from exc
    return EvaluationSettings(base=base, sampling=sampling, loads=loads, options=options, limits=limits)


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


def _axis(name: str, spec: Any, method: str, fail: Any) -> ParameterAxis:
    key = f"parameters.{name}"
    if not isinstance(spec, dict):
        raise fail("expected a table: {values = [...]} or {min = .., max = ..}", key)
    allowed = {"values", "min", "max", "num", "log"}
    for k in spec:
        if k not in allowed:
            raise fail(f"unknown key (expected one of {sorted(allowed)})", f"{key}.{k}")
    if "values" in spec:
        if method != "grid":
            raise fail("explicit values need method = 'grid'; give min and max", f"{key}.values")
        if {"min", "max", "num"} & set(spec):
            raise fail("give values or min/max/num, not both", f"{key}.values")
        values = spec["values"]
        if not isinstance(values, list) or not values:
            raise fail("expected a non-empty list of numbers", f"{key}.values")
        return ParameterAxis(name, tuple(_float(v, f"{key}.values", fail) for v in values))
    for k in ("min", "max"):
        if k not in spec:
            raise fail("missing key (or give values)", f"{key}.{k}")
    low, high = _float(spec["min"], f"{key}.min", fail), _float(spec["max"], f"{key}.max", fail)
    if not low < high:
        raise fail(f"min must be < max, got {low} and {high}", f"{key}.min")
    log = spec.get("log", False)
    if not isinstance(log, bool):
        raise fail(f"expected true or false, got {log!r}", f"{key}.log")
    if log and low <= 0:
        raise fail("log = true needs min > 0", f"{key}.min")
    if method == "grid":
        if "num" not in spec:
            raise fail("missing key (grid over min..max needs num)", f"{key}.num")
        num = _int(spec["num"], f"{key}.num", fail, minimum=1, maximum=MAX_DESIGNS)
        grid = np.geomspace(low, high, num) if log else np.linspace(low, high, num)
        return ParameterAxis(name, tuple(float(v) for v in grid))
    if "num" in spec:
        raise fail("num is for method = 'grid'; use sweep.designs", f"{key}.num")
    return ParameterAxis(name, (), low, high, log)


def _axis_size(name: str, spec: Any, fail: Any) -> int:
    """Number of grid values of one axis, read before any array is built."""
    key = f"parameters.{name}"
    if not isinstance(spec, dict):
        raise fail("expected a table: {values = [...]} or {min = .., max = ..}", key)
    if isinstance(spec.get("values"), list):
        return max(1, len(spec["values"]))
    if "num" in spec:
        return _int(spec["num"], f"{key}.num", fail, minimum=1, maximum=MAX_DESIGNS)
    return 1


def _check_base_value(value: Any, key: str, fail: Any) -> None:
    """A number, or nested lists of numbers (hole rows), finite and within ``+-MAX_VALUE``."""
    if isinstance(value, list):
        if len(value) > 1000:
            raise fail(f"expected a short list, got {len(value)} entries", key)
        for v in value:
            _check_base_value(v, key, fail)
    elif not isinstance(value, str):
        _float(value, key, fail)


def _float(value: Any, key: str, fail: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"expected a finite number, got {value!r:.40}", key)
    if isinstance(value, int) and abs(value) > MAX_VALUE:
        raise fail(f"expected a number within +-{MAX_VALUE:g}, got an integer of {len(str(abs(value)))} digits", key)
    if not math.isfinite(value):
        raise fail(f"expected a finite number, got {value!r:.40}", key)
    if abs(value) > MAX_VALUE:
        raise fail(f"expected a number within +-{MAX_VALUE:g}, got {value:.6g}", key)
    return float(value)


def _int(value: Any, key: str, fail: Any, minimum: int, maximum: int = MAX_DESIGNS) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise fail(f"expected an integer >= {minimum}, got {value!r:.40}", key)
    if value > maximum:
        shown = f"{value:.3g}" if value < 10 ** 30 else f"an integer of {len(str(value))} digits"
        raise fail(f"expected an integer <= {maximum:,}, got {shown}", key)
    return value
