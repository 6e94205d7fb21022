"""The command line's process-level settings (``p3d_cli.cli.main``): what they leave behind."""

from __future__ import annotations

import gc
import subprocess
import sys

import pytest

from p3d_cli.cli import main


@pytest.fixture
def fresh_module():
    """A standard-library module nothing here has imported yet, removed again afterwards."""
    name = "colorsys"
    saved = sys.modules.pop(name, None)
    yield name
    sys.modules.pop(name, None)
    if saved is not None:
        sys.modules[name] = saved


def test_import_frozen_from_python_imports_and_leaves_the_collector_as_it_was(fresh_module):
    frozen = gc.get_freeze_count()
    main.import_frozen(fresh_module)
    assert fresh_module in sys.modules
    assert gc.isenabled()
    assert gc.get_freeze_count() == frozen  # a caller of cli keeps its own objects collectable


def test_import_frozen_keeps_a_paused_collector_paused(fresh_module):
    gc.disable()
    try:
        main.import_frozen(fresh_module)
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_import_frozen_leaves_a_missing_module_to_the_caller():
    main.import_frozen("p3d_no_such_module")  # the library's own import reports it
    assert "p3d_no_such_module" not in sys.modules
    assert gc.isenabled()


def test_in_the_program_import_frozen_freezes_what_start_up_made():
    code = ("import gc, sys; from p3d_cli.cli import main; main._whole_process = True; "
            "main.import_frozen('colorsys'); "
            "print(gc.get_freeze_count() > 10000, gc.isenabled(), 'colorsys' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True", "True"]


def test_usage_errors_are_one_line_whatever_click_s_version(monkeypatch):
    """Issue 24.3: click 8.1 (the declared minimum) has no NoArgsIsHelpError; naming it in an except
    clause turned every usage error into a traceback with exit 1."""
    import click
    from click.testing import CliRunner

    from p3d_cli.cli import main

    for present in (True, False):
        if not present:
            monkeypatch.delattr(click.exceptions, "NoArgsIsHelpError", raising=False)
            monkeypatch.setattr(main, "_NO_ARGS_IS_HELP", None)
        for args in (["props", "--nosuch"], ["nosuch"], ["props", "box", "--jobs", "0"]):
            result = CliRunner().invoke(main.cli, args)
            assert result.exit_code == 2, (present, args, result.output)
            assert result.stderr.count("\n") == 1 and result.stderr.startswith("p3d: error: ")
            assert ".;" not in result.stderr
