"""Parts too small or too large for float64's comfortable range are rescaled (by a power of two,
exactly) or refused, never silently wrong; Monte Carlo never states "± 0" for an estimate that
can be wrong (issue 27, item 5)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from helpers.exact_assembly import ExactPart, error_ratios, whole_of
from p3d_cli.cli.main import cli
from p3d_cli.errors import RangeError
from p3d_cli.geometry.placement import Placement
from p3d_cli.geometry.rotation import rotation_from_axis_degrees

WEDGE = p3d.parse_shape("wedge:1,2,3").triangles() + [0.25, -0.5, 0.125]


@pytest.mark.parametrize("size", [1e-64, 1e-150, 1e-290, 1e64, 1e150, 1e95])
def test_a_tiny_or_huge_part_scaled_to_size_one_is_right_to_its_bound(size):
    # A mesh of size 1e-64 scaled by 1e64 was 137 % wrong in inertia, silently; its bound NaN.
    triangles = WEDGE * size
    placement = Placement(scale=np.full(3, 1 / size), rotation=rotation_from_axis_degrees("x", 30.0),
                          translation=np.array([1e3, 0.0, -2.0]))
    result = p3d.props(triangles, placement)
    exact = ExactPart.of_triangles(triangles).placed(placement.scale, placement.rotation, placement.translation)
    ratios = error_ratios(result, whole_of(exact))
    assert max(ratios.values()) <= 1.0, ratios
    assert all(np.isfinite(np.ravel(v)).all() for v in result.uncertainty.values())
    assert result.properties.volume == pytest.approx(4 * 6, rel=1e-13)
    assert not result.warnings


@pytest.mark.parametrize("size", [1e-33, 1e-50, 1e40])
def test_tiny_and_huge_parts_in_range_are_exact_to_their_bounds(size):
    triangles = WEDGE * size
    result = p3d.props(triangles)
    ratios = error_ratios(result, whole_of(ExactPart.of_triangles(triangles)))
    assert max(ratios.values()) <= 1.0, ratios
    assert result.properties.volume == pytest.approx(24 * size ** 3, rel=1e-14)


@pytest.mark.parametrize("size", [1e-64, 1e-200])
def test_a_part_whose_inertia_underflows_is_refused_in_one_line(tmp_path, size):
    with pytest.raises(RangeError, match="underflow"):
        p3d.props(WEDGE * size)
    path = tmp_path / "tiny.obj"
    v = (WEDGE * size).reshape(-1, 3)
    path.write_text("".join("v %r %r %r\n" % tuple(p) for p in v.tolist())
                    + "".join(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}\n" for i in range(len(v) // 3)))
    for args in (["props", str(path)], ["props", "--json", str(path)]):
        result = CliRunner().invoke(cli, args)
        assert result.exit_code == 2 and "internal error" not in result.output
        assert result.stderr.count("\n") == 1 and "too small" in result.stderr


def test_a_part_of_subnormal_size_is_refused_as_too_small_or_measured_when_scaled_up(tmp_path):
    # Its 2**k (k past 1023) overflowed to an internal error before (found by fuzzing a VTP).
    triangles = WEDGE * 1e-310                     # subnormal coordinates: what they are, exactly
    with pytest.raises(RangeError, match="too small"):
        p3d.props(triangles)
    path = tmp_path / "subnormal.obj"
    v = triangles.reshape(-1, 3)
    path.write_text("".join("v %r %r %r\n" % tuple(p) for p in v.tolist())
                    + "".join(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}\n" for i in range(len(v) // 3)))
    result = CliRunner().invoke(cli, ["props", str(path)])
    assert result.exit_code == 2 and "internal error" not in result.output
    assert result.stderr.count("\n") == 1 and "too small" in result.stderr
    placement = Placement(scale=np.full(3, 1e300))
    scaled = p3d.props(triangles, placement)
    exact = ExactPart.of_triangles(triangles).placed(placement.scale, None, None)
    assert max(error_ratios(scaled, whole_of(exact)).values()) <= 1.0


def test_a_density_that_makes_the_inertia_underflow_is_refused():
    with pytest.raises(RangeError, match="underflow"):
        p3d.props(WEDGE * 1e-50, density=1e-100)


@pytest.mark.parametrize("size", [1e-33, 1e-40, 1e30])
def test_montecarlo_errors_of_tiny_parts_are_the_scaled_errors_of_the_unit_part(size):
    # The covariance holds squared errors: for a part of 1e-33 (inertia 1e-165) they
    # underflowed, and Monte Carlo stated "± 0" for products of inertia.
    one = p3d.props(WEDGE, method="montecarlo", samples=20_000)
    small = p3d.props(WEDGE * size, method="montecarlo", samples=20_000)
    for key, power in (("volume", 3), ("center_of_mass", 1), ("inertia", 5)):
        want = np.asarray(one.uncertainty[key]) * size ** power
        assert np.all(np.asarray(small.uncertainty[key]) > 0)
        np.testing.assert_allclose(small.uncertainty[key], want, rtol=1e-9)
    assert small.properties.volume == pytest.approx(one.properties.volume * size ** 3, rel=1e-12)


def test_montecarlo_never_states_plus_minus_zero_for_a_solid_that_fills_its_box():
    # Every sample inside: the inside fraction's standard error is 0, but the estimate can be
    # wrong (a notch no sample hit); the stated error is at least Clopper-Pearson's.
    n = 10_000
    result = p3d.props("box:1,2,3", method="montecarlo", samples=n)
    assert result.properties.volume == 48.0
    u = result.uncertainty
    assert u["volume"] > 0 and u["mass"] > 0
    # With none outside, the fraction is above (α/2)^(1/N) ≈ 1 - 6.6/N: a third of the gap.
    assert u["volume"] == pytest.approx(48.0 * 6.6 / n / 3, rel=0.01)
    notched = Fraction(48) * (1 - Fraction(1, 10 ** 5))      # what a notch of 1e-5 would give
    assert abs(48.0 - float(notched)) < 3 * u["volume"]
