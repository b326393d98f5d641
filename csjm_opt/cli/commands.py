"""The ``csjm`` commands: name -> (the CLI module that registers it, its one-line help).

Kept in a module that imports nothing, so that ``csjm --help`` (and any one
command) does not import the modules, and through them the subpackages, of the
other commands: :func:`csjm_opt.cli.app.main` imports only the module of the
command it runs.
"""

from __future__ import annotations

#: Every command, in help order: name -> (module under ``csjm_opt.cli``, one-line help).
COMMANDS: dict[str, tuple[str, str]] = {
    "rig": ("rig", "inspect a rig file: `csjm rig show RIG` prints the holes and draws the rig"),
    "plan": ("core", "cable tensions that hold a pose under a load"),
    "stiffness": ("core", "stiffness K at a pose (tensions as planned)"),
    "demo": ("demo", "run the main job on the paper rig and write a report folder"),
    "shape": ("shape", "shape the stiffness K toward a target at a pose"),
    "preprocess": ("identify", "raw tracker/F/T CSV -> measurement log"),
    "identify": ("identify", "identify K per load cycle of a measurement log"),
    "paper": ("identify", "reproduce the paper's Tables 3 and 4 and check them"),
    "plan-experiment": ("plan_experiment", "plan an identification experiment (loads, pretension)"),
    "diagnose": ("diagnose", "which unmodelled effect explains the model-rig gap"),
    "validate": ("validate", "score the diagnosis on a folder of logs with known answers (answers.json)"),
    "simulate": ("simulate", "run a protocol on a simulated rig (testbed plant with effects)"),
    "sweep": ("sweep", "hole-geometry design sweep (workspace, stiffness, margins)"),
    "optimise": ("optimise", "hole-geometry optimisation (guaranteed workspace, stiffness, no collisions)"),
    "report": ("report", "design-study report (HTML + Markdown) of csjm sweep results"),
    "view": ("view", "interactive 3-D view of the rig at a pose (one offline HTML page)"),
    "export-mjcf": ("export_mjcf", "MuJoCo model (MJCF) of a rig"),
    "codegen": ("codegen", "C99 tension planner and K of a rig (no malloc, libm only)"),
}


# Choices the parsers offer, kept here so that building a parser imports no numerical library;
# tests/cli check each against the module that owns it.
#: :data:`csjm_opt.shaping.objectives.OBJECTIVES`.
SHAPING_OBJECTIVES = ("frobenius", "eigen", "directional")
#: :data:`csjm_opt.model.mjcf.ACTUATIONS`.
MJCF_ACTUATIONS = ("spring", "winch", "tension")
#: :data:`csjm_opt.testbed.mujoco.plant.PLANTS`.
TESTBED_PLANTS = ("quasi-static", "mujoco")
#: The diagnosis vocabulary, :data:`csjm_opt.diagnose.effects.EFFECTS` (in its order).
DIAGNOSIS_EFFECTS = ("hole_offsets", "friction", "cable_hardening", "link_compliance", "sensor_bias", "mass_com",
                     "tracker_registration", "stiffness_scale", "guide_radius", "drive_offsets", "sensor_gain",
                     "joint_friction")
#: The effects ``csjm simulate`` injects: :data:`csjm_opt.testbed.plant.EFFECT_NAMES`, the variants
#: (:data:`~csjm_opt.testbed.plant.VARIANT_NAMES`) and :data:`~csjm_opt.testbed.plant.OUTSIDE_NAMES`.
TESTBED_EFFECTS = ("hole_offsets", "friction", "cable_hardening", "link_compliance", "sensor_bias", "mass_com",
                   "tracker_registration", "stiffness_scale", "drive_offsets", "sensor_gain", "joint_friction",
                   "coulomb_friction", "guide_radius", "sensor_drift", "drum_slip")
#: Old effect names ``csjm simulate`` still takes: :data:`csjm_opt.testbed.plant.DEPRECATED_NAMES`.
TESTBED_DEPRECATED = {"eyelet_radius": "guide_radius"}
#: :data:`csjm_opt.design._value_checks.MAX_DESIGNS`.
MAX_DESIGNS = 1_000_000


def command_help(name: str) -> str:
    """The one-line help of command ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`COMMANDS`.

    Returns
    -------
    str
        Its help text.
    """
    return COMMANDS[name][1]
