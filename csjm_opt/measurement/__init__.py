"""Measurements: the log file, tracker/force-sensor preprocessing (Section III-B), instrument noise."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .instruments import InstrumentNoise
    from .logfile import MeasurementLog
    from .preprocess import fit_rigid_transform, preprocess_file, preprocess_text
    from .protocol import Protocol

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'InstrumentNoise': ('.instruments', 'InstrumentNoise'),
    'MeasurementLog': ('.logfile', 'MeasurementLog'),
    'fit_rigid_transform': ('.preprocess', 'fit_rigid_transform'),
    'preprocess_file': ('.preprocess', 'preprocess_file'),
    'preprocess_text': ('.preprocess', 'preprocess_text'),
    'Protocol': ('.protocol', 'Protocol'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["InstrumentNoise", "MeasurementLog", "Protocol", "fit_rigid_transform", "preprocess_file",
           "preprocess_text"]
