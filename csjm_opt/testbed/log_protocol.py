"""Protocols: planned experiments in the log format, run on a testbed plant.

A protocol file is a measurement log (docs/conventions.md) whose *measured*
columns ``tau_x, tau_y, tau_z, rx, ry, rz`` may be empty, with optional
extra columns saying what to do (the columns ``csjm diagnose --suggest``
writes):

==========================================  ====================================================
``load_kg, load_x_A_m, load_y_A_m,          a dead weight of ``load_kg`` hung at that point of
load_z_A_m``                                the tool (its moment ``(m p) x (R^T g)`` follows the
                                            pose)
``intended_tau_x, _y, _z``                  the intended external moment (N m, {A}); with a dead
                                            weight, its value at the planned pose (informative);
                                            without one, a moment fixed in {A} that is applied
``planned_rx, _ry, _rz``                    the planned pose (start of the first row's settling;
                                            checked against the rig)
==========================================  ====================================================

Without ``intended_tau_*`` the ``tau_*`` columns (then filled) are the moments
applied; without ``planned_r*`` the ``r*`` columns (if filled) are the planned
poses. :func:`read_protocol` reads such a file strictly; :func:`check_protocol`
refuses rows the rig cannot hold (a cable slack or above ``t_max`` at the
nominal equilibrium) and planned poses that are not the rig's equilibrium (a
protocol written for another rig); :func:`simulate_protocol` runs it on a plant
and returns the measured log, which keeps the protocol's extra columns.

Two protocol formats exist, and :func:`read_protocol` reads both:

* :class:`LogProtocol` (this module; ``csjm diagnose --suggest`` writes it): dead weights
  ``load_kg`` at points of the tool, whose moment follows the pose, and the planned pose;
* :class:`csjm_opt.measurement.protocol.Protocol` (``csjm plan-experiment`` writes it, for
  identification): a force ``load_N`` of fixed direction ``dir_*`` in {B} at a platform point.
"""

from __future__ import annotations

import csv
import dataclasses
import io
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from .. import so3
from .._fileio import read_text
from ..errors import DataFileError, InvalidInput, NoEquilibrium
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import COLUMNS, MeasurementLog, columns_for, header_cables, parse_number
from ..measurement.protocol import Protocol as LoadProtocol
from ..model import kinematics as kin
from ..model.rig import Rig
from .plant import TestbedPlant
from .protocol_runner import run_protocol

LOAD_COLUMNS = ("load_kg", "load_x_A_m", "load_y_A_m", "load_z_A_m")
INTENDED_COLUMNS = ("intended_tau_x", "intended_tau_y", "intended_tau_z")
PLANNED_COLUMNS = ("planned_rx", "planned_ry", "planned_rz")
#: A planned pose further than this (rad) from the rig's nominal equilibrium: written for another rig.
PLANNED_POSE_TOL_RAD = 0.02


@dataclasses.dataclass(frozen=True, eq=False)
class LogProtocol:
    """A planned experiment (rows in time order).

    Attributes
    ----------
    sample, cycle : (n,) int arrays
    rest_lengths_m : (n, m) array
    tau_fixed_A_Nm : (n, 3) array
        Moments fixed in {A} that are applied (zero on dead-weight rows).
    load_first_moment_A_kgm : (n, 3) array
        Dead weights' ``mass * point`` in {A} (zero without one).
    planned_R : (n, 3, 3) array or None
    lines : (n,) int array
        File lines of the rows (for messages).
    extra : dict
        The extra columns (kept in the simulated log).
    source : str or None
    """

    sample: np.ndarray
    cycle: np.ndarray
    rest_lengths_m: np.ndarray
    tau_fixed_A_Nm: np.ndarray
    load_first_moment_A_kgm: np.ndarray
    planned_R: np.ndarray | None
    lines: np.ndarray
    extra: dict
    source: str | None = None

    def __len__(self) -> int:
        return len(self.cycle)



