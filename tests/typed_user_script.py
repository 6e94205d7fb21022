"""A user's script written against the documented API (docs/api.md): it must type-check with
mypy at its default settings (tests/test_api_typing.py) and run."""

from __future__ import annotations

import json
import sys

import numpy as np

import p3d_cli as p3d


def report(path: str) -> dict[str, object]:
    result: p3d.PropsResult = p3d.props(path, density=7850.0)
    volume: float = result.volume
    mass: float = result.mass
    centre = result.center_of_mass          # None for a shape of no volume
    inertia = result.inertia
    if centre is not None and inertia is not None:
        print(f"{path}: {volume:.6g} m^3, {mass:.6g} kg at {centre.tolist()}, Ixx {float(inertia[0, 0]):.6g}")
    if result.bounds is not None:
        print(" size", result.bounds.size.tolist())
    record: dict[str, object] = result.to_dict()
    line: str = result.to_json()
    assert json.loads(line) == json.loads(json.dumps(record))
    return record


def main(paths: list[str]) -> int:
    placement = p3d.Placement(rotation=p3d.rotation_from_axis_degrees("z", 30), translation=np.array([0, 0, 1.0]))
    box: p3d.BoundsResult = p3d.bounds("box:1,2,3", placement)
    print("box from", box.min.tolist(), "to", box.max.tolist(), "diagonal", box.diagonal)
    shape = p3d.parse_shape("cylinder:0.5,0.5,2")
    print("cylinder mass", p3d.props(shape, density=2700.0).mass)
    triangles = np.array([[[0, 0, 0], [0, 1, 0], [1, 0, 0]], [[0, 0, 0], [1, 0, 0], [0, 0, 1]],
                          [[0, 0, 0], [0, 0, 1], [0, 1, 0]], [[1, 0, 0], [0, 1, 0], [0, 0, 1]]], dtype=float)
    print("tetrahedron volume", p3d.props(triangles).volume)
    status = 0
    for path in paths:
        try:
            report(path)
            verdict: p3d.CheckResult = p3d.check(path)
            if not verdict.ok:
                print(path, "fails", ", ".join(verdict.failed), file=sys.stderr)
                status = 1
        except OSError as error:                # missing or unreadable (p3d.ReadError)
            print("cannot read:", error, file=sys.stderr)
            status = 2
        except ValueError as error:             # corrupt file, bad value (p3d.InputError, p3d.UsageError)
            print("bad input:", error, file=sys.stderr)
            status = 2
        except p3d.P3DError as error:
            print(error.where, error.what, error.hint, file=sys.stderr)
            status = 2
    scene = p3d.load_scene("examples/pendulum.yaml")
    solved: p3d.SolveResult = p3d.solve_scene(scene)
    print("kinetic energy after", solved.kinetic_energy[1], "rank", solved.rank, solved.to_dict()["rank"])
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
