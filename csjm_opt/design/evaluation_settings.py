"""What decides a design's metrics apart from its swept parameters, read from a sweep file."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from typing import Any

import numpy as np

from .._limits import LIMITS
from ..errors import DesignError
from ._value_checks import (
    MAX_LOADS,
    MAX_ORIENTATIONS,
    MAX_SEED,
    MAX_SHAPING_POSES,
    _check_base_value,
    _float,
    _int,
)
from .geometry import GeometryLimits
from .metrics import DesignLoads, MetricOptions
from .sampling import OrientationSampling


@dataclasses.dataclass(frozen=True)
class InterferenceLimits:
    """A sweep's interference validity rule over feasible poses (``[metrics]``; ``None``: not checked)."""

    min_cable_distance_m: float | None = None
    min_link_clearance_m: float | None = None
    max_exit_angle_deg: float | None = None

    def violation(self, metrics: dict[str, Any]) -> str | None:
        """Why a design's metrics break the rule, or ``None``.

        Parameters
        ----------
        metrics : dict
            A sweep record's ``metrics``.

        Returns
        -------
        str or None
        """
        checks = (("min_cable_distance_m", self.min_cable_distance_m, 1, "two cables come {:.4g} m apart"),
                  ("min_link_clearance_m", self.min_link_clearance_m, 1, "a cable comes {:.4g} m from the link"),
                  ("max_exit_angle_deg", self.max_exit_angle_deg, -1, "a cable leaves its hole at {:.4g} deg"))
        for key, limit, sign, text in checks:
            value = metrics.get(key)
            if limit is not None and value is not None and sign * (value - limit) < 0:
                return f"{text.format(value)} (metrics.{key} = {limit:g})"
        return None


@dataclasses.dataclass(frozen=True, eq=False)
class EvaluationSettings:
    """Everything that decides a design's metrics apart from its swept parameters."""

    base: dict[str, Any]
    sampling: OrientationSampling
    loads: DesignLoads
    options: MetricOptions
    limits: GeometryLimits
    interference: InterferenceLimits | None = None

    def digest(self) -> str:
        """Fingerprint of the settings; a result file made with other settings is refused.

        Returns
        -------
        str
            Hex digest of the base design, sampling, loads and metric options.
        """
        data: dict[str, Any] = {"base": self.base, "sampling": dataclasses.asdict(self.sampling),
                "loads": self.loads.taus_ext_A_Nm.tolist(), "options": dataclasses.asdict(self.options),
                "limits": dataclasses.asdict(self.limits)}
        if self.interference is not None:  # absent: the digest of files written before the rule existed
            data["interference"] = dataclasses.asdict(self.interference)
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


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
        loads = DesignLoads(arr)
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
    keys = ("min_cable_distance_m", "min_link_clearance_m", "max_exit_angle_deg")
    rule = InterferenceLimits(**{k: float(m[k]) for k in keys if k in m}) if any(k in m for k in keys) else None
    return EvaluationSettings(base=base, sampling=sampling, loads=loads, options=options, limits=limits,
                              interference=rule)
