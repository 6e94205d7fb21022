"""Reports CI systems read, for any command that runs over inputs: JUnit XML, GitHub workflow
annotations, and a JSON summary of the counts.

A command's run (``p3d_cli.cli.reporting.Batch``) records one ``Entry`` per input; at its end
``write_reports`` writes what ``--report`` and ``--summary`` asked for:

- ``--report junit:FILE``: one ``<testcase>`` per input (classname ``p3d.<command>``, name the
  input), a ``<failure>`` for a failed requirement, an ``<error>`` for an input that could not
  be read, ``<skipped>`` for a file a directory search passed over; warnings of a passing input
  in its ``<system-out>``. The layout of the JUnit schema Jenkins and GitLab read.
- ``--report github`` (standard output) or ``github:FILE``: workflow commands, one line each,
  ``::error file=PATH,title=p3d check::MESSAGE`` and ``::warning file=...::``.
- ``--report html:DIR`` and ``github-summary:FILE``: a page with each input's picture (HTML,
  or Markdown appended to a GitHub job summary), by ``p3d_cli.render.pages``.
- ``--summary json:FILE``: ``{"schema_version", "command", "inputs", "ok", "warned", "failed",
  "errored", "not_done", "skipped", "skipped_by_extension", "warnings_by_code", "exit_status",
  "complete"}``; ``not_done`` counts the errored inputs a batch ended part way never reached (a
  lost Dask scheduler), and ``complete`` is false then.

Every report file is written whole or not at all (``p3d_cli.io.atomic``), and a report that
would overwrite one of the run's inputs is refused before any input is read. Before the run
starts, each report file is replaced by an *incomplete* one (``prepare_reports``): a JUnit
suite with one ``<error>``, a GitHub ``::error`` line, a summary with ``"complete": false``;
so a run that is killed or interrupted never leaves the previous run's "all passed" for CI
to publish. The finished run replaces it with the real report.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from html import escape
from pathlib import Path

import click

from p3d_cli.cli import output
from p3d_cli.errors import UsageError

#: The states of one input, in the order of the summary.
STATES = ("ok", "warned", "failed", "errored", "skipped")


@dataclass(frozen=True)
class Entry:
    """One input's verdict, for reports.

    Attributes
    ----------
    source : str
    state : str
        One of ``STATES``.
    failures : tuple of (code, text)
        Why it failed (``failed``) or could not be done (``errored``: code ``error``).
    warnings : tuple of (code, text)
        Its warnings that were not ignored.
    """

    source: str
    state: str
    failures: tuple[tuple[str, str], ...] = ()
    warnings: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class ReportOptions:
    """What ``--report`` and ``--summary`` asked for: (kind, path or None for stdout) pairs."""

    reports: tuple[tuple[str, str | None], ...] = ()
    summary: str | None = None

    @property
    def wanted(self) -> bool:
        return bool(self.reports or self.summary)


def parse_reports(values, summary: str | None) -> ReportOptions:
    """``--report`` values (``junit:FILE``, ``github``, ``github:FILE``) and ``--summary json:FILE``.

    Raises
    ------
    UsageError
    """
    reports = []
    for value in values:
        kind, _, path = value.partition(":")
        if kind == "junit" and path:
            reports.append(("junit", path))
        elif kind == "github":
            reports.append(("github", path or None))
        elif kind in ("html", "github-summary") and path:
            reports.append((kind, path))
        else:
            raise UsageError("--report", f"{value!r} is not a report",
                             "use junit:FILE, github, github:FILE, html:DIR or github-summary:FILE")
    if summary is not None:
        kind, _, path = summary.partition(":")
        if kind != "json" or not path:
            raise UsageError("--summary", f"{summary!r} is not a summary", "use json:FILE")
        summary = path
    return ReportOptions(tuple(reports), summary)


def counts(entries) -> dict[str, int]:
    """How many entries are in each of ``STATES``."""
    out = dict.fromkeys(STATES, 0)
    for entry in entries:
        out[entry.state] += 1
    return out


#: The message of a report a run has not finished (yet): killed, interrupted, or still running.
INCOMPLETE = "the run did not finish (interrupted, killed, or still running); this report is not a result"


def prepare_reports(options: ReportOptions, command: str, inputs=()) -> None:
    """Before a run: refuse a report path that is one of ``inputs`` (or read-only, hard-linked,
    in a missing folder), then replace every report file with an incomplete one.

    Raises
    ------
    OutputError
    """
    from p3d_cli.io import atomic

    inputs = [path for path in inputs if isinstance(path, str) and path != "-"]
    for kind, path in _files(options):
        atomic.destination(_page_file(kind, path), inputs=inputs, what=_what(kind))
    entry = Entry("(run)", "errored", (("incomplete", INCOMPLETE),))
    for kind, path in _files(options):
        if kind == "github-summary":
            # Appended to, never replaced: a run that dies appends nothing, so there is no
            # earlier verdict of this run's to stand in for it.
            continue
        if kind == "html":
            if Path(path).is_dir():
                _write(str(_page_file(kind, path)), _incomplete_page(command), kind, inputs)
            continue
        if kind == "junit":
            text = junit_xml(command, [entry])
        elif kind == "github":
            text = "".join(line + "\n" for line in github_lines(command, [entry]))
        else:
            text = output.formatted("summary", {"command": command, "complete": False, "exit_status": None},
                                    "json") + "\n"
        _write(path, text, kind, inputs)


def _files(options: ReportOptions) -> list[tuple[str, str]]:
    """``(kind, path)`` of every report written to a file (``summary`` for ``--summary``)."""
    out = [(kind, path) for kind, path in options.reports if path is not None]
    return out + ([("summary", options.summary)] if options.summary is not None else [])


def _what(kind: str) -> str:
    return {"junit": "the JUnit report", "github": "the GitHub report", "summary": "the summary",
            "html": "the HTML report", "github-summary": "the job summary"}[kind]


def _page_file(kind: str, path: str) -> Path:
    """The file a report kind writes at ``path``: ``html:DIR`` writes ``DIR/index.html`` (a DIR
    that does not exist yet is made by the page's writer, so it is checked as a new path)."""
    return Path(path) / "index.html" if kind == "html" and Path(path).is_dir() else Path(path)


def _incomplete_page(command: str) -> str:
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>p3d {escape(command)}: incomplete</title>"
            f"</head><body><h1>p3d {escape(command)}</h1><p>{escape(INCOMPLETE)}</p></body></html>\n")


