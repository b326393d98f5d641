"""The suggested experiment: its rows, and the protocol file and short Markdown account of them."""

from __future__ import annotations

import dataclasses

import numpy as np

from ... import so3
from .dead_weights import DeadWeight


@dataclasses.dataclass(frozen=True)
class Suggestion:
    """A suggested experiment: the rows, what they are for and the separation they should give."""

    purpose: str
    hypotheses: list[str]
    cycle: np.ndarray              # (n,) cycle ids (after the log's)
    rest_lengths_m: np.ndarray     # (n, m)
    loads: list[DeadWeight | None]       # per row (None: no load)
    intended_tau_A_Nm: np.ndarray  # (n, 3) at the planned pose
    planned_R: np.ndarray          # (n, 3, 3) nominal pose
    separation_sd: dict            # "a vs b" -> expected separation (noise sd)
    separation_before_sd: dict     # the same on the log's own rows (what the log could tell)
    equivalent: list = dataclasses.field(default_factory=list)   # pairs no feasible rows separate by 1 sd

    def as_json(self) -> dict:
        """JSON-able summary.

        Returns
        -------
        dict
        """
        return {"purpose": self.purpose, "hypotheses": self.hypotheses, "rows": int(len(self.cycle)),
                "cycles": int(len(np.unique(self.cycle))),
                "expected_separation_sd": self.separation_sd,
                "separation_on_log_sd": self.separation_before_sd,
                "equivalent": self.equivalent,
                "smallest_expected_separation_sd": min((v for k, v in self.separation_sd.items()
                                                        if k not in self.equivalent), default=None)}


PROTOCOL_COLUMNS = ("sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz,load_kg,load_x_A_m,load_y_A_m,"
                    "load_z_A_m,intended_tau_x,intended_tau_y,intended_tau_z,planned_rx,planned_ry,planned_rz")


def protocol_text(s: Suggestion) -> str:
    """The protocol as CSV: log columns (measured ones empty) and the intended loads.

    Parameters
    ----------
    s : Suggestion

    Returns
    -------
    str
    """
    lines = [PROTOCOL_COLUMNS]
    rv = so3.log(s.planned_R)
    for i in range(len(s.cycle)):
        ld = s.loads[i]
        load = ["0", "0", "0", "0"] if ld is None else [f"{ld.mass_kg:.6g}"] + [f"{v:.6g}" for v in ld.point_A_m]
        lines.append(",".join([str(i), str(int(s.cycle[i]))] + [f"{v:.9f}" for v in s.rest_lengths_m[i]]
                              + ["", "", "", "", "", ""] + load + [f"{v:.6g}" for v in s.intended_tau_A_Nm[i]]
                              + [f"{v:.6g}" for v in rv[i]]))
    return "\n".join(lines) + "\n"


def suggestion_markdown(s: Suggestion, protocol: str | None = None) -> str:
    """A short Markdown account of a suggested experiment: what the rows are for, and what they should show.

    Parameters
    ----------
    s : Suggestion
    protocol : str, optional
        Path of the protocol file, to name it.

    Returns
    -------
    str
    """
    sj = s.as_json()
    lines = ["# Suggested experiment", "", f"**Why:** {s.purpose}.", "",
             f"**Rows:** {sj['rows']} in {sj['cycles']} load cycles"
             + (f" (protocol: `{protocol}`)" if protocol else "") + "; run them after the log, fill the measured "
             "columns, then `csjm diagnose LOG --extra MEASURED.csv`.", "",
             "| hypotheses | expected separation (noise sd) | on this log |", "|---|---|---|"]
    for k, v in sj["expected_separation_sd"].items():
        note = " (equivalent: no feasible rows tell them apart)" if k in s.equivalent else ""
        lines.append(f"| {k}{note} | {v:.1f} | {sj['separation_on_log_sd'].get(k, float('nan')):.1f} |")
    lines += ["", "The separation is what the other hypothesis, refitted to the log and the new rows, cannot "
              "absorb (linearised); above about 3 sd the new rows should tell the two apart."]
    return "\n".join(lines) + "\n"
