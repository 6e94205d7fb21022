"""Start-up: `p3d --help` lists the commands without importing them (issue 24 item 5)."""

from __future__ import annotations

import subprocess
import sys

import click
from click.testing import CliRunner

from p3d_cli.cli import main


def test_the_summaries_are_the_commands_own_first_sentences():
    ctx = click.Context(main.cli)
    names = main.cli.list_commands(ctx)
    assert sorted(main.SUMMARIES) == names, "a command without a summary in p3d_cli/cli/main.py SUMMARIES"
    for name in names:
        assert main.cli.get_command(ctx, name).get_short_help_str(500) == main.SUMMARIES[name], name


def test_help_lists_every_command_as_click_would():
    shown = CliRunner().invoke(main.cli, ["--help"]).stdout
    for name in main.SUMMARIES:
        assert f"  {name}  " in shown


def test_help_imports_no_command_and_no_numpy():
    code = ("import sys; from p3d_cli.cli.main import cli; cli.main(['--help'], standalone_mode=False); "
            "print(sorted(m for m in sys.modules if m.startswith(('numpy', 'yaml', 'p3d_cli.cli.', 'p3d_cli.measure'))))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] == "['p3d_cli.cli.main']"
