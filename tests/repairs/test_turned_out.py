"""An inward mesh turned out whole is not checked again: its topology is the input's with the
signs of the volumes flipped, bit for bit. These tests hold that claim against the check
computed on the output (and the mass properties reported against ``props`` of the output)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import p3d_cli as p3d
from helpers.tori import grid_torus
from p3d_cli.mesh.topology import topology
from p3d_cli.repairs import repair


def assert_same_as_checked(mesh, report) -> None:
    checked = topology(mesh.triangles)
    assert checked == report.after
    again = p3d.props(mesh.triangles).properties
    after = report.mass.after
    assert again.volume == after.volume
    assert np.array_equal(again.center_of_mass, after.center_of_mass)
    assert np.array_equal(again.inertia, after.inertia)


@given(st.integers(3, 12), st.integers(3, 12), st.floats(1e-3, 1e3), st.sampled_from([np.float32, np.float64]),
       st.tuples(*[st.floats(-1e6, 1e6)] * 3))
def test_turning_out_an_inward_torus_changes_nothing_but_signs(u, v, scale, dtype, at):
    triangles = grid_torus(u, v, scale, at).astype(dtype)[:, ::-1]
    mesh, report = repair(np.ascontiguousarray(triangles))
    assert report.fixed and report.step("outward").counts["faces_flipped"] == len(triangles)
    assert report.after.volume == -report.before.volume
    assert_same_as_checked(mesh, report)


def test_the_inward_horse(real_meshes):
    mesh, report = repair(real_meshes / "common3d__horse.ply")
    assert report.fixed
    assert_same_as_checked(mesh, report)