def read_protocol(path_or_text: str | Path, source: str | None = None) -> LogProtocol | LoadProtocol:
    """Read a protocol: a diagnosis protocol (:class:`LogProtocol`) or an identification one.

    A file with the columns ``load_N, dir_*, point_*`` (``csjm plan-experiment``: forces fixed in
    {B} at platform points) is read as :class:`csjm_opt.measurement.protocol.Protocol`; any
    other as :class:`LogProtocol` (see :func:`read_log_protocol`). Both run in :func:`simulate_protocol`.

    Parameters
    ----------
    path_or_text : str or Path
        A file path, or CSV text when it contains a newline.
    source : str, optional
        Name used in messages for text input.

    Returns
    -------
    LogProtocol or csjm_opt.measurement.protocol.Protocol
        The protocol read.

    Raises
    ------
    DataFileError
        A malformed protocol (file, line and column named).
    """
    if isinstance(path_or_text, Path) or "\n" not in str(path_or_text):   # a file: read it once
        source = str(path_or_text)
        text = read_text(path_or_text, lambda msg: DataFileError(msg, source), "protocol file",
                         encoding="utf-8-sig")
    else:
        text = str(path_or_text)
    text = text.lstrip("\ufeff")
    header = [h.strip() for h in text.split("\n", 1)[0].split(",")]
    if "load_N" in header:   # csjm plan-experiment: forces fixed in {B} (csjm_opt.measurement.protocol)
        return LoadProtocol.from_text(text, source)
    return read_log_protocol(text if "\n" in text else text + "\n", source)


def read_log_protocol(path_or_text: str | Path, source: str | None = None) -> LogProtocol:
    """Read a protocol (a file path, or CSV text when it contains a newline).

    Parameters
    ----------
    path_or_text : str or Path
    source : str, optional
        Name used in messages for text input.

    Returns
    -------
    LogProtocol

    Raises
    ------
    DataFileError
        Bad header, a cell that is not a number, an empty required cell, a
        half-filled group of columns, no rows.
    """
    if isinstance(path_or_text, Path) or "\n" not in str(path_or_text):
        source = str(path_or_text)
        text = read_text(path_or_text, lambda msg: DataFileError(msg, source), "protocol file",
                         encoding="utf-8-sig")
    else:
        text = str(path_or_text)
    rows = [r for r in csv.reader(io.StringIO(text.lstrip("\ufeff")))]
    if not rows:
        raise DataFileError("empty file: expected a header " + ",".join(COLUMNS), source, 1)
    header = [h.strip() for h in rows[0]]
    m = header_cables(header)
    columns = columns_for(m)
    if tuple(header[:len(columns)]) != columns or not 4 <= m <= 12:
        raise DataFileError("header must start with sample,cycle,l1,...,lm (4 <= m <= 12 cables),"
                            f"{','.join(COLUMNS[8:])}; got {header[:len(columns)]}", source, 1)
    col = {name: j for j, name in enumerate(header)}
    body = [(i + 1, r) for i, r in enumerate(rows) if i > 0 and any(c.strip() for c in r)]
    if not body:
        raise DataFileError("no data rows", source, 2)

    def cells(names: Iterable[str], required: bool, integer: bool = False) -> np.ndarray | None:
        names = list(names)
        if not all(n in col for n in names):
            if required:
                raise DataFileError(f"missing columns {[n for n in names if n not in col]}", source, 1)
            return None
        out = np.full((len(body), len(names)), np.nan)
        for k, (line, r) in enumerate(body):
            if len(r) != len(header):
                raise DataFileError(f"expected {len(header)} values, got {len(r)}", source, line)
            raw = [r[col[n]].strip() for n in names]
            if all(c == "" for c in raw) and not required:
                continue
            for j, (n, c) in enumerate(zip(names, raw, strict=True)):
                if c == "":
                    raise DataFileError("missing value", source, line, n)
                out[k, j] = parse_number(c, n, source, line, integer=integer)
        if not required and np.isnan(out).all():
            return None
        return out

    ids = cells(("sample", "cycle"), True, integer=True)
    lengths = cells(columns[2:2 + m], True)
    assert ids is not None and lengths is not None
    lines = np.array([line for line, _ in body])
    bad = np.flatnonzero(~(lengths > 0) | (lengths > 10.0))
    if bad.size:
        raise DataFileError("rest length must be in (0, 10] m", source, int(lines[bad[0]]))
    intended = cells(INTENDED_COLUMNS, False)
    measured_tau = cells(columns[2 + m:5 + m], False)
    loads = cells(LOAD_COLUMNS, False)
    planned = cells(PLANNED_COLUMNS, False)
    if planned is None:
        planned = cells(columns[5 + m:8 + m], False)
    tau = intended if intended is not None else measured_tau
    n = len(body)
    if tau is None:
        tau = np.zeros((n, 3))
    for name, arr in (("moment", tau), ("load", loads), ("planned pose", planned)):
        if arr is not None and np.isnan(arr).any():
            k = int(np.flatnonzero(np.isnan(arr).any(axis=1))[0])
            raise DataFileError(f"{name} columns filled on some rows and empty on others", source, int(lines[k]))
    mr = np.zeros((n, 3)) if loads is None else loads[:, :1] * loads[:, 1:]
    on_weight = np.zeros(n, bool) if loads is None else loads[:, 0] != 0
    tau_fixed = np.where(on_weight[:, None], 0.0, tau)
    cycle = ids[:, 1].astype(int)
    starts = np.r_[True, cycle[1:] != cycle[:-1]]
    if len(np.unique(cycle)) != int(starts.sum()):
        raise DataFileError("rows of a cycle must be consecutive", source, int(lines[0]))
    if len(np.unique(ids[:, 0])) != n:
        raise DataFileError("sample ids must be unique", source, int(lines[0]))
    known = set(columns)
    extra = {h: np.array([r[col[h]] for _, r in body], dtype=str) for h in header if h not in known}
    return LogProtocol(ids[:, 0].astype(int), cycle, lengths, tau_fixed, mr,
                    None if planned is None else so3.exp(planned), lines, extra, source)