def write_reports(options: ReportOptions, command: str, entries, skipped: dict[str, list[str]],
                  status: int, seconds: float = 0.0, inputs=()) -> None:
    """Write every report ``options`` asks for (each file replaced whole, never over an input)."""
    inputs = [path for path in inputs if isinstance(path, str) and path != "-"]
    entries = list(entries)
    skipped_entries = [Entry(path, "skipped", (("skipped", f"p3d does not read {ext or 'extensionless'} files"),))
                       for ext, paths in sorted(skipped.items()) for path in paths]
    pages = {kind: path for kind, path in options.reports if kind in ("html", "github-summary")}
    if pages:
        from p3d_cli.render.pages import Row, write_pages

        write_pages(command, [Row(e.source, e.state, e.failures, e.warnings) for e in entries],
                    html_dir=pages.get("html"), summary=pages.get("github-summary"), inputs=[e.source for e in entries])
    for kind, path in options.reports:
        if kind in pages:
            continue
        if kind == "junit":
            _write(path, junit_xml(command, entries + skipped_entries, seconds), kind, inputs)
        else:
            text = "".join(line + "\n" for line in github_lines(command, entries))
            if path is None:
                click.echo(text, nl=False)
            else:
                _write(path, text, kind, inputs)
    if options.summary is not None:
        record = summary_record(command, entries, skipped, status)
        _write(options.summary, output.formatted("summary", record, "json") + "\n", "summary", inputs)


