"""``fill`` never damages a file: byte for byte, every byte outside the replaced ``<inertial>``
elements is the file's own, whatever XML construct surrounds them.

The oracle is independent of p3d's XML reader: each description is built from pieces, fixed
text and inertial slots, so the test knows where every slot is. The filled file must be the
fixed pieces, encoded as the file is, with one inertial element (of the form fill writes) in
each slot, and nothing else. Hypothesis draws the constructs (comments, CDATA, processing
instructions, entities, empty and end-tagged inertials first, between siblings, last or alone,
attributes wrapping lines, CRLF, UTF-8 with and without a mark, UTF-16 LE and BE, UTF-32,
ISO-8859-1) and the result is also compiled by MuJoCo where MuJoCo reads the file.
"""

from __future__ import annotations

import os
import re
import stat

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers.cli import run as _run
from p3d_cli.errors import OutputError
from p3d_cli.robots import fill_robot, load_robot
from p3d_cli.robots.fill import write_fill

#: A slot: an inertial to be replaced (its declared text), or "" where a body declares none.
SLOT = object()
#: What fill writes in a slot, MJCF: one self-closing element.
FILLED = re.compile(r"<inertial pos=\"[^\"]*\" mass=\"[^\"]*\" fullinertia=\"[^\"]*\"/>")

#: Encodings, each with its byte order mark (empty: none).
ENCODINGS = [("utf-8", b""), ("utf-8", b"\xef\xbb\xbf"), ("utf-16-le", b"\xff\xfe"), ("utf-16-be", b"\xfe\xff"),
             ("utf-16-le", b""), ("utf-32-le", b"\xff\xfe\x00\x00"), ("iso-8859-1", b"")]

DECOYS = ['<!-- <inertial mass="9" diaginertia="1 1 1"/> a commented-out inertial -->',
          '<![CDATA[ <inertial mass="9"/> & < > ]]>',
          '<?p3d-test a processing instruction, <inertial/> ?>',
          "<!-- déjà vu: not ASCII, ± µ -->",
          "&note;"]


def piece(draw_inertial: str, first: bool, siblings: list[str], where: str) -> list:
    """A body's children: the siblings with the inertial slot first, between or last."""
    body = list(siblings)
    at = {"first": 0, "middle": min(1, len(body)), "last": len(body)}[where]
    body.insert(at, (SLOT, draw_inertial))
    return body


@st.composite
def descriptions(draw):
    """``(pieces, encoding, bom, newline)``: an MJCF of three bodies as fixed text and slots."""
    encoding, bom = draw(st.sampled_from(ENCODINGS))
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    inertials = st.sampled_from([
        '<inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>',
        '<inertial pos="0 0 0"{nl}          mass="2"{nl}          diaginertia="1 1 1" />',
        '<inertial pos="0 0 0" mass="0.5" diaginertia="1 1 1"></inertial>',
        '<inertial pos="0 0 0" mass="0.5" diaginertia="1 1 1">{nl}        </inertial >',
        '<inertial mass="&m;" diaginertia="1 1 1"/>',
        "",  # no inertial: fill inserts one
    ])
    decoys = st.lists(st.sampled_from(DECOYS), max_size=2)
    text: list = [f'<?xml version="1.0" encoding="{_declared(encoding)}"?>{{nl}}',
                  '<!DOCTYPE mujoco [<!ENTITY m "3"> <!ENTITY note "entity text">]>{nl}',
                  "<mujoco model='bytes'>{nl}", *draw(decoys), "  <worldbody>{nl}"]
    for name, geom in (("a", '<geom type="box" size="0.1 0.2 0.3"/>'), ("b", '<geom type="sphere" size="0.05"/>'),
                       ("c", '<geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/>')):
        inertial = draw(inertials)
        where = draw(st.sampled_from(["first", "middle", "last"])) if inertial else "first"  # inserted first
        siblings = [geom, *draw(decoys), '<joint type="hinge"/>'] if name != "c" else [geom]
        alone = draw(st.booleans()) and name == "b"
        if alone:  # the inertial alone in its body, as the shadow hand's tips: nothing to fill from
            siblings = []
            inertial = inertial or '<inertial pos="0 0 0" mass="1" diaginertia="0 0 0"/>'
        text.append(f'    <body name="{name}">')
        for child in piece(inertial, True, siblings, where):
            if isinstance(child, tuple):
                child = child + (not alone,)
                text += ["{nl}      ", child] if child[1] else [child]
            else:
                text.append("{nl}      " + child)
        text.append("{nl}    </body>{nl}")
    text += ["  </worldbody>{nl}", "</mujoco>{nl}"]
    pieces = []
    for p in text:
        if isinstance(p, tuple):
            pieces.append((SLOT, p[1].replace("{nl}", newline), p[2]))
        else:
            pieces.append(p.replace("{nl}", newline))
    return pieces, encoding, bom, newline


