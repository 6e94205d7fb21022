"""The stated bound covers compositions: nested assemblies, placements, mirrors and unit factors.

Every ``uncertainty`` p3d states is an a-priori bound on the rounding error against exact
arithmetic on the same float inputs (docs/accuracy.md, "Placed parts and assemblies"). These
property tests build random nested assemblies of small closed meshes (some far from their own
origin, some placed far out and brought back by an outer rotation and translation, mirrored,
in mm or inches, with densities and masses with units), measure them, and compare with the
rational oracle of ``helpers.exact_assembly``: the error never exceeds the stated bound.

``HYPOTHESIS_PROFILE=thorough pytest tests/measure/test_composition_bounds.py -s`` prints the worst
error/bound ratio seen (docs/accuracy.md quotes it).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from helpers.exact_assembly import EXACT_LENGTHS, ExactPart, combine, error_ratios, whole_of
from hypothesis import given, note
from hypothesis import strategies as st

import p3d_cli as p3d
from p3d_cli.geometry.placement import Placement
from p3d_cli.geometry.rotation import rotation_from_axis_degrees, rotation_from_quaternion
from p3d_cli.measure.assembly.parts import Assembly, Part

CUBE = p3d.parse_shape("box:1,1,1").triangles()
#: Every error/bound ratio per quantity over the run (summarised at the end with -s).
SEEN: dict[str, list[float]] = {}


def _record(ratios: dict[str, float]) -> None:
    for key, value in ratios.items():
        SEEN.setdefault(key, []).append(value)


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    for key, values in sorted(SEEN.items()):
        v = np.array(values)
        print(f"\n{key}: {v.size} results, worst error/bound {v.max():.6g}, median {np.median(v):.2g}, "
              f"90th percentile {np.quantile(v, 0.9):.2g}, exact (error 0) {np.mean(v == 0):.0%}", end="")


@st.composite
def meshes(draw):
    """A closed hexahedron (a cube with moved corners: 12 triangles), of size 1e-3 .. 1e3,
    sometimes far from its own origin (up to 1e6 sizes)."""
    corners = np.array(draw(st.lists(st.floats(-0.3, 0.3), min_size=24, max_size=24))).reshape(8, 3)
    size = 10.0 ** draw(st.floats(-3, 3))
    far = draw(st.sampled_from([0.0, 0.0, 1e3, 1e6]))
    direction = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
    # Corner k of box:1,1,1 is at (±1, ±1, ±1); move each of its copies in the triangles alike.
    moved = CUBE.copy()
    for k, corner in enumerate(np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T):
        moved[np.all(CUBE == corner, axis=2)] += corners[k]
    return (moved + far * direction) * size


@st.composite
def rotations(draw):
    kind = draw(st.sampled_from(["none", "quat", "turn"]))
    if kind == "none":
        return None
    if kind == "turn":
        return rotation_from_axis_degrees(draw(st.sampled_from("xyz")), draw(st.floats(-180, 180)))
    q = draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 0.1))
    return rotation_from_quaternion(*q)


@st.composite
def translations(draw):
    if draw(st.booleans()):
        return None
    magnitude = 10.0 ** draw(st.floats(-3, 9))
    return np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * magnitude


@st.composite
def placements(draw, uniform: bool):
    signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0, 1.0]), min_size=3, max_size=3)))
    if uniform:
        scale = signs * 10.0 ** draw(st.floats(-2, 2)) if draw(st.booleans()) else None
    else:
        scale = signs * 10.0 ** np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
        scale = scale if draw(st.booleans()) else None
    return Placement(scale, draw(rotations()), draw(translations()))


def _materials(draw, units) -> dict:
    """A part's density or mass as an assembly file gives them (with a unit when the
    assembly has units)."""
    kind = draw(st.sampled_from(["none", "density", "mass"]))
    value = draw(st.sampled_from(["0.5", "7.85", "2700", "1.1e-3", "19.3"]))
    if kind == "none":
        return {}
    if units is None:
        return {kind: float(value)}
    return {kind: f"{value} {'kg/m^3' if kind == 'density' else 'kg'}"}


@st.composite
def assemblies(draw, depth: int, units):
    """A nested ``Assembly`` of up to three parts per level, ``depth`` levels deep."""
    own_units = units
    if units is not None and draw(st.booleans()):
        own_units = draw(st.sampled_from(["mm", "in", "m"]))      # a nested file with its own unit
    parts = []
    for i in range(draw(st.integers(1, 3))):
        if depth > 0 and draw(st.booleans()):
            inner = draw(assemblies(depth - 1, own_units))
            placement = draw(placements(uniform=True))
            if draw(st.booleans()):
                # Far out and brought back: the outer placement undoes most of an inner one's
                # translation (the case whose rounding once escaped the bound).
                far = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3))) * 1e8
                inner = Assembly(inner.source, tuple(
                    Part(p.name, p.thing, Placement(p.placement.scale, p.placement.rotation,
                                                    far if p.placement.translation is None
                                                    else p.placement.translation + far), p.density, p.mass, p.where)
                    for p in inner.parts), inner.units)
                r = np.eye(3) if placement.rotation is None else placement.rotation
                s = 1.0 if placement.scale is None else placement.scale[0]
                back = -(r @ (s * far)) + np.array(draw(st.lists(st.floats(-2, 2), min_size=3, max_size=3)))
                placement = Placement(placement.scale, placement.rotation, back)
            parts.append(Part(f"a{i}", inner, placement, where=f"a{i}"))
        else:
            parts.append(Part(f"m{i}", draw(meshes()), draw(placements(uniform=False)), where=f"m{i}",
                              **_materials(draw, units)))
    return Assembly(f"asm{depth}", tuple(parts), own_units)


def exact_parts(assembly: Assembly, units, output=Fraction(1)) -> list[ExactPart]:
    """The exact leaves of ``assembly`` in the output frame (length unit ``output`` metres):
    each leaf's coordinates and every translation scaled by its file's exact unit factor, each
    level's placement applied in turn, densities and masses exactly as written (a mass gives
    the density of the placed part)."""
    return [ExactPart(e.volume, e.center, e.central, e.density if mass is None else mass / abs(e.volume))
            for e, mass in _leaves(assembly, units, output)]


def _leaves(assembly: Assembly, units, output):
    own = assembly.units or units
    f = EXACT_LENGTHS[own] / output if own is not None else Fraction(1)
    out = []
    for part in assembly.parts:
        pl = part.placement
        t = None if pl.translation is None else [x * f for x in map(Fraction, pl.translation.tolist())]
        if isinstance(part.thing, Assembly):
            out += [(e.placed(pl.scale, pl.rotation, t), m) for e, m in _leaves(part.thing, own, output)]
            continue
        e = ExactPart.of_triangles(part.thing).placed([f, f, f]).placed(pl.scale, pl.rotation, t)
        amount = part.density if part.density is not None else part.mass
        value = Fraction(1) if amount is None else Fraction(amount.split()[0] if isinstance(amount, str) else amount)
        if part.mass is not None:
            out.append((e, value))
        else:
            out.append((ExactPart(e.volume, e.center, e.central, value), None))
    return out


@given(st.data())
def test_nested_assemblies_stay_within_their_bounds(data):
    units = data.draw(st.sampled_from([None, None, "mm", "in"]))
    assembly = data.draw(assemblies(2, units))
    note(repr(assembly))
    result = p3d.props(assembly)
    ratios = error_ratios(result, combine(exact_parts(assembly, None)))
    _record(ratios)
    note(repr(ratios))
    assert max(ratios.values()) <= 1.0, ratios


@given(meshes(), placements(uniform=False), st.sampled_from([None, "mm", "in", "ft", "cm"]),
       st.sampled_from([None, "mm,g", "in,lb"]))
def test_placed_parts_with_unit_factors_stay_within_their_bounds(triangles, placement, units, output):
    output = None if units is None else output
    result = p3d.props(triangles, placement, units=units, output_units=output)
    exact = ExactPart.of_triangles(triangles).placed(placement.scale, placement.rotation, placement.translation)
    if units is not None:
        length = (output or "m").split(",")[0]
        mass_unit = {"g": Fraction(1, 1000), "kg": Fraction(1), "lb": Fraction("0.45359237")}[
            (output or "m,kg").split(",")[1]]
        f = EXACT_LENGTHS[units] / EXACT_LENGTHS[length]
        # Default density 1 in the output units.
        exact = ExactPart(exact.volume, exact.center, exact.central).placed([f, f, f])
        del mass_unit
    ratios = error_ratios(result, whole_of(exact))
    _record(ratios)
    assert max(ratios.values()) <= 1.0, ratios


def test_a_nested_assemblys_mass_spread_over_far_parts_stays_within_its_bounds():
    # The group's k = target / Σ m carries the parts' mass errors into every part's mass and
    # inertia; the parts sit 1e8 out in the nested file and are brought back by its placement.
    rng = np.random.default_rng(7)
    far = np.array([1e8, -2e8, 3e7])
    turn = rotation_from_axis_degrees("z", 33.0)
    meshes_ = [CUBE * rng.uniform(0.5, 2.0, 3) + rng.uniform(-1, 1, 3) for _ in range(3)]
    inner = Assembly("inner", tuple(Part(f"m{i}", t, Placement(translation=far + i), where=f"m{i}")
                                    for i, t in enumerate(meshes_)))
    outer = Assembly("outer", (Part("group", inner, Placement(rotation=turn, translation=-(turn @ far)),
                                    mass="2.5 kg", where="group"),
                               Part("plate", CUBE * [3.0, 3.0, 0.1], where="plate", density="7.85 g/cm^3")), "mm")
    result = p3d.props(outer)
    f = EXACT_LENGTHS["mm"]
    parts = [ExactPart.of_triangles(t).placed([f] * 3).placed(None, None, [Fraction(x) * f for x in (far + i)])
             .placed(None, turn, [Fraction(x) * f for x in -(turn @ far)]) for i, t in enumerate(meshes_)]
    k = Fraction(5, 2) / sum(p.volume for p in parts)           # default density 1, scaled to 2.5 kg
    parts = [ExactPart(p.volume, p.center, p.central, k) for p in parts]
    plate = ExactPart.of_triangles(CUBE * [3.0, 3.0, 0.1]).placed([f] * 3)
    parts.append(ExactPart(plate.volume, plate.center, plate.central, Fraction(7850)))
    ratios = error_ratios(result, combine(parts))
    _record(ratios)
    assert max(ratios.values()) <= 1.0, ratios
    assert result.properties.mass == pytest.approx(2.5 + 7850 * 36 * 0.2 * 1e-9, rel=1e-15)


@given(st.lists(st.tuples(rotations(), translations()), min_size=1, max_size=6), meshes(),
       st.sampled_from([None, [1.0, 1.0, -1.0], [-0.5, 2.0, 1.0]]))
def test_links_placed_through_a_chain_of_frames_stay_within_their_bounds(frames, triangles, mesh_scale):
    # A robot link's geom: its own scale (a mirrored mesh: scale="1 1 -1"), then the frames of
    # the bodies above it, innermost first, composed one by one as the robot readers do
    # (``then(own, frame)``), then measured as the link's assembly of geoms.
    from p3d_cli.geometry.placement import then

    placement = Placement(None if mesh_scale is None else np.array(mesh_scale))
    exact = ExactPart.of_triangles(triangles).placed(placement.scale)
    for rotation, translation in frames:
        placement = then(placement, Placement(None, rotation, translation))
        exact = exact.placed(None, rotation, translation)
    link = Assembly("link", (Part("geom", triangles, placement, density=1000.0, where="geom"),
                             Part("cap", triangles * 0.5, placement, density=1000.0, where="cap")))
    cap = ExactPart.of_triangles(triangles * 0.5).placed(placement.scale)
    for rotation, translation in frames:
        cap = cap.placed(None, rotation, translation)
    result = p3d.props(link)
    ratios = error_ratios(result, combine([ExactPart(e.volume, e.center, e.central, Fraction(1000)) for e in (exact, cap)]))
    _record(ratios)
    assert max(ratios.values()) <= 1.0, ratios
