"""``--report html:DIR`` and ``github-summary:FILE``: every input, its picture, nothing from the network."""

from __future__ import annotations

import re

import numpy as np
from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl
from helpers.html_pages import Resources

from p3d_cli.render.overlays import COLOURS
from p3d_cli.render.png import decode_png


def inputs(tmp_path):
    clean, open_, broken = tmp_path / "clean.stl", tmp_path / "open.stl", tmp_path / "broken.stl"
    write_binary_stl(clean, cube_triangles())
    write_binary_stl(open_, cube_triangles()[2:])
    broken.write_bytes(b"solid x\nfacet normal\n")
    return clean, open_, broken


def test_html_report_holds_every_input_and_loads_nothing_from_the_network(tmp_path):
    clean, open_, broken = inputs(tmp_path)
    out = tmp_path / "report"
    result = run("check", clean, open_, broken, "box:1,2,3", "--report", f"html:{out}")
    assert result.exit_code == 2
    page = (out / "index.html").read_text()
    for source in (clean, open_, broken, "box:1,2,3"):
        assert str(source) in page
    parser = Resources()
    parser.feed(page)
    assert "script" not in parser.tags and "link" not in parser.tags
    assert not re.search(r"url\(", page)
    for url in parser.urls:
        assert "://" not in url and not url.startswith("//"), url
        assert (out / url).is_file()
    # Failed and unreadable inputs come first; the open cube's picture shows its hole's border.
    assert page.index(str(open_)) < page.index(str(clean))
    pictures = sorted((out / "images").iterdir())
    assert len(pictures) == 2                                     # clean and open; no picture of errors
    opened = [p for p in pictures if "open" in p.name][0]
    assert np.all(decode_png(opened.read_bytes()) == COLOURS["boundary"], axis=-1).sum() > 50
    assert '<td>boundary edges</td><td class="n">4</td>' in page


def test_github_summary_is_markdown_appended_with_the_same_pictures(tmp_path):
    clean, open_, _ = inputs(tmp_path)
    summary = tmp_path / "summary.md"
    summary.write_text("# earlier step\n")
    result = run("check", clean, open_, "--report", f"github-summary:{summary}")
    assert result.exit_code == 1
    text = summary.read_text()
    assert text.startswith("# earlier step\n")
    assert "| input | verdict |" in text and f"`{open_}` | failed" in text
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert len(images) == 2 and all((tmp_path / image).is_file() for image in images)


def test_a_report_that_would_overwrite_an_input_is_refused(tmp_path):
    clean, _, _ = inputs(tmp_path)
    before = clean.read_bytes()
    result = run("check", clean, "--report", f"github-summary:{clean}")
    assert result.exit_code == 2 and "input" in result.output
    assert clean.read_bytes() == before


def test_unknown_report_kinds_name_the_new_ones(tmp_path):
    result = run("check", "x.stl", "--report", "html")
    assert result.exit_code == 2 and "html:DIR" in result.output
