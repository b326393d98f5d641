"""Bad-input matrix: every malformed input is refused with exit 2 and one line, inputs untouched.

Each case runs ``csjm_opt.cli.main(argv)`` in-process on files written to a
fresh folder and asserts: exit status 2, exactly one line on stderr, no
traceback, no Python warning, every file of the folder byte-for-byte
unchanged (a FIFO stays a FIFO), and an answer within 5 s (``SIGALRM``).
Cases cover rig, log, raw and sweep files (encodings, special files, huge
integers, non-finite and out-of-bound numbers, geometry), every numeric
option and every output path (input named as output, folders, unwritable
places).
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import re
import signal
import stat
import warnings
from pathlib import Path

import pytest

from csjm_opt import cli

ROOT = Path(__file__).resolve().parents[1]
RIG = (ROOT / "rigs" / "paper.toml").read_text()
HUGE = "1" * 400

LOG_HEADER = "sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz"


def _log_rows() -> list[list[str]]:
    rows = []
    for i in range(12):
        c = i // 6
        rows.append([str(i), str(c)] + ["0.15"] * 6 + [f"{0.1 * (i % 6):.2f}", "0.0", f"{0.05 * c:.2f}"]
                    + [f"{0.001 * (i % 6):.4f}", "0.0", "0.0"])
    return rows


def log_text(edit: tuple[int, int, str] | None = None) -> str:
    rows = _log_rows()
    if edit is not None:
        r, c, value = edit
        rows[r][c] = value
    return "\n".join([LOG_HEADER] + [",".join(r) for r in rows]) + "\n"


RAW_COLUMNS = ("record", "sample", "cycle", "name", "x", "y", "z", "rx", "ry", "rz", "px", "py", "pz",
               "fx", "fy", "fz", "mx", "my", "mz", "l1", "l2", "l3", "l4", "l5", "l6")


def raw_text(edit: tuple[int, str, str] | None = None) -> str:
    recs = [{"record": "base_point", "name": f"b{i}", "x": x, "y": y, "z": z, "px": x, "py": y, "pz": z}
            for i, (x, y, z) in enumerate([("0.1", "0", "0"), ("0", "0.1", "0"), ("0", "0", "0.1"),
                                           ("0.1", "0.1", "0")])]
    recs.append({"record": "sensor", "x": "0", "y": "0", "z": "0.02", "rx": "0", "ry": "0", "rz": "0"})
    for s in range(3):
        recs.append({"record": "sample", "sample": str(s), "cycle": "0", "x": "0", "y": "0", "z": "0",
                     "rx": f"{0.01 * s}", "ry": "0", "rz": "0", "fx": "0", "fy": "0", "fz": "1",
                     "mx": "0.1", "my": "0", "mz": "0", **{f"l{i}": "0.15" for i in range(1, 7)}})
    if edit is not None:
        r, col, value = edit
        recs[r][col] = value
    return "\n".join([",".join(RAW_COLUMNS)] + [",".join(r.get(c, "") for c in RAW_COLUMNS) for r in recs]) + "\n"


SWEEP = """[sweep]
method = "grid"
[parameters.platform_d23_m]
values = [0.08, 0.095]
[sampling]
orientations = 50
[metrics]
shaping_poses = 0
"""


def rig_with(old: str, new: str) -> str:
    assert old in RIG, old
    return RIG.replace(old, new, 1)


@dataclasses.dataclass
class Case:
    id: str
    argv: str                                  # placeholders {rig} {log} {raw} {sweep} {dir} {fifo} {tmp}
    files: dict[str, str | bytes] = dataclasses.field(default_factory=dict)  # overrides of the defaults
    expect: str = ""                           # regex the message must contain (what is at fault)


PLAN = "plan --rig {rig} --rotvec 0.1 0 0"
IDENT = "identify {log} --no-progress"
PRE = "preprocess {raw} -o {tmp}/out.csv"
SWP = "sweep {sweep} --out {tmp}/res.jsonl --workers 1 --no-progress"

CASES: list[Case] = []


def add(id_: str, argv: str, expect: str = "", **files: str | bytes) -> None:
    CASES.append(Case(id_, argv, files, expect))


FILE_EXPECT = {"rig": r"rig\.toml", "log": r"log\.csv:\d+", "raw": r"raw\.csv:\d+", "sweep": r"sweep\.toml"}


# ------------------------------------------------------------------ file encodings and kinds
for name, cmd in (("rig", PLAN), ("log", IDENT), ("raw", PRE), ("sweep", SWP)):
    base = {"rig": RIG, "log": log_text(), "raw": raw_text(), "sweep": SWEEP}[name]
    fname = FILE_EXPECT[name].split(":")[0]
    add(f"{name}-latin1", cmd, fname + ".*UTF-8", **{name: base.encode() + "# caf\xe9\n".encode("latin-1")})
    add(f"{name}-utf16-bom", cmd, fname + ".*UTF-16", **{name: base.encode("utf-16")})
    add(f"{name}-utf16-nobom", cmd, fname, **{name: base.encode("utf-16-le")})
    add(f"{name}-utf32", cmd, fname + ".*UTF-32", **{name: base.encode("utf-32")})
    add(f"{name}-binary", cmd, fname, **{name: bytes(range(256)) * 4})
    add(f"{name}-empty", cmd, fname, **{name: b""})
    add(f"{name}-is-fifo", cmd.replace("{" + name + "}", "{fifo}"), "pipe.*FIFO")
    add(f"{name}-is-dir", cmd.replace("{" + name + "}", "{dir}"), "folder")
    add(f"{name}-is-device", cmd.replace("{" + name + "}", "/dev/zero"), "/dev/zero.*device")
    add(f"{name}-missing", cmd.replace("{" + name + "}", "{tmp}/nothing_here"), "nothing_here")

# ------------------------------------------------------------------ rig contents
_RIG_EDIT = {
    "platform_holes": lambda v: ("[0.05773502691896258, -0.005, 0.08]", f"[{v}, -0.005, 0.08]"),
    "base_holes": lambda v: ("[0.03983716857408418, -0.064, -0.08]", f"[{v}, -0.064, -0.08]"),
    "stiffness": lambda v: ("stiffness = [4600.0,", f"stiffness = [{v},"),
    "t_min": lambda v: ("t_min = 5.0", f"t_min = {v}"),
    "t_max": lambda v: ("t_max = 150.0", f"t_max = {v}"),
    "mass": lambda v: ("mass = 0.4913", f"mass = {v}"),
    "com": lambda v: ("com = [0.0, 0.0, 0.081]", f"com = [0.0, 0.0, {v}]"),
    "gravity": lambda v: ("gravity = [0.0, 0.0, -9.81]", f"gravity = [0.0, 0.0, {v}]"),
}
for key, make in _RIG_EDIT.items():
    for label, value in (("huge-int", HUGE), ("neg-huge-int", "-" + HUGE), ("1e308", "1e308"), ("nan", "nan"),
                         ("inf", "inf"), ("string", '"abc"'), ("bool", "true"), ("1e19", "1e19")):
        at = "t_m(in|ax)" if key == "t_min" else key  # t_min above t_max is named at t_max
        add(f"rig-{key}-{label}", PLAN, rf"rig\.toml: \[\w+\.{at}\]", rig=rig_with(*make(value)))
_HOLE_A1 = "[0.05773502691896258, -0.005, 0.08]"
for label, old, new in (
        ("duplicate-platform-hole", "[0.05773502691896258, 0.005, 0.08]", _HOLE_A1),
        ("duplicate-base-hole", "[0.03983716857408418, 0.064, -0.08]", "[0.03983716857408418, -0.064, -0.08]"),
        ("platform-hole-10um-from-O", _HOLE_A1, "[1e-5, 0.0, 0.0]"),
        ("base-hole-10um-from-O", "[0.03983716857408418, -0.064, -0.08]", "[0.0, 1e-5, 0.0]"),
        ("holes-5um-apart", "[0.05773502691896258, 0.005, 0.08]", "[0.05773502691896258, -0.004995, 0.08]"),
        ("hole-at-20m", _HOLE_A1, "[20.0, 0.0, 0.08]"),
        ("hole-at-1e308", _HOLE_A1, "[1e308, 1e308, 1e308]"),
        ("stiffness-zero", "stiffness = [4600.0,", "stiffness = [0.0,"),
        ("stiffness-negative", "stiffness = [4600.0,", "stiffness = [-4600.0,"),
        ("stiffness-1e12", "stiffness = [4600.0,", "stiffness = [1e12,"),
        ("t-min-negative", "t_min = 5.0", "t_min = -5.0"),
        ("t-min-above-t-max", "t_min = 5.0", "t_min = 500.0"),
        ("t-max-1e9", "t_max = 150.0", "t_max = 1e9"),
        ("mass-negative", "mass = 0.4913", "mass = -1.0"),
        ("mass-1e6", "mass = 0.4913", "mass = 1e6"),
        ("gravity-1e6", "gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, -1e6]"),
        ("com-short", "com = [0.0, 0.0, 0.081]", "com = [0.0, 0.081]"),
        ("unknown-key", "mass = 0.4913", "mass = 0.4913\ncolour = 1"),
        ("unknown-section", "[platform]", "[extra]\nx = 1\n[platform]"),
        ("missing-section", "[cables]", "[cables_]"),
        ("ragged-holes", _HOLE_A1, "[0.05773502691896258, -0.005]"),
        ("not-toml", "[cables]", "[cables"),
):
    add(f"rig-{label}", PLAN, r"rig\.toml", rig=rig_with(old, new))

# ------------------------------------------------------------------ log contents
for label, (row, col, value) in {
        "sample-1e19": (3, 0, "1e19"), "sample-1e300": (3, 0, "1e300"), "sample-huge-int": (3, 0, HUGE),
        "sample-fraction": (3, 0, "2.5"), "sample-text": (3, 0, "abc"), "cycle-1e19": (0, 1, "1e19"),
        "cycle-nan": (2, 1, "nan"), "tau-1e19": (4, 8, "1e19"), "tau-1e300": (4, 9, "1e300"),
        "tau-huge-int": (4, 10, HUGE), "tau-nan": (4, 8, "nan"), "tau-inf": (4, 8, "-inf"),
        "rest-length-negative": (2, 2, "-0.1"), "rest-length-zero": (2, 3, "0"), "rest-length-1e5": (2, 4, "1e5"),
        "rotvec-norm-4": (5, 11, "4.0"), "rotvec-1e308": (5, 12, "1e308"), "rotvec-2pi": (5, 13, "6.3"),
        "missing-cell": (6, 5, ""), "duplicate-sample": (7, 0, "6"), "non-consecutive-cycle": (8, 1, "0"),
        "tau-text": (9, 9, "1,2"),
}.items():
    add(f"log-{label}", IDENT, rf"log\.csv:{row + 2}\b", log=log_text((row, col, value)))
add("log-wrong-header", IDENT, r"log\.csv:1\b", log=log_text().replace("tau_x", "tx", 1))
add("log-only-header", IDENT, r"log\.csv", log=LOG_HEADER + "\n")
add("log-extra-value", IDENT, r"log\.csv:4\b", log="\n".join(
    line + (",1" if i == 3 else "") for i, line in enumerate(log_text().split("\n"))))

# ------------------------------------------------------------------ raw contents
for label, (row, col, value) in {
        "sample-1e19": (5, "sample", "1e19"), "force-1e300": (5, "fx", "1e300"), "moment-1e19": (6, "mx", "1e19"),
        "position-1e308": (0, "x", "1e308"), "position-huge-int": (1, "px", HUGE), "rotvec-norm-5": (6, "rx", "5"),
        "sensor-rotvec-1e308": (4, "rx", "1e308"), "rest-length-negative": (5, "l1", "-1"),
        "unknown-record": (5, "record", "sampel"), "nan-force": (7, "fz", "nan"),
}.items():
    add(f"raw-{label}", PRE, rf"raw\.csv:{row + 2}\b", raw=raw_text((row, col, value)))
add("raw-wrong-header", PRE, r"raw\.csv:1\b", raw=raw_text().replace("record", "kind", 1))

# ------------------------------------------------------------------ sweep contents
for label, text in {
        "num-1e9": SWEEP.replace("values = [0.08, 0.095]", "min = 0.07\nmax = 0.1\nnum = 1000000000"),
        "num-float-1e9": SWEEP.replace("values = [0.08, 0.095]", "min = 0.07\nmax = 0.1\nnum = 1e9"),
        "num-huge-int": SWEEP.replace("values = [0.08, 0.095]", f"min = 0.07\nmax = 0.1\nnum = {HUGE}"),
        "grid-product-1e9": SWEEP + "".join(f"[parameters.{p}]\nmin = 0.07\nmax = 0.1\nnum = 1000\n"
                                            for p in ("oo_a_m", "oo_b_m", "base_d23_m")),
        "random-1e9": SWEEP.replace('method = "grid"', 'method = "random"\ndesigns = 1000000000')
                           .replace("values = [0.08, 0.095]", "min = 0.07\nmax = 0.1"),
        "lhs-1e9": SWEEP.replace('method = "grid"', 'method = "lhs"\ndesigns = 1000000000')
                        .replace("values = [0.08, 0.095]", "min = 0.07\nmax = 0.1"),
        "lhs-huge-int": SWEEP.replace('method = "grid"', f'method = "lhs"\ndesigns = {HUGE}')
                             .replace("values = [0.08, 0.095]", "min = 0.07\nmax = 0.1"),
        "orientations-1e9": SWEEP.replace("orientations = 50", "orientations = 1000000000"),
        "orientations-huge-int": SWEEP.replace("orientations = 50", f"orientations = {HUGE}"),
        "orientations-zero": SWEEP.replace("orientations = 50", "orientations = 0"),
        "seed-huge-int": SWEEP.replace('method = "grid"', f'method = "grid"\nseed = {HUGE}'),
        "value-huge-int": SWEEP.replace("values = [0.08, 0.095]", f"values = [0.08, {HUGE}]"),
        "value-nan": SWEEP.replace("values = [0.08, 0.095]", "values = [0.08, nan]"),
        "min-1e308": SWEEP.replace("values = [0.08, 0.095]", "min = -1e308\nmax = 1e308\nnum = 3"),
        "base-huge-int": SWEEP + f"[base]\noo_a_m = {HUGE}\n",
        "loads-1e19": SWEEP + "[loads]\ntau_ext = [[1e19, 0, 0]]\n",
        "loads-huge-int": SWEEP + f"[loads]\ntau_ext = [[{HUGE}, 0, 0]]\n",
        "loads-ragged": SWEEP + "[loads]\ntau_ext = [[1, 0], [0, 0, 0]]\n",
        "shaping-poses-1e9": SWEEP.replace("shaping_poses = 0", "shaping_poses = 1000000000"),
        "unknown-key": SWEEP.replace("[sampling]", "[sampling]\ncolour = 1"),
        "bad-method": SWEEP.replace('"grid"', '"grd"'),
        "not-toml": SWEEP.replace("[sampling]", "[sampling"),
}.items():
    add(f"sweep-{label}", SWP, r"sweep\.toml", sweep=text)

# ------------------------------------------------------------------ numeric options
for cmd in ("plan", "stiffness"):
    base = f"{cmd} --rig {{rig}}"
    for label, opt in (("rotvec-1e308", "--rotvec 1e308 0 0"), ("rotvec-nan", "--rotvec nan 0 0"),
                       ("rotvec-inf", "--rotvec 0 inf 0"), ("rotvec-4", "--rotvec 4 0 0"),
                       ("rotvec-norm", "--rotvec 2 2 2"), ("rotvec-text", "--rotvec a 0 0"),
                       ("tau-1e19", "--rotvec 0 0 0 --tau 1e19 0 0"), ("tau-nan", "--rotvec 0 0 0 --tau 0 nan 0"),
                       ("t-ref-negative", "--rotvec 0 0 0 --t-ref -1"), ("t-ref-nan", "--rotvec 0 0 0 --t-ref nan"),
                       ("t-ref-1e9", "--rotvec 0 0 0 --t-ref 1e9")):
        add(f"{cmd}-{label}", f"{base} {opt}", opt.split()[4 if label.startswith(("tau", "t-ref")) else 0])
SHAPE = "shape --rig {rig} --rotvec 0.1 0 0"
T9 = "20 0 0 0 20 0 0 0 20"
for label, opt in (("target-1e308", "--target " + " ".join(["1e308"] * 9)), ("target-nan", "--target nan" + T9[2:]),
                   ("target-inf", "--target inf" + T9[2:]), ("target-short", "--target 1 2 3"),
                   ("weights-negative", f"--target {T9} --weights -1 1 1 1 1 1 1 1 1"),
                   ("weights-nan", f"--target {T9} --weights nan 1 1 1 1 1 1 1 1"),
                   ("weights-count", f"--target {T9} --weights 1 1"),
                   ("direction-zero", f"--target {T9} --objective directional --direction 0 0 0"),
                   ("direction-nan", f"--target {T9} --objective directional --direction nan 0 0")):
    add(f"shape-{label}", f"{SHAPE} {opt}", "--" + label.split("-")[0])
add("shape-rotvec-1e308", f"shape --rig {{rig}} --rotvec 1e308 0 0 --target {T9}", "--rotvec")
for label, opt in (("bootstrap-negative", "--bootstrap -5"), ("bootstrap-1e9", "--bootstrap 1000000000"),
                   ("bootstrap-text", "--bootstrap many"), ("bootstrap-float", "--bootstrap 2.5"),
                   ("ci-level-0", "--ci-level 0"), ("ci-level-1", "--ci-level 1"), ("ci-level-nan", "--ci-level nan"),
                   ("ci-level-1.5", "--ci-level 1.5"), ("max-condition-nan", "--max-condition nan"),
                   ("max-condition-0", "--max-condition 0"), ("max-condition-inf", "--max-condition inf"),
                   ("cycle-1e19", "--cycle 1e19"), ("cycle-huge", "--cycle 99999999999999999999"),
                   ("cycle-missing", "--cycle 7"), ("order-4", "--order 4")):
    add(f"identify-{label}", f"{IDENT} {opt}", opt.split()[0] if label != "cycle-missing" else "cycle 7")
for label, opt in (("nan", "nan"), ("negative", "-1"), ("zero", "0"), ("inf", "inf"), ("10m", "10")):
    add(f"preprocess-origin-tol-{label}", f"{PRE} --origin-tol {opt}", "--origin-tol")
for label, opt in (("workers-0", "--workers 0"), ("workers-negative", "--workers -1"),
                   ("workers-1e9", "--workers 1000000000"), ("workers-text", "--workers two"),
                   ("limit-0", "--limit 0"), ("limit-huge", "--limit " + HUGE[:25])):
    add(f"sweep-{label}", SWP.replace(" --workers 1", "") + " " + opt, opt.split()[0])
add("demo-seed-negative", "demo --out {tmp}/report --seed -1", "--seed")
add("demo-seed-huge", "demo --out {tmp}/report --seed " + HUGE[:40], "--seed")
add("demo-seed-float", "demo --out {tmp}/report --seed 1e400", "--seed")

# ------------------------------------------------------------------ output paths
for cmd in ("plan", "stiffness"):
    add(f"{cmd}-json-is-rig", f"{cmd} --rig {{rig}} --rotvec 0.1 0 0 --json {{rig}}", "--json")
    add(f"{cmd}-json-is-dir", f"{cmd} --rig {{rig}} --rotvec 0.1 0 0 --json {{dir}}", "--json")
    add(f"{cmd}-json-under-file", f"{cmd} --rig {{rig}} --rotvec 0.1 0 0 --json {{rig}}/out.json", "--json")
    add(f"{cmd}-json-is-fifo", f"{cmd} --rig {{rig}} --rotvec 0.1 0 0 --json {{fifo}}", "--json")
    add(f"{cmd}-json-is-device", f"{cmd} --rig {{rig}} --rotvec 0.1 0 0 --json /dev/null", "--json")
add("plan-json-rig-via-dotdot", "plan --rig {rig} --rotvec 0.1 0 0 --json {dir}/../rig.toml", "--json")
add("plan-json-empty", "plan --rig {rig} --rotvec 0.1 0 0 --json=", "--json")
add("shape-json-is-rig", f"{SHAPE} --target {T9} --json {{rig}}", "--json")
add("shape-json-is-dir", f"{SHAPE} --target {T9} --json {{dir}}", "--json")
add("identify-json-is-log", f"{IDENT} --json {{log}}", "--json")
add("identify-json-is-rig", f"{IDENT} --rig {{rig}} --json {{rig}}", "--json")
add("identify-json-is-dir", f"{IDENT} --json {{dir}}", "--json")
add("identify-figures-is-file", f"{IDENT} --figures {{rig}}", "--figures")
add("identify-figures-is-log", f"{IDENT} --figures {{log}}", "--figures")
add("preprocess-out-is-raw", "preprocess {raw} -o {raw}", "-o/--out")
add("preprocess-out-is-rig", "preprocess {raw} --rig {rig} -o {rig}", "-o/--out")
add("preprocess-out-exists", "preprocess {raw} -o {log}", "-o/--out")
add("preprocess-out-is-dir", "preprocess {raw} -o {dir}", "-o/--out")
add("preprocess-json-is-out", f"{PRE} --json {{tmp}}/out.csv", "--json")
add("preprocess-json-is-raw", f"{PRE} --json {{raw}}", "--json")
add("sweep-out-is-sweep", "sweep {sweep} --out {sweep} --workers 1", "--out")
add("sweep-out-is-dir", "sweep {sweep} --out {dir} --workers 1", "--out")
add("sweep-out-is-fifo", "sweep {sweep} --out {fifo} --workers 1", "--out")
add("sweep-json-is-out", f"{SWP} --json {{tmp}}/res.jsonl", "--json")
add("sweep-json-is-sweep", f"{SWP} --json {{sweep}}", "--json")
add("paper-json-is-dir", "paper --json {dir}", "--json")
add("paper-json-under-file", "paper --json {rig}/x.json", "--json")
add("demo-json-is-dir", "demo --out {tmp}/report --json {dir}", "--json")
add("demo-out-is-file", "demo --out {rig}", "--out")
add("demo-out-under-file", "demo --out {rig}/report", "--out")
add("demo-json-under-file", "demo --out {tmp}/report --json {log}/x.json", "--json")
add("diagnose-json-is-log", "diagnose {log} --json {log}", "--json")
add("diagnose-report-is-file", "diagnose {log} --report {rig}", "--report")
add("diagnose-json-is-dir", "diagnose {log} --json {dir}", "--json")

MJCF = "export-mjcf --rig {rig} -o {tmp}/model.xml"
for label, opt, at in (("rotvec-1e308", "--rotvec 1e308 0 0", "--rotvec"),
                       ("rotvec-norm", "--rotvec 2 2 2", "--rotvec"),
                       ("tau-nan", "--tau nan 0 0", "--tau"), ("timestep-zero", "--timestep 0", "--timestep"),
                       ("timestep-nan", "--timestep nan", "--timestep")):
    add(f"export-mjcf-{label}", f"{MJCF} {opt}", at)
add("export-mjcf-output-is-rig", "export-mjcf --rig {rig} -o {rig}", "-o/--out")
add("export-mjcf-output-is-dir", "export-mjcf --rig {rig} -o {dir}", "-o/--out")
add("export-mjcf-json-is-output", f"{MJCF} --json {{tmp}}/model.xml", "--json")
add("export-mjcf-rig-fifo", "export-mjcf --rig {fifo} -o {tmp}/model.xml", "FIFO")
add("report-results-fifo", "report {fifo} --out {tmp}/rep", "")
add("report-results-utf16", "report {sweep} --out {tmp}/rep", "", sweep='{"id": 1}\n'.encode("utf-16"))
add("report-top-zero", "report {sweep} --out {tmp}/rep --top 0", "--top")
add("report-top-huge", "report {sweep} --out {tmp}/rep --top " + HUGE[:30], "--top")
add("report-out-is-file", "report {sweep} --out {rig}", "--out")
add("report-out-is-input", "report {sweep} --out {sweep}", "--out")

# ------------------------------------------------------------------ usage
add("no-command", "")
add("unknown-command", "plane --rig {rig}")
add("unknown-option", f"{PLAN} --colour red")


def _snapshot(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        mode = p.lstat().st_mode
        if stat.S_ISREG(mode):
            out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
        else:
            out[str(p)] = "fifo" if stat.S_ISFIFO(mode) else "dir" if stat.S_ISDIR(mode) else "other"
    return out


class _Timeout(Exception):
    pass


def _alarm(signum, frame):  # pragma: no cover - only when a case hangs
    raise _Timeout("case took longer than 5 s")


def test_matrix_is_large_and_unique():
    ids = [c.id for c in CASES]
    assert len(ids) >= 150 and len(set(ids)) == len(ids)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_refused_in_one_line(case, tmp_path, capsys, monkeypatch):
    files = {"rig": RIG, "log": log_text(), "raw": raw_text(), "sweep": SWEEP} | case.files
    paths = {"rig": "rig.toml", "log": "log.csv", "raw": "raw.csv", "sweep": "sweep.toml"}
    for name, content in files.items():
        path = tmp_path / paths[name]
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    (tmp_path / "folder").mkdir()
    os.mkfifo(tmp_path / "pipe")
    where = {name: str(tmp_path / p) for name, p in paths.items()}
    where |= {"dir": str(tmp_path / "folder"), "fifo": str(tmp_path / "pipe"), "tmp": str(tmp_path)}
    argv = [re.sub(r"\{(\w+)\}", lambda m: where[m.group(1)], a) for a in case.argv.split()]
    monkeypatch.chdir(tmp_path)
    before = _snapshot(tmp_path)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(5)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            code = cli.main(argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    out, err = capsys.readouterr()
    assert code == 2, (code, err)
    lines = err.strip("\n").split("\n")
    assert len(lines) == 1 and lines[0].startswith("csjm: error: ") and len(lines[0]) > 20, err
    assert "Traceback" not in err + out
    assert re.search(case.expect, lines[0]), (case.expect, lines[0])
    assert not caught, [str(w.message) for w in caught]
    assert _snapshot(tmp_path) == before
