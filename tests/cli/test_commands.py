"""The command table that lets ``csjm`` import only the command it runs."""

import argparse
import importlib
import subprocess
import sys

from csjm_opt import cli
from csjm_opt.cli.commands import COMMANDS


def _registered_by(module: str) -> set[str]:
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    importlib.import_module(f"csjm_opt.cli.{module}").register(sub)
    return set(sub.choices)


def test_table_names_exactly_the_commands_each_module_registers():
    for module in {m for m, _ in COMMANDS.values()}:
        assert _registered_by(module) == {n for n, (m, _) in COMMANDS.items() if m == module}


def test_full_parser_lists_the_commands_in_table_order():
    names = list(cli.build_parser()._subparsers._group_actions[0].choices)
    assert names == list(COMMANDS)


def test_help_imports_no_command_module_and_no_heavy_library():
    code = ("import sys\nfrom csjm_opt.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "heavy = [m for m in ('scipy', 'numba', 'casadi', 'mujoco', 'matplotlib', 'qpsolvers')"
            " if m in sys.modules]\n"
            "cmds = [m for m in sys.modules if m.startswith('csjm_opt.cli.') and m.rsplit('.', 1)[1] not in"
            " ('app', 'commands', '_options')]\n"
            "print(heavy, cmds, file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stderr.strip() == "[] []"
    for name in COMMANDS:
        assert name in out.stdout


def test_one_command_imports_only_its_own_module():
    code = ("import sys\nfrom csjm_opt.cli import main\n"
            "try:\n    main(['sweep', '--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('csjm_opt.cli.')), file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = {m.rsplit(".", 1)[1] for m in eval(out.stderr)}
    assert "sweep" in loaded and not loaded & {"diagnose", "simulate", "codegen", "identify"}
