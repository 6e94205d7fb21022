"""The command line's shared text helpers."""

from __future__ import annotations

from p3d_cli.cli.output import plural


def test_plural_counts_in_words():
    assert plural(1, "face") == "1 face"
    assert plural(12, "face") == "12 faces"
    assert plural(0, "non-manifold vertex") == "0 non-manifold vertices"  # was "vertexs"
    assert plural(1, "non-manifold vertex") == "1 non-manifold vertex"
    assert plural(1, "link") == "1 link"
