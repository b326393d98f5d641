"""Starting designs of an optimisation: space-filling in the variable box, or a sweep's best."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.stats import qmc

from ...errors import DesignError
from .settings import OptimiseSettings


def sweep_starts(settings: OptimiseSettings, records: list[dict[str, Any]], count: int | None = None,
                 key: str = "workspace_fraction") -> list[dict[str, float]]:
    """The best designs of a sweep as starts: valid records sorted by ``key`` (largest first).

    Parameters
    ----------
    settings : OptimiseSettings
    records : list of dict
        Sweep records (``SweepResult.records`` or the lines of a result file).
    count : int, optional
        How many (default ``settings.starts``).
    key : str
        Record key to rank by.

    Returns
    -------
    list of dict of str to float
        The optimised parameters of each start.

    Raises
    ------
    DesignError
        If no valid record has every optimised parameter.
    """
    ok = [r for r in records if r.get("status") == "ok" and r.get(key) is not None
          and all(n in r["params"] for n in settings.names)]
    if not ok:
        raise DesignError(f"no valid sweep record with {key} and the parameters {list(settings.names)}", "starts")
    ok.sort(key=lambda r: -float(r[key]))
    return [{n: float(r["params"][n]) for n in settings.names} for r in ok[:count or settings.starts]]


def space_filling_starts(settings: OptimiseSettings) -> list[dict[str, float]]:
    """``settings.starts`` scrambled-Halton designs in the variable box (seeded by ``settings.seed``).

    Parameters
    ----------
    settings : OptimiseSettings

    Returns
    -------
    list of dict of str to float
    """
    d = len(settings.names)
    u = qmc.Halton(d=d, scramble=True, seed=np.random.default_rng(settings.seed)).random(settings.starts)
    lo, hi = np.array(settings.lower), np.array(settings.upper)
    return [dict(zip(settings.names, (lo + row * (hi - lo)).tolist())) for row in u]


__all__ = ["space_filling_starts", "sweep_starts"]
