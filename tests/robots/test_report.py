"""``p3d robot check --report html:DIR`` (issue #30 item 3): a page that stands alone, every link in
it, failed links first, each link's geometry with the declared and the computed inertia drawn in
their documented colours, turned apart when the declared tensor is about the wrong axes."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from helpers.cli import run
from helpers.html_pages import assert_stands_alone, drawing, extent, mask
from robots.test_check import ROTOR
from robots.test_real_robots import folder

from p3d_cli.render.draw import RING_COLOUR
from p3d_cli.render.overlays import COLOURS
from p3d_cli.render.pages import PICTURE_SIZE
from p3d_cli.render.png import decode_png

DOCS = Path(__file__).resolve().parents[2] / "docs"
#: The colours docs/render.md gives the two boxes.
DECLARED, COMPUTED = COLOURS["declared"], COLOURS["inertia"]
AXIAL, RADIAL = 0.2 * 0.02 ** 2 / 2, 0.2 * (3 * 0.02 ** 2 + 0.2 ** 2) / 12


def rows_of(page: str) -> list[str]:
    """The links in the page's order."""
    return re.findall(r'<tr id="row-\d+"><td class="about">\s*<div class="source">([^<]*)</div>', page)


def picture(folder: Path, link: str) -> np.ndarray:
    (path,) = [p for p in (folder / "images").iterdir() if p.name.endswith(f"-{link}.png")]
    return decode_png(path.read_bytes())


def test_every_link_is_in_the_page_failed_first_and_nothing_is_loaded_from_the_network(arm, tmp_path):
    description = arm.urdf(upper_mass="1900")          # grams in a metre model: upper fails
    out = tmp_path / "report"
    plain = run("robot", "check", description, "--package-path", f"arm_description={arm.package}")
    result = run("robot", "check", description, "--package-path", f"arm_description={arm.package}",
                 "--report", f"html:{out}")
    assert result.exit_code == plain.exit_code == 1
    assert result.output == plain.output                 # the report adds a file, not a line
    page = (out / "index.html").read_text()
    assert rows_of(page) == ["upper", "base", "tool"]     # failed first, then the description's order
    assert "p3d robot check: 3 links: 2 ok, 1 failed" in page
    assert "[density] mass 1900 kg" in page and str(description) in page
    urls = assert_stands_alone(page, out)
    assert sorted(set(urls)) == sorted(f"images/{p.name}" for p in (out / "images").iterdir())
    assert len(list((out / "images").iterdir())) == 2     # the tool has no geometry and no inertial
    assert "nothing to draw" in page
    areas = {}
    for link in ("upper", "base"):
        pixels = picture(out, link)
        assert pixels.shape == (PICTURE_SIZE[1], PICTURE_SIZE[0], 3)
        areas[link] = drawing(pixels)
    assert mask(areas["base"], DECLARED).sum() > 200 and mask(areas["base"], COMPUTED).sum() > 200
    # The mass in grams: the declared box is sqrt(1000) times too small, and circled.
    left, right, top, bottom = extent(mask(areas["upper"], DECLARED))
    c_left, c_right, c_top, c_bottom = extent(mask(areas["upper"], COMPUTED))
    assert 0 < bottom - top < (c_bottom - c_top) / 10
    assert mask(areas["upper"], RING_COLOUR)[max(top - 40, 0):bottom + 40, max(left - 40, 0):right + 40].sum() > 50
    # The numbers, declared beside computed: the upper link's 1900 kg on both sides.
    assert re.search(r"<td>mass \(kg\)</td><td class=\"n side\">1,?900</td><td class=\"n side\">1,?900</td>", page)


def rotor(tmp_path: Path, name: str, xx: float, yy: float, zz: float, *options) -> tuple[Path, CliRunner]:
    description = tmp_path / f"{name}.urdf"
    description.write_text(ROTOR.format(xx=xx, yy=yy, zz=zz))
    out = tmp_path / name
    result = run("robot", "check", description, "--report", f"html:{out}", *options)
    return out, result


