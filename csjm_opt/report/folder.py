"""Report folders: created on demand, and never a user's non-empty folder that is not a previous report."""

from __future__ import annotations

from pathlib import Path

from ..errors import InvalidInput

#: File that marks a folder as a csjm report folder (safe to write into again).
MARKER = ".csjm_report"


def prepare_out_dir(out_dir: Path, what: str = "csjm demo") -> Path:
    """Create a report folder; refuse a non-empty folder that is not a previous report.

    Parameters
    ----------
    out_dir : Path
        The folder (created with its parents).
    what : str
        Written into the marker file that identifies a report folder.

    Returns
    -------
    Path
        ``out_dir``.

    Raises
    ------
    InvalidInput
        ``out_dir`` is a file, or a non-empty folder without the marker.
    """
    out_dir = Path(out_dir)
    if out_dir.exists():
        if not out_dir.is_dir():
            raise InvalidInput(f"{out_dir} exists and is not a folder", "--out")
        if any(out_dir.iterdir()) and not (out_dir / MARKER).exists():
            raise InvalidInput(f"{out_dir} is a non-empty folder that is not a csjm report; "
                               "refusing to write into it (choose another --out)", "--out")
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / MARKER).write_text(f"{what} report folder\n")
    return out_dir
