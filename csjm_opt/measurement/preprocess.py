"""Raw instrument data -> measurement log (Section III-B, (51)-(56), erratum 6).

Raw CSV format (one file, UTF-8, comma separated, SI units: m, rad, N, N m)
---------------------------------------------------------------------------
Header: exactly these columns, in any order (a free-text ``note`` column is
also allowed), with one rest-length column per cable of the rig, ``l1..lm`` (a six-cable
rig's header below; a raw file whose count differs from the rig's is refused, naming it)::

    record,sample,cycle,name,x,y,z,rx,ry,rz,px,py,pz,fx,fy,fz,mx,my,mz,l1,l2,l3,l4,l5,l6

Each row is one record; the cells a record does not use must be empty.

``base_point`` (at least 3 non-collinear points; all are used, repeats allowed)
    ``name``; ``x,y,z`` the point measured by the tracker in {L}; ``px,py,pz``
    the same point's nominal coordinates in the base frame {B}.
``sensor`` (exactly one)
    pose of the F/T sensor frame {S} in {A}: ``x,y,z`` origin of {S} in {A};
    ``rx,ry,rz`` rotation vector of {S} in {A}.
``sample`` (one per static equilibrium, in time order)
    ``sample`` (unique integer id), ``cycle`` (integer; rows of a cycle
    consecutive, first row = reference), ``l1..lm`` commanded rest lengths;
    ``fx,fy,fz,mx,my,mz`` the F/T reading in {S}; and *either* the platform
    pose measured in {L} (``x,y,z`` origin of {A}, ``rx,ry,rz`` rotation
    vector of {A} in {L}) *or* empty pose cells and ``platform_point`` records.
``platform_point`` (optional, at least 3 per sample without a direct pose)
    ``sample``; ``name``; ``x,y,z`` measured in {L}; ``px,py,pz`` nominal in {A}.

Processing
----------
1. ``{B}`` in ``{L}`` by a least-squares rigid fit of all base points
   (Kabsch/Umeyama without scale, erratum 6) instead of the 4x4 inverse of (52).
2. ``{A}`` in ``{B}``: ``T_BA = T_LB^-1 T_LA`` (53); the origins must coincide
   (54): ``||p_BA|| <= origin_tol_m`` or a :class:`DataFileError` names the line.
3. Wrench moved to {A} about O (55): with ``(R_AS, p_AS)`` the pose of {S}
   in {A}, ``f_A = R_AS f_S`` and ``tau_A = R_AS tau_S + p_AS x f_A``
   (``= Ad^T_{T_SA} W_S`` in (f, tau) order).
4. Weight (56): ``tau_G = r_G x (R_BA^T m g_B)`` in {A} is written to extra
   columns ``tauw_x..z``; the log's ``tau_*`` exclude it (docs/conventions.md). If the
   F/T moment includes the platform weight (``ft_includes_weight``), it is
   subtracted.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import so3
from .._fileio import read_text
from ..errors import DataFileError, IllConditionedData, InvalidInput
from ..model.rig import Rig
from .frames import fit_rigid_transform, weight_moment_A, wrench_to_A
from .logfile import MeasurementLog
from .raw_file import RAW_COLUMNS, parse_raw, raw_columns

__all__ = ["DEFAULT_ORIGIN_TOL_M", "MAX_ORIGIN_TOL_M", "RAW_COLUMNS", "fit_rigid_transform", "parse_raw",
           "preprocess_file", "preprocess_text", "raw_columns", "weight_moment_A", "wrench_to_A"]

DEFAULT_ORIGIN_TOL_M = 2e-3
#: Largest accepted ``origin_tol_m`` (m): beyond it (54) checks nothing on a bench-top rig.
MAX_ORIGIN_TOL_M = 1.0


def preprocess_text(text: str, rig: Rig, source: str | None = None, origin_tol_m: float = DEFAULT_ORIGIN_TOL_M,
                    ft_includes_weight: bool = False) -> tuple[MeasurementLog, dict[str, Any]]:
    """Raw instrument CSV text to a measurement log, Section III-B of the paper.

    Base frame by a least-squares rigid fit (erratum 6), platform pose (53)-(54), wrench moved
    to {A} about O (55), weight moment (56) in extra columns ``tauw_x..z``.

    Parameters
    ----------
    text : str
        Raw CSV text.
    rig : Rig
        The rig (weight moment, frames).
    source : str, optional
        Name of the source, used in error messages.
    origin_tol_m : float, optional
        Largest accepted distance between the origins of {A} and {B} (m), (54).
    ft_includes_weight : bool, optional
        The F/T moment contains the platform's weight (it is then subtracted).

    Returns
    -------
    log : MeasurementLog
        The measurement log.
    summary : dict
        Base-frame fit residual, origin distances and counts.

    Raises
    ------
    DataFileError
        A malformed raw file (naming the line) or a pose violating (54).
    InvalidInput
        ``origin_tol_m`` not a number in (0, :data:`MAX_ORIGIN_TOL_M`].
    """
    if isinstance(origin_tol_m, bool) or not isinstance(origin_tol_m, (int, float)) \
            or not 0 < origin_tol_m <= MAX_ORIGIN_TOL_M:
        raise InvalidInput(f"origin_tol_m: expected a number in (0, {MAX_ORIGIN_TOL_M:g}] m, got {origin_tol_m!r}",
                           "origin_tol_m")
    rec = parse_raw(text, source, rig.n_cables)
    base = rec["base_point"]
    if len(base) < 3:
        raise DataFileError(f"need at least 3 base_point records, got {len(base)}", source)
    P_B = np.array([[v["px"], v["py"], v["pz"]] for _, v in base])
    P_L = np.array([[v["x"], v["y"], v["z"]] for _, v in base])
    try:
        R_LB, p_LB, base_rms = fit_rigid_transform(P_B, P_L)
    except IllConditionedData as exc:
        raise DataFileError(f"base points: {exc}", source, base[0][0]) from exc
    if len(rec["sensor"]) != 1:
        raise DataFileError(f"need exactly one sensor record, got {len(rec['sensor'])}", source,
                            rec["sensor"][1][0] if len(rec["sensor"]) > 1 else None)
    s = rec["sensor"][0][1]
    R_AS, p_AS = so3.exp(np.array([s["rx"], s["ry"], s["rz"]])), np.array([s["x"], s["y"], s["z"]])
    points: dict[int, list] = {}
    for line, v in rec["platform_point"]:
        points.setdefault(v["sample"], []).append((line, v))
    samples = rec["sample"]
    if not samples:
        raise DataFileError("no sample records", source)
    seen: dict[int, int] = {}
    rows = []
    for line, v in samples:
        sid = v["sample"]
        if sid in seen:
            raise DataFileError(f"duplicate sample id {sid} (first on line {seen[sid]})", source, line, "sample")
        seen[sid] = line
        R_LA, p_LA = _platform_pose_L(v, points.pop(sid, []), source, line)
        R_BA = R_LB.T @ R_LA                                   # (53)
        p_BA = R_LB.T @ (p_LA - p_LB)
        offset = float(np.linalg.norm(p_BA))
        if offset > origin_tol_m:                              # (54)
            raise DataFileError(f"origin of {{A}} is {offset * 1e3:.3f} mm from the origin of {{B}} "
                                f"(tolerance {origin_tol_m * 1e3:g} mm): frames or base points wrong?",
                                source, line)
        rows.append((line, v, R_BA, offset))
    if points:
        sid, lst = next(iter(points.items()))
        raise DataFileError(f"platform_point for sample {sid}, which has no sample record", source, lst[0][0])
    R_BA = np.array([r[2] for r in rows])
    f_S = np.array([[r[1]["fx"], r[1]["fy"], r[1]["fz"]] for r in rows])
    tau_S = np.array([[r[1]["mx"], r[1]["my"], r[1]["mz"]] for r in rows])
    f_A, tau_A = wrench_to_A(f_S, tau_S, R_AS, p_AS)          # (55)
    tau_G = weight_moment_A(rig, R_BA)                        # (56)
    tau_ext = tau_A - tau_G if ft_includes_weight else tau_A
    extra = {"fx_A": f_A[:, 0], "fy_A": f_A[:, 1], "fz_A": f_A[:, 2],
             "tauw_x": tau_G[:, 0], "tauw_y": tau_G[:, 1], "tauw_z": tau_G[:, 2],
             "origin_offset_m": np.array([r[3] for r in rows])}
    extra = {k: np.array([repr(float(x)) for x in v]) for k, v in extra.items()}
    try:
        log = MeasurementLog.from_arrays([r[1]["cycle"] for r in rows],
                                         [[r[1][f"l{i}"] for i in range(1, rig.n_cables + 1)] for r in rows],
                                         tau_ext, R_BA, sample=[r[1]["sample"] for r in rows], extra=extra)
    except DataFileError as exc:  # re-anchor row numbers to raw lines
        idx = (exc.line or 2) - 2
        raise DataFileError(str(exc).split(": ", 1)[-1], source, rows[min(idx, len(rows) - 1)][0],
                            exc.column) from exc
    log = MeasurementLog(log.sample, log.cycle, log.rest_lengths_m, log.tau_ext_A_Nm, log.rotvec_rad,
                         log.extra, source)
    info = {"base_points": len(base), "base_fit_rms_m": base_rms, "R_LB": R_LB.tolist(), "p_LB_m": p_LB.tolist(),
            "max_origin_offset_m": float(max(r[3] for r in rows)), "ft_includes_weight": ft_includes_weight}
    return log, info


def _platform_pose_L(v: dict, pts: list, source: str | None, line: int) -> tuple[np.ndarray, np.ndarray]:
    if "x" in v:
        if pts:
            raise DataFileError("sample has both a direct pose and platform_point records", source, line)
        return so3.exp(np.array([v["rx"], v["ry"], v["rz"]])), np.array([v["x"], v["y"], v["z"]])
    if len(pts) < 3:
        raise DataFileError(f"sample {v['sample']} has no pose and {len(pts)} platform_point records "
                            "(need at least 3)", source, line)
    P_A = np.array([[p["px"], p["py"], p["pz"]] for _, p in pts])
    P_L = np.array([[p["x"], p["y"], p["z"]] for _, p in pts])
    try:
        R, p, _ = fit_rigid_transform(P_A, P_L)
    except IllConditionedData as exc:
        raise DataFileError(f"platform points of sample {v['sample']}: {exc}", source, pts[0][0]) from exc
    return R, p


def preprocess_file(path: str | Path, rig: Rig, **options: Any) -> tuple[MeasurementLog, dict[str, Any]]:
    """Read a raw instrument CSV file and turn it into a measurement log (see :func:`preprocess_text`).

    Parameters
    ----------
    path : str or Path
        The raw CSV file (format in docs/guide/input-files.md).
    rig : Rig
        The rig (weight moment, frames).
    **options
        Passed to :func:`preprocess_text` (``origin_tol_m``, ``ft_includes_weight``).

    Returns
    -------
    log : MeasurementLog
        The measurement log.
    summary : dict
        Base-frame fit residual, origin distances and counts.

    Raises
    ------
    DataFileError
        If the file cannot be read or is malformed (naming the line).
    InvalidInput
        If an option is invalid.
    """
    path = Path(path)
    text = read_text(path, lambda msg: DataFileError(msg, str(path)), "raw file")
    return preprocess_text(text, rig, str(path), **options)
