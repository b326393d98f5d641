"""What an optimisation returns: certified designs, the requirements they hold, and the work it took."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..geometry import GeometryLimits, design_rig
from .settings import OptimiseSettings


@dataclasses.dataclass
class OptimisedDesign:
    """One certified design of an optimisation."""

    params: dict[str, float]
    objectives: dict[str, float]
    certified: dict[str, Any]
    epsilon: dict[str, float]
    rounds: int
    ok: bool

    def as_dict(self) -> dict[str, Any]:
        """JSON-able record.

        Returns
        -------
        dict
        """
        return dataclasses.asdict(self)


@dataclasses.dataclass
class OptimisationResult:
    """The designs of an optimisation, what they were certified against, and the work it took."""

    designs: list[OptimisedDesign]
    settings: OptimiseSettings
    evaluations: int
    ipopt_iterations: int
    certified_orientations: int

    def as_json(self) -> dict[str, Any]:
        """The ``result.json`` document.

        Returns
        -------
        dict
        """
        s = self.settings
        return {"objective": s.objective, "pareto_with": s.pareto_with or None, "variables": list(s.names),
                "bounds": {n: [lo, hi] for n, lo, hi in zip(s.names, s.lower, s.upper)}, "base": s.base,
                "requirements": s.requirements.as_dict(), "link": dataclasses.asdict(s.link),
                "certify_orientations": s.certify_orientations, "evaluations": self.evaluations,
                "ipopt_iterations": self.ipopt_iterations, "certified_orientations": self.certified_orientations,
                "designs": [d.as_dict() for d in self.designs]}


def design_rig_of(settings: OptimiseSettings, params: dict[str, float]) -> Any:
    """The rig of an optimised design: the base parameters, ``params`` and the settings' link.

    Parameters
    ----------
    settings : OptimiseSettings
    params : dict of str to float

    Returns
    -------
    Rig
    """
    limits = GeometryLimits(settings.requirements.min_hole_spacing_m, 0.0)
    return design_rig({**settings.base, **params}, limits).replace(link=settings.link)


def objectives_of(settings: OptimiseSettings, params: dict[str, float], check: Any,
                values: dict[str, float]) -> dict[str, float]:
    """Certified objective values: the range scale held, and the worst values over the dense check.

    Parameters
    ----------
    settings : OptimiseSettings
    params : dict of str to float
        The design's optimised parameters.
    check : Check
        Its dense certification.
    values : dict of str to float
        The values the solve held (``range`` in particular).

    Returns
    -------
    dict of str to float
        ``range``, ``stiffness`` (N m/rad), ``tension_margin`` (N) and ``size`` (m); ``shaping``
        (N m/rad, the certified smallest LP shaping range) where the check holds it.
    """
    rig = design_rig_of(settings, params)
    size = float(max(np.hypot(*rig.platform_holes_A_m[:, :2].T).max(), np.hypot(*rig.base_holes_B_m[:, :2].T).max()))
    return {"range": values["range"],
            "stiffness": values["stiffness"] + check.worst["stiffness"][0],
            "tension_margin": values["tension_margin"] + check.worst["tension"][0],
            "size": size,
            **({"shaping": values["shaping"] + check.worst["shaping"][0]} if "shaping" in check.worst else {})}


__all__ = ["OptimisationResult", "OptimisedDesign", "design_rig_of", "objectives_of"]