def _nominal(rig: Rig, protocol: LogProtocol) -> tuple[np.ndarray, np.ndarray]:
    """Nominal equilibrium poses and tensions of the protocol's rows (each row from its planned pose)."""
    n = len(protocol)
    R0 = protocol.planned_R if protocol.planned_R is not None else np.repeat(np.eye(3)[None], n, 0)
    plant = dataclasses.replace(TestbedPlant.nominal(rig), persistent=False)
    R = plant.respond(protocol.rest_lengths_m, protocol.tau_fixed_A_Nm, np.arange(n), R0,
                      protocol.load_first_moment_A_kgm)
    c, _ = kin.cable_terms(R, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    return R, np.asarray(rig.cable_stiffness_N_per_m) * (c - protocol.rest_lengths_m)


def check_protocol_cables(rig: Rig, protocol: LogProtocol | LoadProtocol) -> None:
    """Refuse a protocol whose rest-length columns ``l1..lm`` do not match the rig's cable count.

    Raises
    ------
    DataFileError
        Naming the protocol's header line and its last rest-length column.
    """
    m = protocol.rest_lengths_m.shape[1]
    if m != rig.n_cables:
        raise DataFileError(f"{m} rest-length columns l1..l{m}, but the rig has {rig.n_cables} cables "
                            f"(expected l1..l{rig.n_cables})", getattr(protocol, "source", None), 1, f"l{m}")


def check_protocol(rig: Rig, protocol: LogProtocol) -> None:
    """Refuse a protocol the rig cannot run (see the module doc).

    Parameters
    ----------
    rig : Rig
        The nominal rig the protocol was written for.
    protocol : LogProtocol

    Raises
    ------
    DataFileError
        A row without a nominal equilibrium, with a slack cable or a tension
        above ``t_max``, or a planned pose that is not the rig's equilibrium
        (file and line named).
    """
    where = protocol.source
    try:
        R, T = _nominal(rig, protocol)
    except NoEquilibrium as exc:
        raise DataFileError(f"the rig has no equilibrium for a protocol row ({exc})", where) from None
    for k in range(len(protocol)):
        line = int(protocol.lines[k])
        if T[k].min() <= 0.0:
            raise DataFileError(f"outside the rig's limits: cable {int(T[k].argmin()) + 1} slack at the nominal "
                                f"equilibrium", where, line)
        if T[k].max() > rig.t_max_N:
            raise DataFileError(f"outside the rig's limits: cable {int(T[k].argmax()) + 1} at {T[k].max():.1f} N "
                                f"> t_max = {rig.t_max_N:g} N", where, line)
    if protocol.planned_R is not None:
        for k in range(len(protocol)):
            line = int(protocol.lines[k])
            gap = float(so3.angle_between(R[k], protocol.planned_R[k]))
            if gap > PLANNED_POSE_TOL_RAD:
                raise DataFileError(f"the planned pose is {gap:.3f} rad from this rig's equilibrium for the row's "
                                    f"rest lengths and load: written for another rig?", where, line)


def simulate_protocol(rig: Rig, protocol: str | Path | LogProtocol | LoadProtocol, effects: Any = None,
                      severity: float = 1.0,
                      plant: str = "quasi-static", rng: np.random.Generator | None = None,
                      noise: InstrumentNoise | None = None, persistent: bool = True,
                      after: MeasurementLog | None = None,
                      progress: Callable[[int], object] | None = None) -> MeasurementLog:
    """Run a protocol on a testbed plant: the measured log (noise added, extra columns kept).

    Parameters
    ----------
    rig : Rig
        The nominal rig (the protocol's).
    protocol : str, Path, LogProtocol or csjm_opt.measurement.protocol.Protocol
        A protocol file (or CSV text) or a read one.
    effects : str, iterable of str, TestbedPlant, MujocoTestbedPlant or None
        Effect names (injected at ``severity`` with draws from ``rng``) or a ready plant
        (the hidden truth of a study; its own kind is used, ``plant`` ignored).
    severity : float, optional
    plant : {"quasi-static", "mujoco"}, optional
    rng : numpy.random.Generator, optional
        Effect draws and noise (default: seeded 0).
    noise : InstrumentNoise, optional
        Default ``InstrumentNoise.paper()``; ``InstrumentNoise.none()`` for clean logs.
    persistent : bool, optional
        Each cycle starts where the previous one settled (default).
    after : MeasurementLog, optional
        An experiment run on the same plant just before (e.g. the log a diagnosis
        suggested this protocol for): the plant first runs its rows (rest lengths,
        logged moments as the loads, logged poses as starts), so the protocol starts
        from the state where that experiment settled (friction state included).
        Only the protocol's rows are returned.
    progress : callable, optional
        Called with the number of rows just settled (``after``'s rows included).

    Returns
    -------
    MeasurementLog

    Raises
    ------
    DataFileError
        A malformed protocol or one outside the rig's limits (see :func:`check_protocol`).
    InvalidInput
        Unknown effect or plant.
    NoEquilibrium
        The plant (with its effects) cannot hold a row.
    """
    from .injection import make_plant
    from .simulate import with_persistence

    rng = np.random.default_rng(0) if rng is None else rng
    read = protocol if isinstance(protocol, (LogProtocol, LoadProtocol)) else read_protocol(protocol)
    load_protocol, proto = (read, None) if isinstance(read, LoadProtocol) else (None, read)
    check_protocol_cables(rig, read)
    if proto is not None:
        check_protocol(rig, proto)
    if hasattr(effects, "respond"):
        truth = with_persistence(effects, persistent)
    else:
        if plant not in ("quasi-static", "mujoco"):
            raise InvalidInput(f"unknown plant {plant!r}; expected 'quasi-static' or 'mujoco'", "plant")
        truth = make_plant(rig, effects, severity, rng, plant=plant, persistent=persistent)
    noise = InstrumentNoise.paper() if noise is None else noise
    if load_protocol is not None:    # an identification protocol (csjm plan-experiment): forces fixed in {B}
        if after is not None:
            raise InvalidInput("--after is not supported for identification protocols (forces fixed in {B})",
                               "after")
        return run_protocol(truth, load_protocol, rng, noise, progress=progress)
    assert proto is not None
    R_start = proto.planned_R if proto.planned_R is not None else _nominal(rig, proto)[0]
    if after is None:
        R_true = truth.respond(proto.rest_lengths_m, proto.tau_fixed_A_Nm, proto.cycle, R_start,
                               proto.load_first_moment_A_kgm, progress)
    else:       # one history: the earlier experiment, then the protocol (its cycles kept distinct)
        m = len(after)
        cycle = np.r_[after.cycle, proto.cycle + int(after.cycle.max()) - int(proto.cycle.min()) + 1]
        R_true = truth.respond(np.vstack([after.rest_lengths_m, proto.rest_lengths_m]),
                               np.vstack([after.tau_ext_A_Nm, proto.tau_fixed_A_Nm]), cycle,
                               np.concatenate([after.R, R_start]),
                               np.vstack([np.zeros((m, 3)), proto.load_first_moment_A_kgm]), progress)[m:]
    tau_true = proto.tau_fixed_A_Nm + kin.weight_moment(R_true, proto.load_first_moment_A_kgm,
                                                       np.asarray(truth.rig.gravity_B_m_per_s2))
    tau_meas, R_meas = noise.sample(truth.measured_moment(tau_true), truth.measured_pose(R_true), rng)
    return MeasurementLog.from_arrays(proto.cycle, proto.rest_lengths_m, tau_meas, R_meas, sample=proto.sample,
                                      extra=dict(proto.extra))
