"""Report pages with pictures: an HTML page for a CI artifact, Markdown for a GitHub job summary.

One row per input: its verdict, why it failed, its counts and numbers, and its picture (the
defects drawn for ``p3d check``; the principal frame for ``p3d props``; the bounds for ``p3d
bounds``). Rows that failed or could not be read come first, then the rest, each group in input
order. The HTML page is self-contained: inline CSS, no script, no font or image from the
network; the pictures are PNG files in ``images/`` beside it. The Markdown uses the same
pictures, written beside it (docs/render.md, "Reports", says what GitHub shows of them).

The pictures are made when the pages are written, from the inputs as named: an input that
cannot be drawn again gets its row without a picture and a note why.
"""

from __future__ import annotations

import html
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from p3d_cli.errors import P3DError

#: Size of each input's picture in the pages.
PICTURE_SIZE = (640, 480)
#: What each command's pictures show.
OVERLAYS = {"p3d check": "defects", "p3d props": "axes,inertia", "p3d bounds": "bounds"}
#: Counts of a ``p3d check`` row, in order: (record key, column heading).
CHECK_COUNTS = (("faces", "faces"), ("shells", "shells"), ("boundary_edges", "boundary edges"),
                ("nonmanifold_edges", "non-manifold edges"), ("misoriented_edges", "misoriented edges"),
                ("nonmanifold_vertices", "non-manifold vertices"), ("degenerate_faces", "degenerate faces"),
                ("duplicate_faces", "duplicate faces"), ("volume", "volume"))
_ORDER = {"errored": 0, "failed": 1, "warned": 2, "ok": 3, "skipped": 4, "frame": 4}
#: How the tally names each state (``frame``: a robot link that is a massless frame).
_STATES = ("ok", "warned", "failed", "errored", "skipped", "frame")


@dataclass(frozen=True)
class Row:
    """One input's line of a report: the verdict the command reached, and what the page adds.

    Attributes
    ----------
    source : str
    state : str
        ``ok``, ``warned``, ``failed``, ``errored`` or ``skipped`` (a robot link: ``frame``).
    failures, warnings : tuple of (code, text)
    numbers : dict
        Named counts and quantities shown beside the picture; a tuple value fills the columns
        ``html_page`` names (one value spans them).
    picture : bytes or None
        PNG.
    note : str
        Why there is no picture, if there is none.
    """

    source: str
    state: str
    failures: tuple = ()
    warnings: tuple = ()
    numbers: dict = field(default_factory=dict)
    picture: bytes | None = None
    note: str = ""


def with_picture(row: Row, command: str, size=PICTURE_SIZE) -> Row:
    """``row`` with its input's picture and numbers (a row not done, or skipped, as it is)."""
    from dataclasses import replace

    from p3d_cli.render.picture import picture

    if row.state in ("errored", "skipped"):
        return row
    try:
        numbers = _numbers(row.source, command)
        drawn = picture(row.source, show=OVERLAYS.get(command, ""), size=size, title=os.path.basename(row.source))
        return replace(row, numbers=numbers, picture=drawn.to_png())
    except P3DError as error:
        return replace(row, note=f"no picture: {error.message}")


def _numbers(source: str, command: str) -> dict:
    """The counts of ``p3d check`` or the mass properties of ``p3d props``/``bounds`` (raises
    ``P3DError`` as those do)."""
    from p3d_cli import measure

    if command == "p3d check":
        report = measure.check(source).report
        return {heading: getattr(report, key) for key, heading in CHECK_COUNTS}
    result = measure.props(source)
    props, bounds = result.properties, result.facts.bounds
    out: dict[str, object] = {"faces": result.facts.faces, "volume": props.volume, "mass (density 1)": props.mass}
    if props.center_of_mass is not None:
        out["centre of mass"] = _vector(props.center_of_mass)
        out["principal moments"] = _vector(props.principal_moments)
    if bounds is not None:
        out["size"] = _vector(bounds.size)
    return out


def _vector(values) -> str:
    return "(" + ", ".join(f"{float(v) + 0.0:.6g}" for v in values) + ")"


def _shown(value) -> str:
    if isinstance(value, float):
        return f"{value + 0.0:.6g}"
    if isinstance(value, int):
        return f"{value:,}"
    return str(value)


def ordered(rows: list[Row]) -> list[Row]:
    """Failed and unreadable inputs first, then warned, ok and skipped; input order within each."""
    return sorted(rows, key=lambda r: _ORDER.get(r.state, 5))


