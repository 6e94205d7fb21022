"""The title line above a picture and the legend below it, in the built-in bitmap font.

Both sit in strips of their own, outside the drawing area, so that neither hides the part. The
legend lists each overlay drawn: a swatch in its colour (a line, a mark or a patch) and its
label, flowing left to right and onto more rows as the width requires.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.render.font import CELL_HEIGHT, CELL_WIDTH, draw_text, text_width

TEXT = (30, 30, 35)
MUTED = (105, 105, 115)
RULE = (215, 215, 222)
SWATCH = 22          # swatch width, in font pixels at scale 1 ... times the text scale / 2


@dataclass(frozen=True)
class Entry:
    """One legend entry: ``kind`` is ``line``, ``mark`` or ``patch``."""

    label: str
    colour: tuple[int, int, int]
    kind: str = "line"


def legend_entries(layers) -> list:
    """The legend's entries for ``layers``."""
    return [Entry(layer.label, layer.colour, _kind(layer)) for layer in layers]


def _kind(layer) -> str:
    if len(layer.faces):
        return "patch"
    return "mark" if len(layer.points) and not len(layer.segments) else "line"


def text_scale(width: int, height: int) -> int:
    """The font's scale for a picture: 2 at 800 x 600 and above, 1 for thumbnails."""
    return 2 if min(width / 800, height / 600) >= 0.75 else 1


def _fit(text: str, room: int, scale: int) -> str:
    """``text`` cut with ``...`` to fit ``room`` pixels."""
    most = max(room // (CELL_WIDTH * scale), 4)
    return text if len(text) <= most else text[:most - 3] + "..."


def layout(entries: list[Entry], width: int, scale: int) -> list[list[tuple[int, Entry, str]]]:
    """Rows of ``(x, entry, shown label)``, each row within ``width``."""
    pad = 8 * scale
    swatch = SWATCH * scale // 2 + 4 * scale
    rows: list[list[tuple[int, Entry, str]]] = [[]]
    x = pad
    for entry in entries:
        label = _fit(entry.label, width - 2 * pad - swatch, scale)
        need = swatch + text_width(label, scale)
        if rows[-1] and x + need > width - pad:
            rows.append([])
            x = pad
        rows[-1].append((x, entry, label))
        x += need + 6 * CELL_WIDTH * scale // 2
    return [row for row in rows if row]


def row_height(scale: int) -> int:
    return (CELL_HEIGHT + 4) * scale


def strip_height(rows: int, scale: int) -> int:
    """Height of a strip of ``rows`` text rows (0 for none)."""
    return 0 if rows == 0 else rows * row_height(scale) + 6 * scale


def draw_legend(image: np.ndarray, rows, top: int, scale: int) -> None:
    """Draw the rows of ``layout`` into ``image`` from pixel row ``top`` down, under a rule."""
    image[top:top + max(scale // 2, 1)] = RULE
    y = top + 4 * scale
    for row in rows:
        for x, entry, label in row:
            _swatch(image, entry, x, y, scale)
            draw_text(image, label, x + SWATCH * scale // 2 + 4 * scale, y + 2 * scale, TEXT, scale)
        y += row_height(scale)


def _swatch(image: np.ndarray, entry: Entry, x: int, y: int, scale: int) -> None:
    w = SWATCH * scale // 2
    middle = y + 2 * scale + (CELL_HEIGHT * scale) // 2 - scale
    if entry.kind == "line":
        image[middle - scale:middle + scale, x:x + w] = entry.colour
    elif entry.kind == "mark":
        s = 3 * scale
        c = x + w // 2
        image[middle - s - 1:middle + s + 1, c - s - 1:c + s + 1] = (40, 40, 40)
        image[middle - s:middle + s, c - s:c + s] = entry.colour
    else:
        image[middle - 3 * scale:middle + 3 * scale, x:x + w] = entry.colour


def draw_title(image: np.ndarray, text: str, scale: int, note: str = "") -> None:
    """The title at the top left, ``note`` (muted) at the top right if it fits beside it."""
    width = image.shape[1]
    pad = 8 * scale
    shown = _fit(text, width - 2 * pad, scale)
    draw_text(image, shown, pad, 3 * scale, TEXT, scale)
    if note and text_width(shown, scale) + text_width(note, scale) + 4 * pad <= width:
        draw_text(image, note, width - pad - text_width(note, scale), 3 * scale, MUTED, scale)