def test_a_tensor_about_the_wrong_axis_is_drawn_turned_away_from_the_geometry(tmp_path):
    """The rotor's axial moment declared about x: the sorted moments agree, the boxes do not."""
    right, result = rotor(tmp_path, "right", RADIAL, RADIAL, AXIAL)
    assert result.exit_code == 0
    wrong, result = rotor(tmp_path, "wrong", AXIAL, RADIAL, RADIAL)
    assert result.exit_code == 1
    boxes = {}
    for name, out in (("right", right), ("wrong", wrong)):
        area = drawing(picture(out, "rotor"))
        boxes[name] = {key: mask(area, colour) for key, colour in (("declared", DECLARED), ("computed", COMPUTED))}
        assert all(m.sum() > 200 for m in boxes[name].values()), name   # both drawn, where they coincide too
    # Agreeing: one footprint (the declared box's wider lines rim the computed one's).
    left, right_, top, bottom = extent(boxes["right"]["declared"])
    assert np.allclose((left, right_, top, bottom), extent(boxes["right"]["computed"]), atol=6)
    # About the wrong axis: the declared box lies across the rotor, the computed one along it.
    d_left, d_right, d_top, d_bottom = extent(boxes["wrong"]["declared"])
    c_left, c_right, c_top, c_bottom = extent(boxes["wrong"]["computed"])
    assert d_right - d_left > 2 * (c_right - c_left)
    assert c_bottom - c_top > 2 * (d_bottom - d_top)
    # The computed box is the geometry's either way: the same pixels in both pictures.
    assert (boxes["wrong"]["computed"] == boxes["right"]["computed"]).mean() > 0.999


def test_ellipsoids_on_request(tmp_path):
    out, result = rotor(tmp_path, "wrong", AXIAL, RADIAL, RADIAL, "--report-shape", "ellipsoid")
    assert result.exit_code == 1
    page = (out / "index.html").read_text()
    assert "uniform ellipsoids of the same mass" in page and "equivalent ellipsoid (m)" in page
    # Full axes 2 sqrt(5 (I_i + I_j - I_k) / 2m) of the declared tensor.
    axes = sorted(2 * np.sqrt(5 * (AXIAL + RADIAL + RADIAL - 2 * i) / (2 * 0.2)) for i in (AXIAL, RADIAL, RADIAL))
    shown = re.search(r"<td>equivalent ellipsoid \(m\)</td><td class=\"n side\">\(([^)]*)\)", page).group(1)
    np.testing.assert_allclose(sorted(float(v) for v in shown.split(",")), axes, rtol=1e-3)
    area = drawing(picture(out, "rotor"))
    assert mask(area, DECLARED).sum() > 200 and mask(area, COMPUTED).sum() > 200


def test_a_link_without_geometry_shows_its_declared_box_and_an_open_mesh_no_computed_one(tmp_path):
    mesh = tmp_path / "open.obj"          # a unit cube without its top: bounds no solid
    corners = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    faces = [(1, 3, 4), (1, 4, 2), (1, 2, 6), (1, 6, 5), (2, 4, 8), (2, 8, 6), (4, 3, 7), (4, 7, 8),
             (3, 1, 5), (3, 5, 7)]
    mesh.write_text("".join(f"v {x * 0.1} {y * 0.1} {z * 0.1}\n" for x, y, z in corners)
                    + "".join(f"f {a} {b} {c}\n" for a, b, c in faces))
    description = tmp_path / "two.urdf"
    inertial = ('<inertial><origin xyz="0.05 0.05 0.05"/><mass value="1"/>'
                '<inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial>')
    description.write_text(f'<robot name="r"><link name="sensor">{inertial}</link><link name="cover">'
                           f'<collision><geometry><mesh filename="open.obj"/></geometry></collision>{inertial}'
                           '</link></robot>')
    out = tmp_path / "report"
    result = run("robot", "check", description, "--report", f"html:{out}")
    assert result.exit_code == 0, result.output
    page = (out / "index.html").read_text()
    assert rows_of(page) == ["sensor", "cover"]
    for link in ("sensor", "cover"):
        area = drawing(picture(out, link))
        assert mask(area, DECLARED).sum() > 200 and mask(area, COMPUTED).sum() == 0, link
    assert "no computed box: the geometry is not a closed solid" in page
    assert "sensor  (no geometry)" in picture_title_text(out)


def picture_title_text(out: Path) -> str:
    """The titles the pictures carry in their PNG text chunks."""
    return " ".join(p.read_bytes().split(b"Title\x00", 1)[1][:80].decode("latin-1")
                    for p in (out / "images").iterdir())


def test_the_copies_of_a_replicated_body_share_its_picture(tmp_path):
    description = tmp_path / "copies.xml"
    description.write_text('<mujoco><worldbody><replicate count="3" offset="0.2 0 0"><body name="b">'
                           '<geom type="box" size="0.05 0.02 0.01"/>'
                           '<inertial pos="0 0 0" mass="0.32" diaginertia="5.4e-5 2.8e-4 3.1e-4"/>'
                           '</body></replicate></worldbody></mujoco>')
    out = tmp_path / "report"
    result = run("robot", "check", description, "--report", f"html:{out}")
    assert result.exit_code == 0, result.output
    page = (out / "index.html").read_text()
    links = rows_of(page)
    assert len(links) == 3
    pictures = {picture(out, link).tobytes() for link in links}
    assert len(pictures) == 1
    assert page.count(f"drawn as {links[0]}, a copy of the same body") == 2


