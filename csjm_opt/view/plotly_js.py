"""plotly.js, taken from the installed ``plotly`` pip package and packed for an offline page.

``plotly.min.js`` (about 4.8 MB) is gzip-compressed and base64-encoded (about 2.0 MB) once per
process; the page inflates it with the browser's ``DecompressionStream`` and evaluates it. Nothing
is fetched: the page needs no network and no file beside it.
"""

from __future__ import annotations

import base64
import functools
import gzip
import importlib.util
from pathlib import Path

from ..errors import CsjmError

__all__ = ["PlotlyMissing", "plotly_js_gzip_base64", "plotly_js_path"]


class PlotlyMissing(CsjmError):
    """The ``plotly`` pip package (which ships plotly.js) is not installed."""


def plotly_js_path() -> Path:
    """Path of ``plotly.min.js`` inside the installed ``plotly`` package (the package is not imported).

    Returns
    -------
    Path

    Raises
    ------
    PlotlyMissing
        ``plotly`` is not installed, or ships no ``package_data/plotly.min.js``.
    """
    spec = importlib.util.find_spec("plotly")
    if spec is None or not spec.submodule_search_locations:
        raise PlotlyMissing("the 3-D view needs the 'plotly' package (pip install plotly)")
    for folder in spec.submodule_search_locations:
        path = Path(folder) / "package_data" / "plotly.min.js"
        if path.is_file():
            return path
    raise PlotlyMissing("the installed 'plotly' package has no package_data/plotly.min.js")


@functools.lru_cache(maxsize=1)
def plotly_js_gzip_base64() -> str:
    """``plotly.min.js``, gzip-compressed (level 9, fixed mtime) and base64-encoded (ASCII)."""
    raw = plotly_js_path().read_bytes()
    return base64.b64encode(gzip.compress(raw, compresslevel=9, mtime=0)).decode("ascii")
