"""SVG pictures: the shaded surface as an embedded PNG, everything drawn over it as vectors.

What an SVG from ``p3d render`` holds (docs/render.md, "SVG"):

- one ``<image>``: the shaded, z-buffered surface (the same pixels as the PNG's drawing area),
  PNG-encoded inline (``data:`` URI), so the file stands alone;
- one group per overlay (``<g class="boundary">``, ``axis1``, ``bounds``, ...): its visible
  stretches as solid paths, its hidden ones as thin dashed half-transparent paths, its marks as
  squares, its tags as text: lines stay sharp at any zoom and can be restyled or counted;
- the title and the legend as text and shapes.

Hidden-line decisions are the raster's (the same depth test as the PNG), made at the picture's
pixel size.
"""

from __future__ import annotations

import base64
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from p3d_cli.render import legend
from p3d_cli.render.draw import DASH, HIDDEN_ALPHA
from p3d_cli.render.font import CELL_HEIGHT
from p3d_cli.render.png import encode_png

FONT = "DejaVu Sans Mono, Menlo, Consolas, monospace"


def _rgb(colour) -> str:
    return "#%02x%02x%02x" % tuple(int(c) for c in colour)


def _num(x: float) -> str:
    return f"{float(x):.2f}".rstrip("0").rstrip(".")


def _text(x: float, y: float, text: str, colour, scale: int, anchor: str = "start") -> str:
    # Font size: the bitmap font's cell height; y is the top of its cell, the baseline 7/10 down.
    size = CELL_HEIGHT * scale * 0.95
    return (f'<text x="{_num(x)}" y="{_num(y + 0.72 * CELL_HEIGHT * scale)}" font-family={quoteattr(FONT)} '
            f'font-size="{_num(size)}" fill="{_rgb(colour)}" text-anchor="{anchor}">{escape(text)}</text>')


def picture_svg(picture) -> str:
    """The SVG document of a ``Picture``."""
    width, height = picture.size
    top, rows = picture.area
    surface = encode_png(np.ascontiguousarray(picture.surface[top:top + rows]))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}">',
           f"<title>{escape(picture.title)}</title>",
           "<desc>p3d render: shaded surface as an embedded PNG; overlays, title and legend as vectors</desc>",
           f'<rect width="{width}" height="{height}" fill="#ffffff"/>',
           f'<image x="0" y="{top}" width="{width}" height="{rows}" '
           f'href="data:image/png;base64,{base64.b64encode(surface).decode("ascii")}"/>']
    for stroke in picture.strokes:
        out.append(_stroke(stroke))
    scale = picture.text_scale
    out.append(_text(8 * scale, 3 * scale, picture.title, legend.TEXT, scale))
    if picture.note:
        out.append(_text(width - 8 * scale, 3 * scale, picture.note, legend.MUTED, scale, "end"))
    out += _legend(picture)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _stroke(stroke) -> str:
    colour = _rgb(stroke.colour)
    cls = f'class="{stroke.key}{"" if stroke.visible else " hidden"}"'
    if stroke.text:
        x, y = stroke.runs[0, :2]
        return _text(x, y, stroke.text, stroke.colour, max(1, int(round(stroke.width / CELL_HEIGHT))))
    runs = stroke.runs
    if np.all(runs[:, :2] == runs[:, 2:]):                       # marks
        half = stroke.width / 2
        opacity = "" if stroke.visible else f' fill-opacity="{HIDDEN_ALPHA}"'
        rim = ' stroke="#282828" stroke-width="1"' if stroke.visible else ""
        body = "".join(f'<rect x="{_num(x - half)}" y="{_num(y - half)}" width="{_num(2 * half)}" '
                       f'height="{_num(2 * half)}"/>' for x, y in runs[:, :2])
        return f'<g {cls} fill="{colour}"{opacity}{rim}>{body}</g>'
    path = " ".join(f"M{_num(a)} {_num(b)}L{_num(c)} {_num(d)}" for a, b, c, d in runs)
    if stroke.visible:
        style = f'stroke-width="{_num(stroke.width)}" stroke-linecap="square"'
    else:
        style = f'stroke-width="1" stroke-dasharray="{DASH} {DASH}" stroke-opacity="{HIDDEN_ALPHA}"'
    return f'<path {cls} fill="none" stroke="{colour}" {style} d="{path}"/>'


def _legend(picture) -> list[str]:
    scale = picture.text_scale
    width = picture.size[0]
    rows = legend.layout(legend.legend_entries(picture.layers), width, scale)
    if not rows:
        return []
    top = picture.legend_top
    out = [f'<rect x="0" y="{top}" width="{width}" height="{max(scale // 2, 1)}" fill="{_rgb(legend.RULE)}"/>']
    y = top + 4 * scale
    swatch = legend.SWATCH * scale // 2
    for row in rows:
        for x, entry, label in row:
            middle = y + 2 * scale + (CELL_HEIGHT * scale) // 2 - scale
            if entry.kind == "line":
                out.append(f'<rect x="{x}" y="{middle - scale}" width="{swatch}" height="{2 * scale}" '
                           f'fill="{_rgb(entry.colour)}"/>')
            else:
                s = 3 * scale if entry.kind == "mark" else swatch // 2
                out.append(f'<rect x="{x + swatch // 2 - s}" y="{middle - 3 * scale}" width="{2 * s}" '
                           f'height="{6 * scale}" fill="{_rgb(entry.colour)}"/>')
            out.append(_text(x + swatch + 4 * scale, y + 2 * scale, label, legend.TEXT, scale))
        y += legend.row_height(scale)
    return out
