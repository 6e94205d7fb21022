"""Robotics placement vocabulary: rpy angles, uniform and mirroring scales, the principal
frame as a quaternion and as rpy."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from helpers.meshes import cube_triangles, write_ascii_stl
from p3d_cli.cli.main import cli
from p3d_cli.errors import UsageError
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.geometry.placement import Placement
from p3d_cli.geometry.rotation import (
    matrix_quaternion,
    matrix_rpy,
    parse_rpy,
    quaternion_matrix,
    rotation_from_axis_degrees,
    rotation_from_rpy,
)


def record(*args):
    result = CliRunner().invoke(cli, ["props", *args, "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_rpy_is_urdf_fixed_axes_x_then_y_then_z():
    r, p, y = 0.3, -0.7, 1.9
    want = (rotation_from_axis_degrees("z", math.degrees(y)) @ rotation_from_axis_degrees("y", math.degrees(p))
            @ rotation_from_axis_degrees("x", math.degrees(r)))
    np.testing.assert_allclose(rotation_from_rpy(r, p, y), want, atol=1e-15)
    # A quarter roll takes y to z; a quarter yaw takes x to y.
    np.testing.assert_allclose(rotation_from_rpy(math.pi / 2, 0, 0) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(rotation_from_rpy(0, 0, math.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(parse_rpy("0.3,-0.7,1.9"), want, atol=1e-15)
    for bad in ("1,2", "a,b,c", "1,2,inf"):
        with pytest.raises(UsageError):
            parse_rpy(bad)


def test_quaternion_and_rpy_invert_the_matrix():
    rng = np.random.default_rng(5)
    quats = rng.normal(size=(300, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    # Half turns and gimbal lock, where the naive formulas lose their digits.
    specials = [rotation_from_axis_degrees(a, d) for a in ("x", "y", "z", (1, 1, 0)) for d in (180, 90, -90)]
    specials += [rotation_from_rpy(0.4, math.pi / 2, -1.0), rotation_from_rpy(0.4, -math.pi / 2, 2.0)]
    for m in [quaternion_matrix(q) for q in quats] + specials:
        q = matrix_quaternion(m)
        assert q[0] >= 0 and math.isclose(np.linalg.norm(q), 1.0, rel_tol=1e-15)
        np.testing.assert_allclose(quaternion_matrix(q), m, atol=2e-15)
        np.testing.assert_allclose(rotation_from_rpy(*matrix_rpy(m)), m, atol=2e-15)


@pytest.mark.parametrize("spec", ["wedge:1,2,3", "corner:1,2,3", "box:1,2,3", "capsule:0.5,2"])
@pytest.mark.parametrize("signs", [(-1, 1, 1), (1, -1, 1), (-1, -1, -1), (-1, -1, 1)])
def test_a_mirror_has_the_mirror_image_s_mass_properties(spec, signs):
    s = np.array(signs, dtype=float)
    plain = p3d.props(spec).properties
    mirrored = p3d.props(spec, Placement(scale=s)).properties
    assert mirrored.volume == pytest.approx(plain.volume, rel=1e-15) and mirrored.volume > 0
    np.testing.assert_allclose(mirrored.center_of_mass, s * plain.center_of_mass, atol=1e-15)
    np.testing.assert_allclose(mirrored.inertia, np.diag(s) @ plain.inertia @ np.diag(s), rtol=1e-15, atol=1e-14)
    # The mirror image's own triangles (corners reflected, winding reversed) agree, and so do
    # the mirrored shape's own faces.
    shape = p3d.parse_shape(spec)
    tris = (shape.triangles() if shape.polyhedral else shape.tessellate(64)) * s
    if np.prod(s) < 0:                                    # a reflection: wind outward again
        tris = tris[:, [0, 2, 1]]
    m = triangle_moments(tris)
    if shape.polyhedral:
        own = triangle_moments(Placement(scale=s).shape(shape).triangles())
        assert own.volume == pytest.approx(m.volume, rel=1e-15)
    tess = p3d.props(spec, Placement(scale=s), tessellate=64).properties
    assert tess.volume == pytest.approx(m.volume, rel=1e-13)
    np.testing.assert_allclose(tess.second_moments, m.central, rtol=1e-12, atol=1e-13)
    # Bounds: the mirrored corners' box.
    bounds = p3d.bounds(spec, Placement(scale=s, rotation=rotation_from_rpy(0.2, 0.3, 0.4))).bounds
    verts = tris.reshape(-1, 3) @ rotation_from_rpy(0.2, 0.3, 0.4).T
    if shape.polyhedral:
        np.testing.assert_allclose(bounds.min, verts.min(axis=0), atol=1e-14)
        np.testing.assert_allclose(bounds.max, verts.max(axis=0), atol=1e-14)
    else:
        assert np.all(bounds.min <= verts.min(axis=0) + 1e-12) and np.all(bounds.max >= verts.max(axis=0) - 1e-12)


def test_mirrored_mesh_and_monte_carlo(tmp_path):
    """A mesh mirrored by scale -1 along x: positive volume, I' = S I S, Monte Carlo agrees."""
    path = tmp_path / "wedge.stl"
    tris = p3d.parse_shape("wedge:1,2,3").triangles() + [0.5, 0, 0]
    write_ascii_stl(path, tris)
    s = np.array([-1.0, 1.0, 1.0])
    plain = p3d.props(str(path)).properties
    mirrored = p3d.props(str(path), Placement(scale=s))
    assert mirrored.properties.volume == pytest.approx(plain.volume, rel=1e-14) and plain.volume > 0
    assert not mirrored.warnings
    np.testing.assert_allclose(mirrored.properties.inertia, np.diag(s) @ plain.inertia @ np.diag(s), rtol=1e-13)
    mc = p3d.props(str(path), Placement(scale=s), method="montecarlo", samples=100_000)
    assert abs(mc.properties.volume - plain.volume) < 5 * mc.uncertainty["volume"]
    assert abs(mc.properties.center_of_mass[0] + plain.center_of_mass[0]) < 5 * mc.uncertainty["center_of_mass"][0]