def image_name(index: int, source: str) -> str:
    """A file name for an input's picture: its position, then its name made safe."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", os.path.basename(source) or "input")[:60]
    return f"{index:04d}-{stem}.png"


def tally_line(command: str, rows: list[Row], noun: str = "input") -> str:
    counts: dict[str, int] = {}
    for row in rows:
        counts[row.state] = counts.get(row.state, 0) + 1
    parts = [f"{counts[s]} {s}" if s != "frame" else f"{counts[s]} massless frame{'s' if counts[s] != 1 else ''}"
             for s in _STATES if counts.get(s)]
    return f"{command}: {len(rows)} {noun}{'s' if len(rows) != 1 else ''}" + (": " + ", ".join(parts) if parts else "")


_CSS = """
body{font:14px/1.45 system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:24px;color:#1d1d22;background:#fff}
h1{font-size:20px;margin:0 0 4px} p.tally{color:#555;margin:0 0 18px}
table.rows{border-collapse:collapse;width:100%} table.rows>tbody>tr{border-top:1px solid #ddd}
td{vertical-align:top;padding:10px 12px} td.picture img{max-width:100%;height:auto;border:1px solid #e4e4ea}
td.picture{width:50%} td.side{white-space:nowrap}
table.numbers th{font-weight:600;color:#555;padding:1px 10px 1px 0}
.state{display:inline-block;padding:1px 8px;border-radius:10px;font-weight:600;font-size:12px;color:#fff}
.ok{background:#2e7d32}.warned{background:#b26a00}.failed{background:#c62828}.errored{background:#6a1b9a}
.skipped{background:#757575}.frame{background:#546e7a}
.source{font-family:ui-monospace,Menlo,Consolas,monospace;word-break:break-all}
table.numbers td{padding:1px 10px 1px 0} table.numbers td.n{text-align:right;font-variant-numeric:tabular-nums}
ul{margin:6px 0;padding-left:18px} .note{color:#777} div.intro{margin:0 0 14px;max-width:60em}
.swatch{display:inline-block;width:22px;height:4px;vertical-align:middle;margin-right:4px}
"""


def html_page(command: str, rows: list[Row], images: dict[int, str], *, noun: str = "input",
              intro: str = "", columns: tuple[str, ...] = ()) -> str:
    """The HTML page of ``rows`` (already ordered); ``images`` maps a row's index to its picture's
    relative path. ``noun`` names what a row is in the tally; ``intro`` is HTML put above the
    rows (its maker escapes what it quotes); ``columns`` heads the numbers' value columns (a
    tuple value fills them, side by side)."""
    title = html.escape(tally_line(command, rows, noun))
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{html.escape(command)} report</title><style>{_CSS}</style></head><body>",
           f"<h1>{html.escape(command)} report</h1>", f'<p class="tally">{title}</p>']
    if intro:
        out.append(f'<div class="intro">{intro}</div>')
    out.append('<table class="rows"><tbody>')
    for i, row in enumerate(rows):
        out.append(f'<tr id="row-{i}"><td class="about">')
        out.append(f'<div class="source">{html.escape(row.source)}</div>')
        out.append(f'<span class="state {row.state}">{html.escape(row.state)}</span>')
        items = [f"[{html.escape(c)}] {html.escape(t)}" for c, t in row.failures]
        items += [f"warning [{html.escape(c)}] {html.escape(t)}" for c, t in row.warnings]
        if items:
            out.append("<ul>" + "".join(f"<li>{item}</li>" for item in items) + "</ul>")
        if row.numbers:
            out.append(_numbers_table(row.numbers, columns))
        if row.note:
            out.append(f'<p class="note">{html.escape(row.note)}</p>')
        out.append('</td><td class="picture">')
        if i in images:
            alt = html.escape(f"picture of {row.source}")
            out.append(f'<a href="{html.escape(images[i])}"><img src="{html.escape(images[i])}" alt="{alt}" '
                       f'width="{PICTURE_SIZE[0]}" height="{PICTURE_SIZE[1]}" loading="lazy"></a>')
        out.append("</td></tr>")
    out.append("</tbody></table></body></html>")
    return "\n".join(out) + "\n"


def _numbers_table(numbers: dict, columns: tuple[str, ...]) -> str:
    span = max(len(columns), 1)
    head = "" if not columns else "<tr><td></td>" + "".join(f'<th class="n">{html.escape(c)}</th>'
                                                           for c in columns) + "</tr>"
    cells = []
    for key, value in numbers.items():
        if isinstance(value, tuple):
            row = "".join(f'<td class="n side">{html.escape(_shown(v))}</td>' for v in value)
        else:
            wide = f' colspan="{span}"' if span > 1 else ""
            row = f'<td class="n"{wide}>{html.escape(_shown(value))}</td>'
        cells.append(f"<tr><td>{html.escape(key)}</td>{row}</tr>")
    return '<table class="numbers">' + head + "".join(cells) + "</table>"


def markdown_summary(command: str, rows: list[Row], images: dict[int, str]) -> str:
    """GitHub-flavoured Markdown: a heading with the tally, a table of verdicts and numbers, and
    each input's picture under its name."""
    keys: list[str] = []
    for row in rows:
        keys += [k for k in row.numbers if k not in keys]
    cell = lambda text: str(text).replace("|", "\\|").replace("\n", " ")
    out = [f"### {cell(tally_line(command, rows))}", "",
           "| input | verdict | " + " | ".join(cell(k) for k in keys) + " |",
           "|---|---|" + "---:|" * len(keys)]
    for row in rows:
        why = "; ".join(text for _, text in row.failures)
        verdict = row.state + (f": {why}" if why else "")
        values = " | ".join(cell(_shown(row.numbers[k])) if k in row.numbers else "" for k in keys)
        out.append(f"| `{cell(row.source)}` | {cell(verdict)} | {values} |")
    pictured = [(i, row) for i, row in enumerate(rows) if i in images]
    if pictured:
        out += ["", "<details><summary>pictures</summary>", ""]
        for i, row in pictured:
            out += [f"**{cell(row.source)}** ({row.state})", "", f"![{cell(row.source)}]({images[i]})", ""]
        out.append("</details>")
    return "\n".join(out) + "\n"


def write_pages(command: str, rows: list[Row], *, html_dir: str | None = None, summary: str | None = None,
                inputs=()) -> None:
    """Write the HTML page (``html_dir/index.html``, pictures in ``html_dir/images/``) and/or the
    Markdown summary (appended to ``summary``, pictures in ``<summary>-images/`` beside it), each
    file whole or not at all.

    Raises
    ------
    OutputError
        A file cannot be written, or would replace one of ``inputs``.
    """
    from p3d_cli.io.atomic import write_bytes

    rows = ordered([with_picture(row, command) for row in rows])
    if html_dir is not None:
        write_html(html_dir, command, rows, inputs=inputs)
    if summary is not None:
        target = Path(summary)
        pictures = target.parent / f"{target.name}-images"
        images = {}
        if any(row.picture is not None for row in rows):
            _make_folder(pictures)
        for i, row in enumerate(rows):
            if row.picture is not None:
                name = image_name(i, row.source)
                write_bytes(pictures / name, row.picture, inputs=inputs, what="a summary picture")
                images[i] = f"{pictures.name}/{name}"
        before = target.read_bytes() if target.is_file() else b""
        text = markdown_summary(command, rows, images).encode("utf-8")
        separator = b"\n" if before and not before.endswith(b"\n") else b""
        write_bytes(target, before + separator + text, inputs=inputs, what="the job summary")


def write_html(html_dir: str | os.PathLike, command: str, rows: list[Row], *, inputs=(), noun: str = "input",
               intro: str = "", columns: tuple[str, ...] = ()) -> Path:
    """Write ``html_dir/index.html`` for ``rows`` (already ordered, with their pictures) and the
    pictures in ``html_dir/images/``, each file whole or not at all; returns the page's path.

    Raises
    ------
    OutputError
        A file cannot be written, or would replace one of ``inputs``.
    """
    from p3d_cli.io.atomic import write_bytes

    folder = Path(html_dir)
    _make_folder(folder / "images")
    images = {}
    for i, row in enumerate(rows):
        if row.picture is not None:
            name = image_name(i, row.source)
            write_bytes(folder / "images" / name, row.picture, inputs=inputs, what="a report picture")
            images[i] = f"images/{name}"
    page = html_page(command, rows, images, noun=noun, intro=intro, columns=columns)
    return write_bytes(folder / "index.html", page.encode("utf-8"), inputs=inputs, what="the HTML report")


def _make_folder(folder: Path) -> None:
    from p3d_cli.errors import OutputError

    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(str(folder), f"cannot make the report folder: {error.strerror}",
                          "check the path and its permissions") from None
