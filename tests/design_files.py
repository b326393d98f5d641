"""A small design file (one swept parameter, few orientations) for the optimiser's tests."""

from __future__ import annotations


def tiny_design_toml(*, orientations: int, max_tilt_deg: float, max_torsion_deg: float,
                     tau_ext: list[list[float]], optimise: str) -> str:
    """The text of a one-parameter design file (platform radius 40-60 mm) with an ``[optimise]`` table.

    ``optimise`` holds the table's own lines (objective, starts, ...); the clearance requirements
    are switched off after them, as the tests' tiny geometries would not meet the defaults.
    """
    return f"""
[sweep]
method = "grid"
[base]
platform_gamma_deg = 60.0
base_radius_m = 0.075
base_gamma_deg = 20.0
[parameters.platform_radius_m]
min = 0.04
max = 0.06
num = 3
[sampling]
orientations = {orientations}
max_tilt_deg = {max_tilt_deg!r}
max_torsion_deg = {max_torsion_deg!r}
[loads]
tau_ext = {tau_ext!r}
[optimise]
{optimise.strip()}
min_cable_distance_m = 0.0
min_link_clearance_m = 0.0
max_exit_angle_deg = 90.0
"""