def summary_record(command: str, entries, skipped: dict[str, list[str]], status: int) -> dict:
    """The ``--summary json:FILE`` object."""
    tally = counts(entries)
    by_code: dict[str, int] = {}
    for entry in entries:
        for code, _ in entry.warnings:
            by_code[code] = by_code.get(code, 0) + 1
    not_done = sum(1 for entry in entries if entry.failures[:1] and entry.failures[0][0] == "not-done")
    return {"schema_version": output.SCHEMA_VERSION, "command": command, "inputs": len(entries),
            **{k: tally[k] for k in STATES[:-1]}, "not_done": not_done,
            "skipped": sum(len(p) for p in skipped.values()),
            "skipped_by_extension": {ext: len(p) for ext, p in sorted(skipped.items())},
            "warnings_by_code": dict(sorted(by_code.items())), "exit_status": status, "complete": not not_done}


def junit_xml(command: str, entries, seconds: float = 0.0) -> str:
    """The JUnit XML report: one ``<testsuite>`` for the command, one ``<testcase>`` per entry
    (the batch's wall time on the suite; inputs run in parallel have no time of their own)."""
    import xml.etree.ElementTree as ET
    tally = counts(entries)
    suite_name = command
    # The skipped count goes on the suite only: Jenkins' schema has no such attribute on testsuites.
    suites = ET.Element("testsuites", name=suite_name, tests=str(len(entries)), failures=str(tally["failed"]),
                        errors=str(tally["errored"]), time=_seconds(seconds))
    suite = ET.SubElement(suites, "testsuite", name=suite_name, tests=str(len(entries)),
                          failures=str(tally["failed"]), errors=str(tally["errored"]),
                          skipped=str(tally["skipped"]), time=_seconds(seconds),
                          timestamp=time.strftime("%Y-%m-%dT%H:%M:%S"))
    classname = command.replace(" ", ".")
    for entry in entries:
        case = ET.SubElement(suite, "testcase", name=_text(entry.source), classname=classname)
        tag = {"failed": "failure", "errored": "error", "skipped": "skipped"}.get(entry.state)
        if tag is not None:
            first = entry.failures[0] if entry.failures else ("", "")
            element = ET.SubElement(case, tag, message=_text(first[1]).splitlines()[0] if first[1] else "")
            if tag != "skipped":
                element.set("type", first[0])
                element.text = _text("\n".join(f"[{code}] {text}" for code, text in entry.failures))
        if entry.warnings:
            ET.SubElement(case, "system-out").text = _text(
                "\n".join(f"warning [{code}] {text}" for code, text in entry.warnings))
    ET.indent(suites)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(suites, encoding="unicode") + "\n"


def github_lines(command: str, entries) -> list[str]:
    """GitHub Actions workflow commands: ``::error`` per failure or error, ``::warning`` per warning."""
    lines = []
    for entry in entries:
        file = _property(entry.source)
        for code, text in entry.failures:
            lines.append(f"::error file={file},title={_property(f'{command} [{code}]')}::{_data(text)}")
        for code, text in entry.warnings:
            lines.append(f"::warning file={file},title={_property(f'{command} [{code}]')}::{_data(text)}")
    return lines


def _data(text: str) -> str:
    # The escapes of the runner's command parser (actions/toolkit, command.ts: escapeData).
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _property(text: str) -> str:
    # Property values also escape ':' and ',' (command.ts: escapeProperty).
    return _data(text).replace(":", "%3A").replace(",", "%2C")


def _text(text: str) -> str:
    """Text XML 1.0 can hold: control characters and undecodable bytes as ``\\xNN``."""
    from p3d_cli.cli.output import shown_name

    keep = "\n\t"
    return "".join(ch if ch in keep else shown_name(ch) for ch in text)


def _seconds(seconds: float) -> str:
    return f"{seconds:.3f}"


def _write(path: str, text: str, kind: str, inputs=()) -> None:
    """``text`` as UTF-8 to ``path``, whole or not at all (``p3d_cli.io.atomic``)."""
    from p3d_cli.io import atomic

    atomic.write_bytes(path, text.encode("utf-8", "surrogateescape"), inputs=inputs, what=_what(kind))


__all__ = ["Entry", "INCOMPLETE", "ReportOptions", "STATES", "counts", "github_lines", "junit_xml", "parse_reports",
           "prepare_reports", "summary_record", "write_reports"]
