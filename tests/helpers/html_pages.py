"""Reading report pages back: what a page would load, and the colours of its pictures."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np


class Resources(HTMLParser):
    """Every URL the page would load (src, href, url(...)), and its tags."""

    def __init__(self):
        super().__init__()
        self.urls, self.tags = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.urls += [v for k, v in attrs if k in ("src", "href", "srcset", "data") and v]


def assert_stands_alone(page: str, folder: Path) -> list[str]:
    """No script, stylesheet link, ``url(...)`` or address with a scheme or host; every URL a
    file in ``folder``. Returns the URLs."""
    parser = Resources()
    parser.feed(page)
    assert "script" not in parser.tags and "link" not in parser.tags
    assert not re.search(r"url\(", page)
    assert not re.search(r"(?i)\b(https?|ftp)://", page)
    for url in parser.urls:
        assert "://" not in url and not url.startswith("//"), url
        assert (folder / url).is_file(), url
    return parser.urls


def drawing(pixels: np.ndarray, rule=(215, 215, 222)) -> np.ndarray:
    """The pixels above the legend (its rule is the first row all of one colour ``rule``)."""
    rows = np.flatnonzero(np.all(pixels == rule, axis=(1, 2)))
    return pixels if not len(rows) else pixels[:rows[0]]


def mask(pixels: np.ndarray, colour) -> np.ndarray:
    return np.all(pixels == np.asarray(colour, dtype=np.uint8), axis=-1)


def extent(m: np.ndarray) -> tuple[int, int, int, int]:
    """Left, right, top, bottom of a mask's pixels."""
    rows, cols = np.nonzero(m)
    return int(cols.min()), int(cols.max()), int(rows.min()), int(rows.max())
