"""Monte Carlo mass properties: an estimate that needs nothing but an inside test.

Points are drawn uniformly in the solid's axis-aligned bounding box ``B`` (numpy's
``default_rng(seed)``, so one seed always gives the same numbers). With the inside indicator
``I`` (0 or 1; 0.5 where an open mesh's rays disagree, see ``p3d_cli.mesh.winding``) and the
box-normalised coordinates ``u = (x - b) / h`` (``b`` the box centre, ``h`` its half-size), the
sample means ``m0 = ⟨I⟩``, ``m1 = ⟨I u⟩``, ``m2 = ⟨I u uᵀ⟩`` give

- volume ``V = |B| m0``,
- centre ``c = b + h ∘ m1 / m0``,
- central second moments ``C_ij = h_i h_j |B| (m2 - m1 m1ᵀ / m0)_ij``,

and the inertia ``I = ρ (tr(C) E - C)``. Each is a smooth function ``g`` of the mean vector
``m`` (10 numbers), so its standard error follows from the delta method:
``Var(g(m̄)) ≈ J Σ Jᵀ / N``, with ``Σ`` the sample covariance of the 10 summands and ``J``
the Jacobian of ``g`` (taken by central differences; ``g`` is a rational function, smooth where
``m0 > 0``). The tests check these stated errors against the spread over many seeds.

Sampling is plain (independent, uniform): slow (error ``∝ 1/√N``) but honest, whatever the
shape. Box-normalised coordinates keep the sums well scaled whatever the part's size, and
points drawn about a local ``origin`` (the translation, or a mesh's box centre) reach the inside
test unrounded however far the part is (world coordinates at 3e15 are 0.5 apart). With fewer
than ``MIN_INSIDE`` points inside, the delta method is not trusted (one point gives the centre
a zero error) and ``conservative_errors`` states bounds (docs/accuracy.md, "Few samples inside").
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from p3d_cli.errors import RangeError, UsageError
from p3d_cli.geometry.inertia import density_for, inertia_from_second_moments, mass_properties
from p3d_cli.geometry.placement import IDENTITY, Placement
from p3d_cli.measure.exact import mesh_facts, mesh_warnings
from p3d_cli.measure.confidence import _PAIRS, ALPHA, _central, clopper_pearson, conservative_errors  # noqa: F401
from p3d_cli.measure.solid import Solid
from p3d_cli.mesh.analysis import analyze
from p3d_cli.results import Bounds, MeshFacts, Moments, PropsResult
from p3d_cli.warning_codes import CodedWarning

#: Points drawn per chunk (the random stream is consumed chunk by chunk, so the chunk size is
#: part of what "the same seed gives the same numbers" means: do not change it lightly).
CHUNK = 1 << 17
#: Default sample count and seed of ``p3d props --method montecarlo``.
DEFAULT_SAMPLES = 100_000
DEFAULT_SEED = 0
#: Pilot run used by ``tolerance`` to learn the inside fraction, and the limits on N.
PILOT_SAMPLES = 20_000
MIN_SAMPLES = 1_000
MAX_SAMPLES = 100_000_000
#: Fewest inside samples for delta-method standard errors; below it, conservative bounds (at 300
#: inside, inertia's ±3σ misses up to 0.8 % of runs on thin rotated solids: docs/accuracy.md).
MIN_INSIDE = 1_000



@dataclass(frozen=True)
class Estimate:
    """Sample statistics of one Monte Carlo run (box-normalised coordinates).

    Attributes
    ----------
    bounds : Bounds
        The sampled box.
    samples : int
    seed : int
    mean : (10,) float64
        ``m0, m1 (3), m2 (xx, yy, zz, xy, xz, yz)``.
    covariance : (10, 10) float64
        Sample covariance of the summands (divide by ``samples`` for the mean's).
    origin : (3,) float64 or None
        The world position of the frame of ``bounds`` (None: the world origin).
    """

    bounds: Bounds
    samples: int
    seed: int | tuple[int, int]
    mean: np.ndarray
    covariance: np.ndarray
    origin: np.ndarray | None = None

    @property
    def box_volume(self) -> float:
        return float(np.prod(self.bounds.size))

    @property
    def inside(self) -> float:
        """How many samples fell inside (a sum of weights: half-inside points count 0.5)."""
        return float(self.mean[0] * self.samples)

    @property
    def conservative(self) -> bool:
        """True when too few samples fell inside for standard errors (``MIN_INSIDE``)."""
        return self.inside < MIN_INSIDE

    def moments(self) -> Moments:
        """The estimated ``Moments`` (volume is unsigned: the inside test ignores winding)."""
        m = self.mean
        half, centre = 0.5 * self.bounds.size, self.bounds.center
        # In units of a power of two near the box (exact), so that a tiny part's box volume
        # (size³) and second moments (size⁵) are formed without passing through an underflow.
        scaled, length = self._scaled_half()
        box = float(np.prod(2.0 * scaled))
        volume = float(np.ldexp(box * m[0], 3 * length))   # inf past float64: refused by the caller
        if not m[0] > 0:
            return Moments(0.0, None, None)
        center = centre + half * m[1:4] / m[0]      # in the sampled frame, then moved once
        if self.origin is not None:
            center = self.origin + center
        central = np.ldexp(_central(m, box) * np.outer(scaled, scaled), 5 * length)
        return Moments(float(volume), center, central)

    def uncertainty(self, density: float | None = None, mass: float | None = None) -> dict:
        """Standard errors of the reported quantities, keyed like the estimates (with fewer
        than ``MIN_INSIDE`` samples inside, the bounds of ``conservative_errors``).

        Returns
        -------
        dict
            ``volume`` (float), ``mass`` (float), ``center_of_mass`` (3,) and ``inertia``
            (3, 3); the last two None when no sample fell inside.
        """
        m = self.mean
        if self.conservative:
            return conservative_errors(self, density, mass)
        # Mass and inertia are linear in the density (or the mass given): differentiate at
        # unit density or mass and scale the errors after, so that a mass near float64's largest
        # does not overflow the finite differences (whose steps are 1e-6 of m0).
        factor = mass if mass is not None else (1.0 if density is None else density)
        unit_density, unit_mass = (None, 1.0) if mass is not None else (1.0, None)
        # Lengths in units of a power of two near the box (exact): the covariance holds squares
        # of the errors, which for a part of 1e-33 (inertia ~1e-165) would underflow to 0 and
        # state "± 0"; the errors are scaled back after the square root.
        half, length = self._scaled_half()
        box = float(np.prod(2.0 * half))
        f = lambda x: _reported(x, box, half, unit_density, unit_mass)  # noqa: E731
        jac = _jacobian(f, m, step=1e-6 * m[0])
        cov = jac @ self.covariance @ jac.T / self.samples
        se = np.sqrt(np.maximum(np.diag(cov), 0.0))
        se[1] *= factor
        se[5:] *= factor
        volume_power = 3 if mass is None else 0
        se[0:2] = np.ldexp(se[0:2], [3 * length, volume_power * length])
        se[2:5] = np.ldexp(se[2:5], length)
        se[5:] = np.ldexp(se[5:], (5 if mass is None else 2) * length)
        out = {"volume": float(se[0]), "mass": float(se[1]), "center_of_mass": se[2:5],
               "inertia": se[5:14].reshape(3, 3)}
        if self.samples - self.inside < MIN_INSIDE:
            # Few points fell outside (a solid filling most of its box): the inside fraction's
            # standard error is as unreliable as with few inside, and with none outside it is 0.
            # Never state "± 0" for an estimate that can be wrong: at least Clopper-Pearson's.
            bounds = conservative_errors(self, density, mass)
            out["volume"] = max(out["volume"], bounds["volume"])
            out["mass"] = max(out["mass"], bounds["mass"])
        return out

    def underflows(self) -> bool:
        """True when the estimated volume or a second moment, non-zero in box units, falls
        below float64's normal range in world units (a part too small: a few bits left)."""
        m = self.mean
        if not m[0] > 0:
            return False
        scaled, length = self._scaled_half()
        box = float(np.prod(2.0 * scaled))
        tiny = np.finfo(np.float64).tiny
        moments = self.moments()
        central = np.diag(_central(m, box) * np.outer(scaled, scaled))
        return abs(moments.volume) < tiny or bool(np.any((central != 0) & (np.abs(np.diag(moments.central)) < tiny)))

    def _scaled_half(self) -> tuple[np.ndarray, int]:
        """The box's half-size in units of ``2**length`` (a power of two near it), and ``length``."""
        half = 0.5 * self.bounds.size
        length = int(np.frexp(float(half.max()))[1])
        return np.ldexp(half, -length), length


def _reported(m, box_volume, half, density, mass) -> np.ndarray:
    """``volume, mass, centre (3), inertia (9)`` from the mean vector (centre without the
    constant box centre, which has no error)."""
    volume = box_volume * m[0]
    rho = density_for(volume, density, mass)
    central = _central(m, box_volume) * np.outer(half, half)
    inertia = rho * inertia_from_second_moments(central)
    return np.concatenate([[volume, rho * volume], half * m[1:4] / m[0], inertia.reshape(-1)])


def _jacobian(f: Callable, x: np.ndarray, step: float) -> np.ndarray:
    """Central-difference Jacobian of ``f`` at ``x`` (error ~ step², far below an error's)."""
    cols = []
    for k in range(len(x)):
        d = np.zeros_like(x)
        d[k] = step
        cols.append((f(x + d) - f(x - d)) / (2 * step))
    return np.array(cols).T


def sample(inside: Callable[[np.ndarray], np.ndarray], bounds: Bounds, samples: int,
           seed: int | tuple[int, int] = DEFAULT_SEED, *, origin=None) -> Estimate:
    """Draw ``samples`` points uniformly in ``bounds`` and average the inside indicator.

    Parameters
    ----------
    inside : callable
        ``inside(points (k, 3) float64) -> (k,) bool or float`` indicator in [0, 1], for points
        in the frame of ``bounds``.
    bounds : Bounds
        The box to sample, relative to ``origin``.
    samples : int
    seed : int, or a pair of ints
        numpy's ``default_rng`` seed (a pair gives an independent stream, e.g. for a pilot run).
    origin : (3,) array_like, optional
        The world position of the frame of ``bounds`` and ``inside`` (default: the world
        origin). A far part sampled about a local origin keeps its points unrounded.

    Returns
    -------
    Estimate
    """
    samples = check_samples(samples)
    rng = np.random.default_rng(seed)
    half, centre = 0.5 * bounds.size, bounds.center
    total = np.zeros(10)
    outer = np.zeros((10, 10))
    done = 0
    while done < samples:
        k = min(CHUNK, samples - done)
        u = rng.random((k, 3)) * 2.0 - 1.0
        weight = np.asarray(inside(centre + half * u), dtype=np.float64)
        f = np.empty((k, 10))
        f[:, 0] = weight
        f[:, 1:4] = weight[:, None] * u
        for col, (i, j) in enumerate(_PAIRS, start=4):
            f[:, col] = f[:, 1 + i] * u[:, j]
        total += f.sum(axis=0)
        outer += f.T @ f
        done += k
    mean = total / samples
    covariance = (outer - samples * np.outer(mean, mean)) / (samples - 1)
    if origin is not None:
        origin = np.asarray(origin, dtype=np.float64).reshape(3)
    return Estimate(bounds, samples, seed, mean, covariance, origin)


def check_samples(samples) -> int:
    """``samples`` as an int in [2, ``MAX_SAMPLES``], refused before any point is drawn.

    The upper limit keeps a run to minutes, not days (1e13 points would take weeks): the
    error falls only as ``1/√N``, so 1e8 points already give a relative error near 1e-4.
    """
    samples = int(samples)
    if samples < 2:
        raise UsageError("samples", f"{samples} is too few", "give at least 2 (thousands for a useful answer)")
    if samples > MAX_SAMPLES:
        raise UsageError("samples", f"{samples} is over the limit of {MAX_SAMPLES:,} samples",
                         f"give at most {MAX_SAMPLES}; the error falls only as 1/sqrt(samples), "
                         "so average independent seeds if you need more")
    return samples


def samples_for_tolerance(inside: Callable, bounds: Bounds, tolerance: float,
                          seed: int = DEFAULT_SEED) -> int:
    """Samples needed for a relative standard error ``tolerance`` on the volume.

    A pilot run (its own random stream, derived from ``seed``) estimates the inside fraction
    ``p`` and the indicator's variance ``s²``; the volume's relative standard error is
    ``s / (p √N)``, so ``N = s² / (p² tolerance²)``, raised to put 1.25 ``MIN_INSIDE`` points
    inside (standard errors, not bounds) and clipped to [MIN_SAMPLES, MAX_SAMPLES] (a cap that
    falls short of the tolerance is warned about by ``montecarlo_props``).
    """
    if not (tolerance > 0 and math.isfinite(tolerance)):
        raise UsageError("tolerance", f"{tolerance!r} is not a positive relative error",
                         "give e.g. tolerance=1e-3 for 0.1 %")
    pilot = sample(inside, bounds, PILOT_SAMPLES, seed=(int(seed), 1))
    p, var = float(pilot.mean[0]), float(pilot.covariance[0, 0])
    if not p > 0:
        return MAX_SAMPLES
    # (s / (p tolerance))² formed as a square of a quotient, so that a tiny tolerance gives
    # inf (then the cap) rather than 0 / 0 = nan; a solid filling its box has s = 0.
    ratio = math.sqrt(max(var, 0.0)) / p
    spread = ratio / tolerance if ratio > 0 else 0.0
    need = max(spread * spread, 1.25 * MIN_INSIDE / p)  # a float product: inf, never an exception
    if not need < MAX_SAMPLES:
        return MAX_SAMPLES
    return int(max(MIN_SAMPLES, math.ceil(need)))


def triangles_inside(triangles: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """An inside test for a triangle mesh (ray parity over a face grid)."""
    from p3d_cli.mesh.winding import face_grid, inside

    grid = face_grid(triangles)
    return lambda points: inside(grid, points)


def montecarlo_moments(inside: Callable, bounds: Bounds, *, samples: int | None = None,
                       seed: int = DEFAULT_SEED, tolerance: float | None = None, origin=None) -> Estimate:
    """Run the estimate with ``samples`` points, or as many as ``tolerance`` needs (``bounds``
    and ``inside`` relative to ``origin``, as for ``sample``)."""
    if tolerance is not None:
        samples = samples_for_tolerance(inside, bounds, tolerance, seed)
    elif samples is None:
        samples = DEFAULT_SAMPLES
    return sample(inside, bounds, samples, seed, origin=origin)


def montecarlo_props(solid: Solid, placement: Placement = IDENTITY, *, samples: int | None = None,
                     seed: int | None = None, tolerance: float | None = None,
                     density: float | None = None, mass: float | None = None, about=None) -> PropsResult:
    """Monte Carlo mass properties of a resolved mesh or shape.

    Parameters
    ----------
    solid : Solid
    placement : Placement
        Scale, rotate and move the solid before sampling.
    samples : int, optional
        Points to draw (default ``DEFAULT_SAMPLES``, at most ``MAX_SAMPLES``); ignored when
        ``tolerance`` is given.
    seed : int, optional
        Random seed (default ``DEFAULT_SEED``): the same seed gives the same numbers.
    tolerance : float, optional
        Target relative standard error of the volume; picks the sample count (at most
        ``MAX_SAMPLES``: a tolerance that needs more runs the cap and warns, however small).
    density, mass, about
        As for ``p3d_cli.measure.exact.exact_props``.

    Returns
    -------
    PropsResult
        ``method`` is ``"montecarlo"``; ``uncertainty`` holds standard errors, or (with a
        warning) conservative bounds when fewer than ``MIN_INSIDE`` samples fell inside.

    Raises
    ------
    InputError, UsageError
    """
    with np.errstate(all="ignore"):  # out-of-range results end in one RangeError instead
        return _montecarlo_props(solid, placement, samples, seed, tolerance, density, mass, about)


def _montecarlo_props(solid, placement, samples, seed, tolerance, density, mass, about) -> PropsResult:
    seed = DEFAULT_SEED if seed is None else int(seed)
    setup = _shape_setup if solid.shape is not None else _mesh_setup
    inside, bounds, origin, facts, warnings = setup(solid, placement)
    estimate, moments = None, Moments(0.0, None, None)
    if not np.all(np.isfinite(bounds.size)):
        raise RangeError(solid.source, "the placed solid's bounding box overflows float64 (the part is too "
                         "large)", "measure in a larger unit (e.g. m instead of mm)")
    if np.all(bounds.size > 0):
        estimate = montecarlo_moments(inside, bounds, samples=samples, seed=seed, tolerance=tolerance,
                                      origin=origin)
        moments = estimate.moments()
        if estimate.underflows():
            raise RangeError(solid.source, "the volume or its second moments underflow float64 (the part is too "
                             "small)", "measure in a smaller unit (e.g. mm instead of m)")
    if moments.is_empty and mass is not None:
        raise UsageError("mass", "the Monte Carlo estimate found no volume, so no density "
                         "follows from a mass", "give density=, or more samples=")
    props = mass_properties(moments, density=density, mass=mass, about=about, where=solid.source)
    if estimate is None:
        uncertainty = {"volume": 0.0, "mass": 0.0, "center_of_mass": None, "inertia": None}
        warnings.append(CodedWarning("the solid's bounding box is flat, so nothing was sampled: centre of mass "
                                     "and inertia are undefined", "montecarlo-flat-box"))
    else:
        uncertainty = estimate.uncertainty(density=props.density if mass is None else None, mass=mass)
        warnings += sampling_warnings(estimate, uncertainty["volume"], tolerance)
        _check_uncertainty(uncertainty, solid.source)
    details: dict = {"samples": 0 if estimate is None else estimate.samples, "seed": seed}
    if not placement.is_identity:
        details["placement"] = placement.describe()
    return PropsResult(facts, props, "montecarlo", tuple(warnings), uncertainty, details)


def _check_uncertainty(uncertainty: dict, where: str) -> None:
    """Standard errors are finite (they are at most about the values, which are checked)."""
    for key, value in uncertainty.items():
        if value is not None and not np.all(np.isfinite(value)):
            raise RangeError(where, f"the Monte Carlo error of the {key.replace('_', ' ')} overflows float64",
                             "measure in units that keep the numbers nearer 1")


def sampling_warnings(estimate: Estimate, volume_error: float, tolerance: float | None = None) -> list[CodedWarning]:
    """Warnings for too few samples inside, and for a ``tolerance`` the sample cap did not meet."""
    out: list[tuple[str, str]] = []     # (code, text)
    k, n = estimate.inside, estimate.samples
    if not k > 0:
        out.append(("montecarlo-empty", f"no Monte Carlo sample of {n} fell inside the solid: centre of mass and "
                    "inertia are undefined, and the volume's uncertainty is a conservative bound, not a standard "
                    "error; use more samples or check the mesh"))
    elif estimate.conservative:
        out.append(("montecarlo-few-inside", f"only {k:g} of {n} Monte Carlo samples fell inside the solid (fewer "
                    f"than {MIN_INSIDE}): the uncertainties are conservative bounds, not standard errors; use about "
                    f"{math.ceil(1.25 * MIN_INSIDE * n / k):d} samples or more for standard errors"))
    volume = estimate.box_volume * estimate.mean[0]
    if tolerance is not None and n >= MAX_SAMPLES and not volume_error <= tolerance * volume:
        got = f"{volume_error / volume:.2g}" if volume > 0 else "unbounded"
        out.append(("montecarlo-cap", f"tolerance={tolerance:g} needs more than the cap of {MAX_SAMPLES} samples: "
                    f"stopped there with a relative volume error of {got}; accept it, or loosen the tolerance"))
    return [CodedWarning(text, code) for code, text in out]


def _shape_setup(solid: Solid, placement: Placement):
    """The placed shape's inside test and box, relative to its translation (so that the shape's
    own test sees ``q = (p - t) R`` computed without ever forming the far world point ``p``)."""
    scaled = placement.shape(solid.shape)
    rotation = placement.rotation
    bounds = scaled.bounds(rotation, None)
    facts = MeshFacts(solid.source, "primitive", 0, None, scaled.bounds(rotation, placement.translation))
    inside = scaled.inside if rotation is None else (lambda q: scaled.inside(q @ rotation))
    return inside, bounds, placement.translation, facts, list(solid.warnings)


def _mesh_setup(solid: Solid, placement: Placement):
    mesh = solid.mesh
    if mesh.tetrahedra is not None:
        tets = np.asarray(mesh.tetrahedra)
        # Every face of every tetrahedron: shared inner faces are crossed twice, which parity
        # ignores, so the soup's inside is the volume mesh's inside.
        triangles = tets[:, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]].reshape(-1, 3, 3)
    else:
        triangles = mesh.triangles()    # read once; the analysis below reuses the array
        mesh = dataclasses.replace(mesh, read_blocks=lambda: iter([triangles]))
    found = analyze(mesh, mesh.where, rescale=True)     # scaled moments: the warnings are scale-free
    facts = mesh_facts(solid, found)
    warnings = list(mesh.warnings) + mesh_warnings(found.moments, facts)
    if not found.moments.is_empty and found.moments.volume < 0:
        warnings.append(CodedWarning("Monte Carlo's inside test ignores the winding, so its volume and mass "
                                     "are positive (about |exact signed volume|)", "montecarlo-winding"))
    if facts.closed is False:
        warnings.append(CodedWarning("Monte Carlo on an open mesh: a point whose up and down rays disagree "
                                     "(the ray escapes through a hole) counts as half inside", "montecarlo-open"))
    # Sample about the scaled, rotated mesh's box centre; the translation is added once, at the end.
    flat = Placement(placement.scale, placement.rotation).points(np.asarray(triangles, dtype=np.float64).reshape(-1, 3))
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    shift = np.zeros(3) if placement.translation is None else placement.translation
    facts = dataclasses.replace(facts, bounds=Bounds(lo + shift, hi + shift))   # rounding is monotone
    flat = flat - 0.5 * (lo + hi)       # a new array: the mesh's own stays as read
    bounds = Bounds(flat.min(axis=0), flat.max(axis=0))
    return triangles_inside(flat.reshape(-1, 3, 3)), bounds, 0.5 * (lo + hi) + shift, facts, warnings


__all__ = ["Estimate", "sample", "check_samples", "MAX_SAMPLES", "samples_for_tolerance",
           "montecarlo_moments", "montecarlo_props",
           "triangles_inside", "conservative_errors", "clopper_pearson", "sampling_warnings",
           "DEFAULT_SAMPLES", "DEFAULT_SEED", "MIN_INSIDE", "ALPHA"]
