"""Coverage-guided fuzzing of one target with atheris (``pip install atheris``), for long runs.

Usage::

    python tests/fuzz/run_atheris.py TARGET [libFuzzer options]
    python tests/fuzz/run_atheris.py ply -max_total_time=3600 -rss_limit_mb=2048 corpus-ply/

TARGET is one of ``targets.TARGETS`` (stl, obj, ply, off, gltf, glb, 3mf, dae, amf, vtp, scene, scene_steps,
urdf, mjcf, sdf, robot_fill). The run starts from the
target's seeds (written to the corpus folder if it is empty); any exception other than a
P3DError, a crash, a timeout or a memory blow-up stops it with the input that caused it, which
then belongs in ``tests/fuzz/corpus/TARGET/`` (docs/fuzzing.md).
"""

from __future__ import annotations

import os
import sys

import atheris

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))   # tests/: helpers

with atheris.instrument_imports(include=["p3d_cli"]):
    from targets import TARGETS, seeds

    import p3d_cli.constraints.scene  # noqa: F401 - the scene targets' code, instrumented too
    import p3d_cli.constraints.simulation  # noqa: F401
    import p3d_cli.io.amf  # noqa: F401 - the readers are imported on first use: instrument them here
    import p3d_cli.io.dae  # noqa: F401
    import p3d_cli.io.formats  # noqa: F401
    import p3d_cli.io.gltf  # noqa: F401
    import p3d_cli.io.threemf  # noqa: F401
    import p3d_cli.io.vtp  # noqa: F401
    import p3d_cli.measure.exact  # noqa: F401 - instrumented before the targets import them
    import p3d_cli.robots  # noqa: F401 - the robot targets' readers, checks and fill
    import p3d_cli.robots.check  # noqa: F401
    import p3d_cli.robots.fill  # noqa: F401
    import p3d_cli.robots.mjcf  # noqa: F401
    import p3d_cli.robots.sdf  # noqa: F401
    import p3d_cli.robots.urdf  # noqa: F401
    import p3d_cli.robots.xmltree  # noqa: F401


def main() -> None:
    if len(sys.argv) < 2 or sys.argv[1] not in TARGETS:
        sys.exit(f"usage: {sys.argv[0]} TARGET [libFuzzer options]; targets: {', '.join(TARGETS)}")
    name = sys.argv.pop(1)
    folders = [a for a in sys.argv[1:] if not a.startswith("-")]
    for folder in folders:
        os.makedirs(folder, exist_ok=True)
        if not os.listdir(folder):
            for i, data in enumerate(seeds(name)):
                with open(os.path.join(folder, f"seed-{i}"), "wb") as f:
                    f.write(data)
    atheris.Setup(sys.argv, TARGETS[name])
    atheris.Fuzz()


if __name__ == "__main__":
    main()