def _declared(encoding: str) -> str:
    return {"utf-8": "UTF-8", "utf-16-le": "UTF-16", "utf-16-be": "UTF-16", "utf-32-le": "UTF-32",
            "iso-8859-1": "ISO-8859-1"}[encoding]


def write(folder, pieces, encoding, bom, name="model.xml"):
    text = "".join(p[1] if isinstance(p, tuple) else p for p in pieces)
    path = folder / name
    path.write_bytes(bom + text.encode(encoding))
    return path


def assert_only_slots_changed(filled: bytes, pieces, encoding: str, bom: str, newline: str) -> list[str]:
    """The filled bytes are the pieces' own bytes with one filled inertial per slot; returns
    the inertials written."""
    assert filled.startswith(bom)
    text = filled[len(bom):].decode(encoding)
    assert filled == bom + text.encode(encoding)
    at, written = 0, []
    for p in pieces:
        if not isinstance(p, tuple):
            assert text[at:at + len(p)] == p, (text[at:at + 80], p)
            at += len(p)
            continue
        declared = p[1]
        if not p[2]:  # kept: the declared element, untouched
            assert text[at:at + len(declared)] == declared
            at += len(declared)
            continue
        if not declared:  # inserted as the body's first child, on its own line, indented
            m = re.compile(re.escape(newline) + r" +" + FILLED.pattern).match(text, at)
        else:
            m = FILLED.match(text, at)
        assert m is not None, text[at:at + 120]
        written.append(m.group(0))
        at = m.end()
    assert at == len(text)
    return written


