"""Writing a rig as compact, human-editable TOML."""

from __future__ import annotations

from typing import Any


def _format_toml(data: dict[str, dict[str, Any]]) -> str:
    """Compact, human-editable TOML (one hole per line); round-trips through tomllib.

    Written by hand rather than with tomli-w, whose arrays put every number on
    its own line, which makes a rig file hard to read and edit.
    """
    units = {"platform_holes": "m, A_i in {A}", "base_holes": "m, B_i in {B}",
             "stiffness": "N/m, cable with drive", "t_min": "N", "t_max": "N", "mass": "kg",
             "com": "m, in {A}", "gravity": "m/s^2, in {B}", "inertia": "kg m^2 about the COM, in {A}",
             "joint_damping": "N m s/rad", "cable_damping": "N s/m",
             "rod_radius": "m, rod from (0, 0, -rod_length) in {B} to O", "rod_length": "m",
             "ball_radius": "m, the joint's ball at O", "tilt_deg": "deg, largest tilt of the stated range"}
    lines = ["# csjm_opt rig file (SI units; frames per docs/conventions.md)"]
    for section, table in data.items():
        lines.append(f"\n[{section}]")
        for key, value in table.items():
            if isinstance(value, list) and value and isinstance(value[0], list):
                rows = ",\n".join("    [" + ", ".join(repr(float(x)) for x in row) + "]" for row in value)
                lines.append(f"{key} = [  # {units[key]}\n{rows},\n]")
            elif isinstance(value, list):
                lines.append(f"{key} = [" + ", ".join(repr(float(x)) for x in value) + f"]  # {units[key]}")
            else:
                lines.append(f"{key} = {float(value)!r}  # {units[key]}")
    return "\n".join(lines) + "\n"
