"""The one assertion of the hostile-input tests: ``p3d props FILE`` ends in one error line."""

from __future__ import annotations

from helpers.cli import run as run_p3d


def one_error(path, match: str) -> str:
    """Run ``p3d props path``: exit status 2, one ``p3d: error:`` line holding ``match``, no
    traceback; the line."""
    run = run_p3d("props", path)
    lines = [line for line in run.output.splitlines() if line.strip()]
    assert run.exit_code == 2, run.output
    assert len(lines) == 1 and lines[0].startswith("p3d: error:") and "Traceback" not in run.output, run.output
    assert match in lines[0], lines[0]
    return lines[0]