def test_reports_that_cannot_be_written_are_refused_before_any_work(arm, tmp_path):
    description = arm.urdf()
    before = description.read_bytes()
    result = run("robot", "check", description, "--report", "junit:out.xml")
    assert result.exit_code == 2 and "use html:DIR" in result.output
    result = run("robot", "check", description, "--package-path", f"arm_description={arm.package}",
                 "--report", f"html:{description}")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    # A description named index.html, reported into its own folder.
    page = tmp_path / "index.html"
    page.write_bytes(before)
    result = run("robot", "check", page, "--package-path", f"arm_description={arm.package}",
                 "--report", f"html:{tmp_path}")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    assert page.read_bytes() == before and not (tmp_path / "images").exists()
    assert description.read_bytes() == before


def test_check_without_a_report_imports_no_picture_code(arm):
    """``p3d robot check`` stays as fast as it was: the render package is read only for --report."""
    code = ("import sys; from click.testing import CliRunner; from p3d_cli.cli.main import cli; "
            f"r = CliRunner().invoke(cli, ['robot', 'check', {str(arm.urdf())!r}, '--package-path', "
            f"'arm_description={arm.package}']); print(r.exit_code, 'p3d_cli.render' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.split() == ["0", "False"]


def test_the_documented_colours_are_the_ones_drawn():
    text = (DOCS / "render.md").read_text()
    for colour in (DECLARED, COMPUTED):
        assert "#{:02x}{:02x}{:02x}".format(*colour) in text


#: Real descriptions: (folder, description, packages, a link that fails with both boxes drawn).
REAL = {
    "kuka": ("kuka_kr16_2", "kuka_kr16_support/urdf/kr16_2.urdf", {"kuka_kr16_support": "kuka_kr16_support"},
             "link_2"),
    "vx300s": ("menagerie_vx300s", "trossen_vx300s/vx300s.xml", {}, "left_finger_link"),
}


@pytest.mark.parametrize("case", sorted(REAL))
def test_real_descriptions(case, tmp_path):
    name, relative, packages, failing = REAL[case]
    root = folder(name)
    out = tmp_path / "report"
    options = [a for k, v in packages.items() for a in ("--package-path", f"{k}={root / v}")]
    result = run("robot", "check", root / relative, *options, "--report", f"html:{out}")
    assert result.exit_code == 1
    failed = re.search(r": \d+ links, \d+ failed: (.*)", result.output).group(1).split(", ")
    page = (out / "index.html").read_text()
    links = rows_of(page)
    assert links[:len(failed)] == failed and failing in failed
    from p3d_cli.robots import load_robot

    robot = load_robot(root / relative, {k: str(root / v) for k, v in packages.items()})
    assert sorted(links) == sorted(link.name for link in robot.links)
    assert_stands_alone(page, out)
    area = drawing(picture(out, failing.replace(":", "_")))
    assert mask(area, DECLARED).sum() > 200 and mask(area, COMPUTED).sum() > 200


def test_hostile_declared_numbers_give_a_page_and_say_what_is_not_drawn(tmp_path):
    """Moments near float64's limit, a centre of mass at 1e300 m, a tensor no body has: every
    link gets its row, nothing overflows into a warning or an internal error."""
    links = {"huge": ('0 0 0', '2', '1e308 1e308 1e308'), "far": ('1e300 0 0', '2', '0.01 0.01 0.01'),
             "impossible": ('0 0 0', '2', '-0.01 0.01 0.05'), "zero": ('0 0 0', '0', '0 0 0')}
    body = "".join(f'<link name="{name}"><collision><geometry><box size="0.1 0.2 0.3"/></geometry></collision>'
                   f'<inertial><origin xyz="{com}"/><mass value="{mass}"/><inertia ixx="{i.split()[0]}" ixy="0" '
                   f'ixz="0" iyy="{i.split()[1]}" iyz="0" izz="{i.split()[2]}"/></inertial></link>'
                   for name, (com, mass, i) in links.items())
    description = tmp_path / "hostile.urdf"
    description.write_text(f'<robot name="r">{body}</robot>')
    out = tmp_path / "report"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)       # numpy's overflow warnings fail the run
        result = run("robot", "check", description, "--report", f"html:{out}")
    assert result.exit_code == 1, result.output
    page = (out / "index.html").read_text()
    assert sorted(rows_of(page)) == sorted(links)
    assert page.count("too far from the link frame") == 2            # huge, far
    for name in links:
        area = drawing(picture(out, name))
        assert mask(area, COMPUTED).sum() > 100, name      # the box's own, at 2 kg (zero: at 1 kg/m^3)
