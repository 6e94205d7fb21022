"""Damaged scene files: every truncation or byte flip is a result or one P3DError, never another
exception (seeded mutations of valid files, so the run is the same every time)."""

from __future__ import annotations

import random
import zipfile
from io import BytesIO

import numpy as np
import pytest
import trimesh

import p3d_cli as p3d
from p3d_cli.errors import P3DError

BOX = trimesh.creation.box(extents=(1.0, 2.0, 3.0))


def valid(kind: str) -> bytes:
    scene = trimesh.Scene()
    scene.add_geometry(BOX, node_name="a", transform=np.diag([0.5, 1, 1, 1]))
    scene.add_geometry(BOX, node_name="b", transform=trimesh.transformations.translation_matrix([3, 0, 0]))
    if kind in ("glb", "3mf"):
        return scene.export(file_type=kind)
    if kind == "dae":
        return BOX.export(file_type="dae")
    if kind == "amf":
        from test_scene_formats import amf_text

        return amf_text().encode()
    from test_vtk_polydata import vtp

    return vtp("binary", compressed=True)


def mutations(data: bytes, seed: int, count: int):
    rng = random.Random(seed)
    for _ in range(count):
        choice = rng.random()
        if choice < 0.3:
            yield data[:rng.randrange(1, len(data))]
        else:
            out = bytearray(data)
            for _ in range(rng.randrange(1, 4)):
                out[rng.randrange(len(out))] = rng.randrange(256)
            yield bytes(out)


@pytest.mark.parametrize("kind", ["glb", "3mf", "dae", "amf", "vtp"])
def test_damaged_files_are_results_or_one_error(tmp_path, kind):
    data = valid(kind)
    path = tmp_path / f"damaged.{kind}"
    for i, damaged in enumerate(mutations(data, seed=len(kind) * 7919 + ord(kind[0]), count=40)):
        path.write_bytes(damaged)
        try:
            result = p3d.props(path)
        except P3DError:
            continue
        except Exception as exc:  # noqa: BLE001 - the point of the test
            pytest.fail(f"mutation {i} of {kind} raised {type(exc).__name__}: {exc}")
        assert np.isfinite(result.properties.volume)


def test_3mf_inside_a_damaged_zip_member(tmp_path):
    """A 3MF whose model is not XML at all."""
    buffer = BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("3D/3dmodel.model", b"\x00\xff not xml")
    path = tmp_path / "bad.3mf"
    path.write_bytes(buffer.getvalue())
    with pytest.raises(P3DError):
        p3d.props(path)
