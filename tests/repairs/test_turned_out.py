"""An inward mesh turned out whole: every face turned round and nothing else, its signed volume
negated exactly (each term of check's sums is), and the report's check of the output is the one
``p3d check`` makes of it."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import p3d_cli as p3d
from helpers.tori import grid_torus
from p3d_cli.repairs import repair
from p3d_cli.repairs.report import check_summary


def assert_as_checked(mesh, report) -> None:
    again = p3d.check(mesh.source).report
    assert check_summary(again) == check_summary(report.after)
    assert again.volume == report.after.volume and again.shell_list == report.after.shell_list
    props = p3d.props(mesh.triangles).properties
    assert props.volume == report.mass.after.volume
    assert np.array_equal(props.center_of_mass, report.mass.after.center_of_mass)
    assert np.array_equal(props.inertia, report.mass.after.inertia)


@given(st.integers(3, 12), st.integers(3, 12), st.floats(1e-3, 1e3), st.sampled_from([np.float32, np.float64]),
       st.tuples(*[st.floats(-1e6, 1e6)] * 3))
def test_turning_out_an_inward_torus_changes_nothing_but_signs(u, v, scale, dtype, at):
    triangles = np.ascontiguousarray(grid_torus(u, v, scale, at).astype(dtype)[:, ::-1])
    mesh, report = repair(triangles)
    if report.failed_before != ("outward",):
        return        # float32 far out can collapse a coarse torus (degenerate faces): not this case
    assert report.step("outward").counts["faces_flipped"] == len(triangles)
    assert mesh.triangles.tobytes() == np.ascontiguousarray(triangles[:, [0, 2, 1]]).tobytes()
    assert report.after.volume == -report.before.volume
    assert "outward" not in report.failed_after
    assert_as_checked(mesh, report)


def test_the_inward_horse(real_meshes):
    mesh, report = repair(real_meshes / "common3d__horse.ply")
    assert report.failed_after == ("no-self-intersection",)          # its own, which no flip mends
    assert_as_checked(mesh, report)