def test_cli_uniform_scale_rpy_and_principal_frame(tmp_path):
    path = tmp_path / "block.stl"
    write_ascii_stl(path, (cube_triangles() * 2 - 1) * [1, 2, 3])
    uniform = record(str(path), "--scale", "2")
    three = record(str(path), "--scale", "2,2,2")
    assert uniform["volume"] == three["volume"] == 48 * 8
    turned = record("box:1,2,3", "--rpy", "0.3,-0.7,1.9")
    rotation = rotation_from_rpy(0.3, -0.7, 1.9)
    np.testing.assert_allclose(turned["inertia"], rotation @ np.asarray(record("box:1,2,3")["inertia"]) @ rotation.T,
                               atol=1e-12)
    q, rpy = np.array(turned["principal_quaternion"]), np.array(turned["principal_rpy"])
    frame = quaternion_matrix(q)
    np.testing.assert_allclose(frame, np.array(turned["principal_axes"]).T, atol=1e-15)
    np.testing.assert_allclose(rotation_from_rpy(*rpy), frame, atol=1e-14)
    # The MJCF reading: I = R diag(principal) Rᵀ.
    np.testing.assert_allclose(frame @ np.diag(turned["principal_moments"]) @ frame.T, turned["inertia"], atol=1e-12)
    mirrored = record("wedge:1,2,3", "--scale", "-1,1,1")
    assert mirrored["volume"] == 24.0


@pytest.mark.parametrize("args, words", [
    (["--rotate", "z:90", "--rpy", "0,0,1"], ["--rotate/--rpy", "both given"]),
    (["--quat", "1,0,0,0", "--rpy", "0,0,1"], ["--quat/--rpy", "both given"]),
    (["--rpy", "0,1"], ["--rpy", "not 3"]),
    (["--scale", "0"], ["--scale"]),
    (["--scale", "1,2"], ["--scale"]),
])
def test_refusals(args, words):
    result = CliRunner().invoke(cli, ["props", "box", *args])
    assert result.exit_code == 2 and result.stderr.startswith("p3d: error:"), result.output
    for w in words:
        assert w in result.stderr
