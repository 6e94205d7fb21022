"""Monte Carlo mass properties against the exact method, closed forms, trimesh and itself.

Statistical checks are deterministic (fixed seeds), so they never flake; their tolerances are
still chosen as if the seeds were random, so that a pass means something:

- single comparisons allow 5 standard errors (two-sided p ≈ 6e-7 each);
- the spread over R = 200 seeds is compared with the stated standard error through the
  chi-square law: (R - 1) s² / σ² ~ χ²(R - 1), and we accept the ratio s / σ inside the
  central 99.9 % interval, i.e. s / σ ∈ [0.838, 1.168] for R = 200 (computed below).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

import p3d_cli as p3d
from p3d_cli.cli.main import cli
from p3d_cli.geometry.inertia import inertia_from_second_moments, mass_properties
from p3d_cli.measure.montecarlo import sample, samples_for_tolerance, triangles_inside
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.mesh.winding import face_grid, inside
from p3d_cli.results import Bounds
from p3d_cli.shapes import parse_spec

SEEDS = 200
CHI2_LO, CHI2_HI = (np.sqrt(stats.chi2.ppf(q, SEEDS - 1) / (SEEDS - 1)) for q in (0.0005, 0.9995))


def icosphere(subdivisions=3, scale=(1.0, 1.0, 1.0), offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(mesh.triangles) * scale + offset


def torus() -> np.ndarray:
    """A non-convex closed mesh (a hole through the middle)."""
    return np.asarray(trimesh.creation.torus(major_radius=2.0, minor_radius=0.7,
                                             major_sections=48, minor_sections=24).triangles)


def assert_within(estimate, reference, se, k=5.0):
    estimate, reference, se = (np.asarray(x, dtype=np.float64) for x in (estimate, reference, se))
    diff = np.abs(estimate - reference)
    # An entry with zero standard error (exactly known by symmetry of the sampling) must match
    # to rounding.
    allowed = k * se + 1e-12 * np.abs(reference).max()
    assert (diff <= allowed).all(), (diff / np.maximum(se, 1e-300))


def check_against_exact(result, exact_moments):
    exact = mass_properties(exact_moments)
    p, u = result.properties, result.uncertainty
    assert_within(p.volume, abs(exact.volume), u["volume"])
    assert_within(p.center_of_mass, exact.center_of_mass, u["center_of_mass"])
    assert_within(p.inertia, np.sign(exact.volume) * exact.inertia, u["inertia"])


# --- the inside test ------------------------------------------------------------------------

def test_chi_square_interval_is_what_the_docstring_says():
    assert CHI2_LO == pytest.approx(0.838, abs=1e-3)
    assert CHI2_HI == pytest.approx(1.168, abs=1e-3)


def subdivided_cube(k=4) -> np.ndarray:
    """[0, 1]³ with each face split into k × k squares (2 triangles each), outward."""
    t = np.linspace(0.0, 1.0, k + 1)
    u, v = np.meshgrid(t[:-1], t[:-1], indexing="ij")
    u, v, d = u.ravel(), v.ravel(), 1.0 / k
    quads = np.stack([np.stack([u, v], 1), np.stack([u + d, v], 1),
                      np.stack([u + d, v + d], 1), np.stack([u, v + d], 1)], 1)   # (m, 4, 2) ccw
    faces = []
    for axis in range(3):
        for side in (0.0, 1.0):
            pts = np.zeros(quads.shape[:2] + (3,))
            a, b = (axis + 1) % 3, (axis + 2) % 3
            pts[..., a], pts[..., b], pts[..., axis] = quads[..., 0], quads[..., 1], side
            if side == 0.0:
                pts = pts[:, ::-1]
            faces += [pts[:, [0, 1, 2]], pts[:, [0, 2, 3]]]
    return np.concatenate(faces)


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rays_through_shared_edges_and_vertices_count_once(axis, reverse):
    """Query points on a 1/8 grid send rays exactly through the faces' shared edges and
    vertices (the faces sit on a 1/4 grid); parity must still be exact, for either winding."""
    tri = subdivided_cube()
    assert triangle_moments(tri).volume == pytest.approx(1.0)
    if reverse:
        tri = tri[:, ::-1]
    t = np.arange(-2, 11) / 8.0                     # -0.25 .. 1.25, includes 0 and 1 and faces
    g = np.stack(np.meshgrid(t, t, t, indexing="ij"), -1).reshape(-1, 3)
    strictly_in = ((g > 0) & (g < 1)).all(axis=1)
    strictly_out = ((g < 0) | (g > 1)).any(axis=1)
    got = inside(face_grid(tri, axis=axis), g)
    assert (got[strictly_in] == 1).all()
    assert (got[strictly_out] == 0).all()


def test_inside_matches_the_convex_hull_on_random_points():
    rng = np.random.default_rng(5)
    hull = trimesh.convex.convex_hull(rng.normal(size=(200, 3)))
    points = rng.uniform(-3, 3, size=(100_000, 3))
    eq = hull.face_normals, np.einsum("ij,ij->i", hull.face_normals, hull.triangles[:, 0])
    margin = (points @ eq[0].T - eq[1]).max(axis=1)
    got = triangles_inside(np.asarray(hull.triangles))(points)
    clear = np.abs(margin) > 1e-9
    assert ((got == 1) == (margin < 0))[clear].all()


def test_inside_is_graceful_on_an_open_mesh():
    tri = subdivided_cube()[1:]                     # one small triangle missing
    rng = np.random.default_rng(0)
    points = rng.uniform(-0.2, 1.2, size=(50_000, 3))
    got = triangles_inside(tri)(points)
    assert set(np.unique(got)) <= {0.0, 0.5, 1.0}
    inner = ((points > 0.01) & (points < 0.99)).all(axis=1)
    # Only rays through the hole can disagree: a small minority, counted half.
    assert (got[inner] == 1).mean() > 0.9
    assert (got == 0.5).any()


# --- estimates against exact values ---------------------------------------------------------

@pytest.mark.parametrize("name,tri", [
    ("ellipsoid far away", icosphere(3, (1.0, 2.0, 3.0), (1e6, -2e6, 5e5))),
    ("torus", torus()),
    ("cube", cube_triangles() * [1.0, 3.0, 0.5]),
])
def test_mesh_estimate_within_five_standard_errors(tmp_path, name, tri):
    path = tmp_path / "part.stl"
    write_ascii_stl(path, tri)
    result = p3d.props(str(path), method="montecarlo", samples=200_000, seed=11)
    assert result.method == "montecarlo"
    check_against_exact(result, triangle_moments(tri))


@pytest.mark.parametrize("spec", ["sphere:2", "cylinder:1,1,3", "box:1,2,3", "wedge:1,2,0.5",
                                  "corner:2,1,1", "ellipsoid:1,2,3", "ecylinder:1,3,0.5"])
def test_primitive_estimate_within_five_standard_errors(spec):
    result = p3d.props(spec, method="montecarlo", samples=200_000, seed=3, density=2.5)
    exact = parse_spec(spec).moments()
    assert result.facts.format == "primitive"
    p, u = result.properties, result.uncertainty
    assert_within(p.volume, exact.volume, u["volume"])
    assert_within(p.mass, 2.5 * exact.volume, u["mass"])
    assert_within(p.center_of_mass, exact.center, u["center_of_mass"])
    assert_within(p.inertia, 2.5 * inertia_from_second_moments(exact.central), u["inertia"])


def test_same_seed_same_numbers_other_seed_other_numbers():
    a = p3d.props("ellipsoid:1,2,3", method="montecarlo", samples=30_000, seed=42)
    b = p3d.props("ellipsoid:1,2,3", method="montecarlo", samples=30_000, seed=42)
    c = p3d.props("ellipsoid:1,2,3", method="montecarlo", samples=30_000, seed=43)
    assert a.properties.volume == b.properties.volume
    np.testing.assert_array_equal(a.properties.inertia, b.properties.inertia)
    np.testing.assert_array_equal(a.uncertainty["inertia"], b.uncertainty["inertia"])
    assert a.properties.volume != c.properties.volume


def test_inward_wound_mesh_gives_positive_volume_and_says_so(tmp_path):
    tri = icosphere(3)[:, ::-1]
    path = tmp_path / "inward.stl"
    write_ascii_stl(path, tri)
    exact = triangle_moments(tri)
    assert exact.volume < 0
    result = p3d.props(str(path), method="montecarlo", samples=100_000, seed=1)
    assert result.properties.volume > 0
    assert_within(result.properties.volume, -exact.volume, result.uncertainty["volume"])
    assert any("ignores the winding" in w for w in result.warnings)
    assert any("negative" in w for w in result.warnings)


def test_open_mesh_does_not_crash_and_warns(tmp_path):
    path = tmp_path / "open.stl"
    write_ascii_stl(path, icosphere(2)[3:])
    result = p3d.props(str(path), method="montecarlo", samples=20_000, seed=1)
    assert np.isfinite(result.properties.volume) and result.properties.volume > 0
    assert any("open mesh" in w for w in result.warnings)


# --- honest standard errors -----------------------------------------------------------------

def spread_vs_stated(inside_fn, bounds, samples):
    """Empirical std over SEEDS seeds, divided by the RMS of the stated standard errors."""
    volumes, centers, inertias, se_v, se_c, se_i = [], [], [], [], [], []
    for seed in range(SEEDS):
        est = sample(inside_fn, bounds, samples, seed=seed)
        props = mass_properties(est.moments())
        u = est.uncertainty()
        volumes.append(props.volume)
        centers.append(props.center_of_mass)
        inertias.append(props.inertia)
        se_v.append(u["volume"])
        se_c.append(u["center_of_mass"])
        se_i.append(u["inertia"])
    rms = lambda x: np.sqrt(np.mean(np.square(x), axis=0))  # noqa: E731
    return (np.std(volumes, ddof=1) / rms(se_v),
            np.std(centers, axis=0, ddof=1) / rms(se_c),
            np.std(inertias, axis=0, ddof=1) / rms(se_i))


@pytest.mark.parametrize("case", ["mesh", "primitive"])
def test_stated_standard_errors_match_the_spread_over_seeds(case):
    if case == "mesh":
        tri = icosphere(2, (1.0, 0.6, 0.3), (0.2, 0.0, 0.0))
        fn = triangles_inside(tri)
        flat = tri.reshape(-1, 3)
        bounds = Bounds(flat.min(axis=0), flat.max(axis=0))
    else:
        shape = parse_spec("cylinder:1,1,2")
        fn, bounds = shape.inside, shape.bounds()
    ratio_v, ratio_c, ratio_i = spread_vs_stated(fn, bounds, samples=4_000)
    ratios = np.concatenate([[ratio_v], ratio_c, np.diag(ratio_i), ratio_i[np.triu_indices(3, 1)]])
    assert ((ratios > CHI2_LO) & (ratios < CHI2_HI)).all(), ratios


def test_tolerance_picks_enough_samples():
    shape = parse_spec("sphere:1")
    n = samples_for_tolerance(shape.inside, shape.bounds(), 3e-3, seed=0)
    p = np.pi / 6
    assert n == pytest.approx((1 - p) / p / 3e-3 ** 2, rel=0.1)
    result = p3d.props("sphere:1", method="montecarlo", tolerance=3e-3, seed=0)
    rel = result.uncertainty["volume"] / result.properties.volume
    assert rel == pytest.approx(3e-3, rel=0.1)


# --- against the divergence formulas and trimesh, over random shapes ------------------------

@settings(max_examples=10)
@given(seed=st.integers(0, 2**32 - 1), stretch=st.floats(0.2, 5.0), offset=st.floats(-100.0, 100.0))
def test_montecarlo_agrees_with_divergence_formulas_and_trimesh(seed, stretch, offset):
    rng = np.random.default_rng(seed)
    hull = trimesh.convex.convex_hull(rng.normal(size=(30, 3)) * [1.0, stretch, 1.0])
    tri = np.asarray(hull.triangles) + [offset, 0.0, 0.0]
    exact = triangle_moments(tri)
    est = sample(triangles_inside(tri), Bounds(tri.reshape(-1, 3).min(0), tri.reshape(-1, 3).max(0)),
                 40_000, seed=seed)
    props, u = mass_properties(est.moments()), est.uncertainty()
    ref = mass_properties(exact)
    assert_within(props.volume, ref.volume, u["volume"])
    assert_within(props.center_of_mass, ref.center_of_mass, u["center_of_mass"])
    assert_within(props.inertia, ref.inertia, u["inertia"])
    # trimesh is right here (closed, consistently wound, near the origin): it agrees with the
    # divergence formulas to rounding.
    moved = trimesh.Trimesh(hull.vertices + [offset, 0.0, 0.0], hull.faces, process=False)
    assert moved.volume == pytest.approx(ref.volume, rel=1e-9)
    np.testing.assert_allclose(moved.center_mass, ref.center_of_mass, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(moved.moment_inertia, ref.inertia, rtol=1e-7,
                               atol=1e-7 * np.abs(ref.inertia).max())


# --- the command line -----------------------------------------------------------------------

def shapes_of(value):
    return None if value is None else np.shape(value)


def test_cli_json_names_the_method_and_gives_standard_errors(tmp_path):
    path = tmp_path / "part.stl"
    write_binary_stl(path, icosphere(2))
    args = ["props", str(path), "--method", "montecarlo", "--samples", "5000", "--seed", "9", "--json"]
    first = CliRunner().invoke(cli, args)
    again = CliRunner().invoke(cli, args)
    assert first.exit_code == 0, first.output
    assert first.stdout == again.stdout
    record = json.loads(first.stdout)
    assert record["method"] == "montecarlo"
    u = record["uncertainty"]
    for key in ("volume", "mass", "center_of_mass", "inertia"):
        assert shapes_of(u[key]) == shapes_of(record[key]), key
    assert 0 < u["volume"] < 0.1 * record["volume"]


def test_cli_exact_json_uncertainty_has_the_estimates_shapes(tmp_path):
    path = tmp_path / "part.stl"
    write_binary_stl(path, icosphere(2))
    result = CliRunner().invoke(cli, ["props", str(path), "--json"])
    record = json.loads(result.stdout)
    assert record["method"] == "exact"
    for key in ("volume", "mass", "center_of_mass", "inertia"):
        assert shapes_of(record["uncertainty"][key]) == shapes_of(record[key]), key


def test_cli_table_names_the_method_and_tolerance_works():
    result = CliRunner().invoke(cli, ["props", "sphere:1", "--method", "montecarlo", "--tolerance", "0.01"])
    assert result.exit_code == 0, result.output
    assert "method: montecarlo" in result.stdout


def test_cli_refuses_sampling_options_without_montecarlo():
    result = CliRunner().invoke(cli, ["props", "sphere:1", "--samples", "100"])
    assert result.exit_code == 2
    assert "--method montecarlo" in result.output


@pytest.mark.parametrize("source", ["wedge:1,2,3", "cylinder:1,1,2", "mesh"])
def test_placed_inputs_agree_with_the_exact_placed_result(tmp_path, source):
    from p3d_cli.geometry.placement import Placement

    if source == "mesh":
        source = str(tmp_path / "part.stl")
        write_ascii_stl(source, torus())
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    placement = Placement(scale=np.array([1.0, 2.0, 0.5]), rotation=rot, translation=np.array([5.0, -3.0, 1e6]))
    exact = p3d.props(source, placement)
    result = p3d.props(source, placement, method="montecarlo", samples=100_000, seed=5)
    p, u = result.properties, result.uncertainty
    assert_within(p.volume, exact.properties.volume, u["volume"])
    assert_within(p.center_of_mass, exact.properties.center_of_mass, u["center_of_mass"])
    assert_within(p.inertia, exact.properties.inertia, u["inertia"])