@settings(max_examples=int(os.environ.get("P3D_ROBOT_EXAMPLES", 60)), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(case=descriptions())
def test_fill_changes_only_the_inertials_whatever_surrounds_them(tmp_path, case):
    pieces, encoding, bom, newline = case
    path = write(tmp_path, pieces, encoding, bom)
    robot = load_robot(path)
    result = fill_robot(robot)
    slots = [p[2] for p in pieces if isinstance(p, tuple)]
    assert [link.status for link in result.links] == ["filled" if s else "kept" for s in slots]
    written = assert_only_slots_changed(result.data, pieces, encoding, bom, newline)
    assert len(written) == sum(slots)
    # Read back, the bodies have what fill computed.
    (tmp_path / "filled.xml").write_bytes(result.data)
    again = load_robot(tmp_path / "filled.xml")
    for link, filled in zip(again.links, result.links):
        if filled.status == "kept":
            continue
        assert link.inertial.mass == filled.mass
        np.testing.assert_array_equal(link.inertial.center, filled.center)
        np.testing.assert_allclose(link.inertial.inertia, filled.inertia, rtol=0, atol=1e-15)
    # Run twice, it changes nothing the second time.
    assert fill_robot(again).data == result.data


def test_mujoco_compiles_the_filled_constructs_with_p3ds_numbers(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    from p3d_cli.geometry.rotation import quaternion_matrix

    # MuJoCo (tinyxml2) reads UTF-8, knows no DTD entities and no processing instructions inside
    # the root: the constructs it does read, all at once.
    text = ('<?xml version="1.0"?>\r\n<!-- <inertial mass="9"/> -->\r\n<mujoco>\r\n'
            '  <worldbody>\r\n    <body name="first">\r\n      <inertial pos="0 0 0"\r\n                mass="1" '
            'diaginertia="1 1 1"/>\r\n      <joint type="hinge"/>\r\n      <geom type="box" size="0.1 0.2 0.3"/>'
            '\r\n      <body name="tip">\r\n        <geom type="sphere" size="0.05" density="500"/>\r\n'
            '        <inertial pos="0 0 0" mass="0.001" diaginertia="0 0 0"/>\r\n      </body>\r\n'
            '      <body name="ended"><inertial pos="0 0 0" mass="2" diaginertia="1 1 1"></inertial>'
            '<geom type="capsule" fromto="0 0 0 0 0.1 0.2" size="0.02" mass="0.7"/></body>\r\n'
            '    </body>\r\n  </worldbody>\r\n</mujoco>\r\n')
    path = tmp_path / "constructs.xml"
    path.write_bytes(text.encode())
    result = fill_robot(load_robot(path))
    out = tmp_path / "filled.xml"
    out.write_bytes(result.data)
    model = mujoco.MjModel.from_xml_path(str(out))
    for filled in result.links:
        b = model.body(filled.link).id
        r = quaternion_matrix(model.body_iquat[b])
        assert model.body_mass[b] == pytest.approx(filled.mass, rel=1e-12)
        np.testing.assert_allclose(model.body_ipos[b], filled.center, rtol=0, atol=1e-12)
        np.testing.assert_allclose(r @ np.diag(model.body_inertia[b]) @ r.T, filled.inertia, rtol=0,
                                   atol=1e-9 * np.abs(filled.inertia).max())
    # Per-geom density and mass, as MuJoCo's own compile of the geoms gives them.
    bare = mujoco.MjModel.from_xml_string(re.sub(r"<inertial[^>]*?(/>|></inertial>)", "",
                                                 text.replace("\r\n", "\n")).replace("\n", ""))
    for name, expected in (("tip", 500 * 4 / 3 * np.pi * 0.05 ** 3), ("ended", 0.7), ("first", 1000 * 0.048)):
        assert result.links[[f.link for f in result.links].index(name)].mass == pytest.approx(expected, rel=1e-12)
        assert bare.body_mass[bare.body(name).id] == pytest.approx(expected, rel=1e-6)


def test_the_real_constructs(tmp_path):
    """The constructs of the real files (real-robots README, construct 5), as fixtures: the
    empty <inertial/> first and followed by siblings with its attributes wrapping a line
    (vx300s), as a body's only child (shadow hand tips), and with an end tag after joints and
    alone (gym fetch). The old reader deleted the next sibling after each empty inertial."""
    text = """<mujoco model="real">
  <worldbody>
    <body name="upper_arm_link" pos="0 0 0.04805">
      <inertial pos="0.0171605 2.725e-07 0.191323" quat="0.705539 0.0470667 -0.0470667 0.705539" mass="0.792592"
        diaginertia="0.00911338 0.008925 0.000759317"/>
      <joint name="elbow" axis="0 1 0"/>
      <geom type="box" size="0.02 0.02 0.1" pos="0 0 0.1"/>
      <body name="fftip" pos="0 0 0.026">
        <inertial pos="0 0 0" mass="0.001" diaginertia="0 0 0"/>
      </body>
      <body name="robot0:base_link" pos="0.2869 0.2641 0">
        <joint name="robot0:slide0" pos="0 0 0" axis="1 0 0" type="slide"></joint>
        <joint name="robot0:slide1" pos="0 0 0" axis="0 1 0" type="slide"></joint>
        <inertial diaginertia="1.2869 1.2236 0.9868" mass="70.1294" pos="-0.0036 0 0.0014" quat="0.7605 -0.0133 -0.0061 0.6491"></inertial>
        <geom type="cylinder" size="0.3 0.2"/>
        <body name="robot0:head_camera_depth_optical_frame" pos="0 0 0" quat="0.5 -0.5 0.5 -0.5">
          <inertial diaginertia="0 0 0" mass="0" pos="0 0 0"></inertial>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
    path = tmp_path / "real.xml"
    path.write_text(text)
    result = fill_robot(load_robot(path), density=1000.0)
    status = {link.link: link.status for link in result.links}
    assert status == {"upper_arm_link": "filled", "fftip": "kept", "robot0:base_link": "filled",
                      "robot0:head_camera_depth_optical_frame": "kept"}
    after = result.data.decode()
    # Everything but the two filled elements is as it was, and every joint is still there.
    kept = re.sub(r"<inertial pos=\"0\.0171605.*?/>", "", re.sub(r"<inertial diaginertia=\"1\.2869.*?</inertial>",
                                                                  "", text, flags=re.S), flags=re.S)
    assert re.sub(r"<inertial pos=\"[^\"]*\" mass=\"[^\"]*\" fullinertia=\"[^\"]*\"/>", "", after) == kept
    assert after.count("<joint ") == 3 and after.count("</body>") == 4


def test_utf16_description_is_filled_in_utf16(arm, tmp_path):
    """#27: fill spliced UTF-8 bytes into a UTF-16 file."""
    text = arm.urdf().read_text().replace('<?xml version="1.0"?>', '<?xml version="1.0" encoding="UTF-16"?>')
    path = tmp_path / "wide.urdf"
    path.write_bytes(text.encode("utf-16"))  # with its byte order mark
    result = fill_robot(load_robot(path, arm.packages), density=2700.0)
    assert result.data[:2] == path.read_bytes()[:2]
    decoded = result.data.decode("utf-16")
    assert decoded.count("<inertial>") == 2 and "\x00" not in decoded
    assert decoded.encode("utf-16") == result.data


def test_a_stateful_encoding_is_refused_rather_than_damaged(tmp_path):
    text = ('<?xml version="1.0" encoding="ISO-2022-JP"?>\n<mujoco><!-- 日本 --><worldbody><body name="a">'
            '<geom size="0.1"/></body></worldbody></mujoco>\n')
    path = tmp_path / "jp.xml"
    path.write_bytes(text.encode("iso-2022-jp"))
    try:
        result = fill_robot(load_robot(path))
    except Exception as error:  # noqa: BLE001 - must be p3d's own refusal, checked below
        from p3d_cli.errors import InputError

        assert isinstance(error, InputError) and "byte for byte" in error.what
        return
    assert result.data.decode("iso-2022-jp").replace(re.search(r"\n *<inertial[^>]*/>",
                                                               result.data.decode("iso-2022-jp")).group(0), "") \
        == text


def test_in_place_keeps_permissions_and_refuses_output_over_the_input(arm, tmp_path):
    path = arm.urdf()
    os.chmod(path, 0o640)
    before = path.read_bytes()
    result = _run("robot", "fill", path, "--package-path", f"arm_description={arm.package}", "--density", "2700",
                  "-o", path)
    assert result.exit_code == 2 and "would overwrite the input" in result.stderr and "--in-place" in result.stderr
    assert path.read_bytes() == before
    result = _run("robot", "fill", path, "--package-path", f"arm_description={arm.package}", "--density", "2700",
                  "--in-place")
    assert result.exit_code == 0, result.output
    assert path.read_bytes() != before and stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert "rewritten in place" in result.stderr and result.stdout == ""
    once = path.read_bytes()
    assert _run("robot", "fill", path, "--package-path", f"arm_description={arm.package}", "--density", "2700",
                "--in-place").exit_code == 0
    assert path.read_bytes() == once  # idempotent
    assert "nothing changed, nothing rewritten" in _run("robot", "fill", path, "--package-path",
                                                        f"arm_description={arm.package}", "--density", "2700",
                                                        "--in-place").stderr
    assert not [p for p in path.parent.iterdir() if p.name.endswith(".p3d-tmp")]


def test_in_place_refuses_a_read_only_description(arm, monkeypatch):
    import p3d_cli.io.atomic as atomic

    path = arm.urdf()
    before = path.read_bytes()
    robot = load_robot(path, arm.packages)
    result = fill_robot(robot, density=2700.0)
    os.chmod(path, 0o444)
    if os.access(path, os.W_OK):  # root may write anyway: make the check see what a user would
        monkeypatch.setattr(atomic.os, "access", lambda p, mode: False)
    with pytest.raises(OutputError, match="read-only"):
        write_fill(robot, result)
    assert path.read_bytes() == before


def test_in_place_through_a_symlink_replaces_the_target(arm, tmp_path):
    path = arm.urdf()
    link = tmp_path / "link.urdf"
    link.symlink_to(path)
    robot = load_robot(link, arm.packages)
    result = fill_robot(robot, density=2700.0)
    write_fill(robot, result)
    assert link.is_symlink() and path.read_bytes() == result.data
    hard = tmp_path / "hard.urdf"
    os.link(path, hard)
    with pytest.raises(OutputError, match="hard"):
        write_fill(load_robot(path, arm.packages), result)


def test_output_over_a_mesh_is_refused(arm):
    robot = load_robot(arm.urdf(), arm.packages)
    mesh = robot.links[1].collision[0].thing
    before = open(mesh, "rb").read()
    with pytest.raises(OutputError, match="would overwrite the input"):
        write_fill(robot, fill_robot(robot, density=2700.0), mesh)
    assert open(mesh, "rb").read() == before


def test_a_kill_mid_write_leaves_the_description_whole(arm, monkeypatch):
    """#27: `-o` onto the description truncated it first. Now a failure while writing leaves
    it as it was, and no temporary file behind."""
    import p3d_cli.io.atomic as atomic

    path = arm.urdf()
    before = path.read_bytes()
    robot = load_robot(path, arm.packages)
    result = fill_robot(robot, density=2700.0)

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full_disk)
    with pytest.raises(OutputError, match="No space left"):
        write_fill(robot, result)
    assert path.read_bytes() == before
    assert not [p for p in path.parent.iterdir() if p.name.endswith(".p3d-tmp")]


def test_xacro_descriptions_are_never_written_back(tmp_path):
    pytest.importorskip("xacro")
    from p3d_cli.errors import UsageError

    path = tmp_path / "one.urdf.xacro"
    path.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="a"><xacro:property name="s" '
                    'value="0.1"/><link name="l"><collision><geometry><box size="${s} ${s} ${s}"/></geometry>'
                    '</collision></link></robot>')
    robot = load_robot(path)
    result = fill_robot(robot, density=1000.0)
    assert result.links[0].mass == pytest.approx(1.0)
    with pytest.raises(UsageError, match="expanded by xacro"):
        write_fill(robot, result)
    write_fill(robot, result, tmp_path / "out.urdf")
    assert load_robot(tmp_path / "out.urdf").links[0].inertial.mass == pytest.approx(1.0)
