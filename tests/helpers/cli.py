"""The one command-line runner of the tests: ``run("props", path, "--json")``.

Each argument is passed as ``str(arg)``, so paths and numbers may be given as they are. Click's
``CliRunner`` with its defaults: ``result.stdout`` and ``result.stderr`` apart, ``result.output``
both as a terminal would show them, exceptions caught into ``result.exception``. Keywords go to
``CliRunner.invoke`` (``input``, ``env``, ``catch_exceptions``, ...)."""

from __future__ import annotations

from click.testing import CliRunner, Result

from p3d_cli.cli.main import cli


def run(*args, input=None, **kw) -> Result:
    """``p3d ARGS...`` in process; the click ``Result``."""
    return CliRunner().invoke(cli, [str(a) for a in args], input=input, **kw)
