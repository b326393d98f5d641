"""What a sweep run returns: every design's record and the run's statistics."""

from __future__ import annotations

import dataclasses
from typing import Any


@dataclasses.dataclass(frozen=True, eq=False)
class SweepResult:
    """Records of every design of the sweep, in sweep order, and run statistics."""

    records: list[dict[str, Any]]
    computed: int            # designs evaluated in this run
    skipped: int             # designs found in the result file
    seconds: float           # wall time of this run
    complete: bool           # False when stopped early (stop_after)
    duplicates: int = 0      # repeated lines in the result file (ignored)

    @property
    def designs_per_second(self) -> float:
        """Designs evaluated per wall-clock second in this run (0 when none were)."""
        return self.computed / self.seconds if self.computed and self.seconds > 0 else 0.0

    def as_json(self) -> dict[str, Any]:
        """The ``csjm sweep --json`` document.

        Returns
        -------
        dict
            ``{"designs": [...], "designs_per_second", "computed", "skipped", "seconds",
            "complete"}`` (keys in docs/conventions.md).
        """
        designs = []
        for r in self.records:
            designs.append({"params": r["params"], "status": r["status"],
                            "workspace_fraction": r["workspace_fraction"],
                            "min_stiffness_Nm_per_rad": r["min_stiffness_Nm_per_rad"],
                            "metrics": r["metrics"], "error": r["error"], "id": r["id"]})
        return {"designs": designs, "designs_per_second": self.designs_per_second,
                "computed": self.computed, "skipped": self.skipped, "seconds": self.seconds,
                "complete": self.complete}
