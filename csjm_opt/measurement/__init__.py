"""Measurements: the log file, tracker/force-sensor preprocessing (Section III-B), instrument noise."""

from .instruments import InstrumentNoise
from .logfile import MeasurementLog
from .preprocess import fit_rigid_transform, preprocess_file, preprocess_text
from .protocol import Protocol

__all__ = ["InstrumentNoise", "MeasurementLog", "Protocol", "fit_rigid_transform", "preprocess_file",
           "preprocess_text"]
