"""The ``csjm`` commands: name -> (the CLI module that registers it, its one-line help).

Kept in a module that imports nothing, so that ``csjm --help`` (and any one
command) does not import the modules, and through them the subpackages, of the
other commands: :func:`csjm_opt.cli.app.main` imports only the module of the
command it runs.
"""

from __future__ import annotations

#: Every command, in help order: name -> (module under ``csjm_opt.cli``, one-line help).
COMMANDS: dict[str, tuple[str, str]] = {
    "plan": ("core", "cable tensions that hold a pose under a load"),
    "stiffness": ("core", "stiffness K at a pose (tensions as planned)"),
    "demo": ("demo", "run the main job on the paper rig and write a report folder"),
    "shape": ("shape", "shape the stiffness K toward a target at a pose"),
    "preprocess": ("identify", "raw tracker/F/T CSV -> measurement log"),
    "identify": ("identify", "identify K per load cycle of a measurement log"),
    "paper": ("identify", "reproduce the paper's Tables 3 and 4 and check them"),
    "plan-experiment": ("plan_experiment", "plan an identification experiment (loads, pretension)"),
    "diagnose": ("diagnose", "which unmodelled effect explains the model-rig gap"),
    "simulate": ("simulate", "run a protocol on a simulated rig (testbed plant with effects)"),
    "sweep": ("sweep", "hole-geometry design sweep (workspace, stiffness, margins)"),
    "optimise": ("optimise", "hole-geometry optimisation (guaranteed workspace, stiffness, no collisions)"),
    "report": ("report", "design-study report (HTML + Markdown) of csjm sweep results"),
    "view": ("view", "interactive 3-D view of the rig at a pose (one offline HTML page)"),
    "export-mjcf": ("export_mjcf", "MuJoCo model (MJCF) of a rig"),
    "codegen": ("codegen", "C99 tension planner and K of a rig (no malloc, libm only)"),
}


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
