"""How p3d's values show themselves in Jupyter: a picture for shapes and meshes (``_repr_png_``),
the numbers and a thumbnail for results (``_repr_html_``).

The values call these from their display methods (``_repr_*_``): callbacks that Jupyter calls,
no part of the road from an input to a result, and the only place a value below ``render``
imports this module. Pictures are made through the package's public face (``p3d_cli.picture``),
as a user makes them, so that this module imports no part of the road below it. A result
whose input cannot be drawn again (an array given from Python, a file since moved) shows its
numbers alone.
"""

from __future__ import annotations

import base64
import html

#: Size of the pictures values show in a notebook.
THUMBNAIL = (480, 360)


def png_of(thing, show=()) -> bytes:
    """A PNG picture of anything ``p3d.render`` takes."""
    import p3d_cli

    return p3d_cli.picture(thing, show=show, size=THUMBNAIL).to_png()


def _thumbnail(source: str, show) -> str:
    """An ``<img>`` of ``source`` with ``show``, or "" when it cannot be drawn."""
    from p3d_cli.errors import P3DError

    if source in ("", "-", "<array>", "<stdin>"):
        return ""
    try:
        data = png_of(source, show)
    except P3DError:
        return ""
    return (f'<img src="data:image/png;base64,{base64.b64encode(data).decode("ascii")}" '
            f'width="{THUMBNAIL[0] // 2}" alt="{html.escape(source)}" style="float:right;margin-left:12px">')


def _number(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, str):
        return html.escape(value)
    if hasattr(value, "__len__"):
        return "(" + ", ".join(f"{float(v) + 0.0:.6g}" for v in value) + ")"
    if isinstance(value, float):
        return f"{value + 0.0:.6g}"
    return html.escape(str(value))


def _table(title: str, rows: list[tuple[str, object]], picture: str = "") -> str:
    body = "".join(f"<tr><td style='text-align:left'>{html.escape(k)}</td>"
                   f"<td style='text-align:left;font-family:monospace'>{_number(v)}</td></tr>" for k, v in rows)
    return (f"<div>{picture}<b>{html.escape(title)}</b><table>{body}</table>"
            f"<div style='clear:both'></div></div>")


def props_html(result) -> str:
    """A ``PropsResult`` as HTML: mass properties, units, warnings, and the part with its frame."""
    p, facts = result.properties, result.facts
    rows = [("faces", facts.faces), ("volume", p.volume), ("mass", p.mass), ("density", p.density),
            ("centre of mass", p.center_of_mass), ("principal moments", p.principal_moments)]
    if p.inertia is not None:
        rows += [(f"inertia row {i + 1}", p.inertia[i]) for i in range(3)]
    if facts.bounds is not None:
        rows.append(("size", facts.bounds.size))
    rows += [("warning", w) for w in result.warnings]
    units = (result.units or {}).get("system", "")
    title = f"{facts.source} ({result.method}{', ' + units if units else ''})"
    return _table(title, rows, _thumbnail(facts.source, "axes,inertia"))


def bounds_html(result) -> str:
    """A ``BoundsResult`` as HTML."""
    b = result.bounds
    rows = [("min", b.min), ("max", b.max), ("size", b.size), ("method", result.method)]
    return _table(result.source, rows, _thumbnail(result.source, "bounds"))


def check_html(result) -> str:
    """A ``CheckResult`` as HTML: the verdict, the counts, and the mesh with its defects."""
    r = result.report
    verdict = "ok" if result.ok else "FAILED " + ", ".join(result.failed)
    rows = [("verdict", verdict), ("faces", r.faces), ("shells", r.shells), ("boundary edges", r.boundary_edges),
            ("non-manifold edges", r.nonmanifold_edges), ("misoriented edges", r.misoriented_edges),
            ("non-manifold vertices", r.nonmanifold_vertices), ("degenerate faces", r.degenerate_faces),
            ("duplicate faces", r.duplicate_faces), ("volume", r.volume)]
    return _table(result.source, rows, _thumbnail(result.source, "defects"))
