"""The documented limits of the readers, and the bounded reads that enforce them.

A file can describe far more than it holds: a zlib stream inflates about a thousandfold, a zip
member declares any size, and a scene graph that instances a node twice, which instances the
next twice, places 2^n copies in n lines ("billion laughs"). Readers never expand what a file
describes without these bounds (docs/scene-formats.md, "Limits"):

- ``MAX_INFLATED``: bytes one compressed input may inflate to (a zipped AMF's model, the zlib
  blocks of one VTK XML file, all arrays together), checked against what the file declares
  before anything is inflated, and against what really comes out while inflating;
- ``MAX_INSTANCES``: mesh instances one scene file may place (COLLADA geometry instances
  through nodes and ``instance_node``, AMF constellation instances), counted over the graph
  before any is placed;
- ``MAX_PLACED_FACES``: triangles those instances may place in all.

Every limit is far above what real files reach (a 25-million-triangle VTK file inflates to
about 1 GiB; the largest scenes of the test corpus place a few thousand instances) and far
below what would exhaust the memory or the patience of a run.
"""

from __future__ import annotations

import zlib

from p3d_cli.errors import FormatError

#: Bytes one input may inflate to (1 GiB).
MAX_INFLATED = 1 << 30
#: Mesh instances one scene file may place.
MAX_INSTANCES = 100_000
#: Triangles one scene file may place, over all its instances.
MAX_PLACED_FACES = 1 << 28


def check_declared(where: str, declared: int, what: str) -> None:
    """Refuse ``declared`` inflated bytes beyond ``MAX_INFLATED`` before inflating anything.

    Raises
    ------
    FormatError
    """
    if declared > MAX_INFLATED:
        raise FormatError(where, f"{what} declares {declared:,} bytes once inflated, more than p3d inflates "
                          f"({MAX_INFLATED:,} bytes)", "write the file uncompressed, or check that it is "
                          "what it claims to be (a compression bomb declares far more than it holds)")


def inflate(where: str, data: bytes, size: int, what: str) -> bytes:
    """The zlib stream ``data``, which must inflate to exactly ``size`` bytes; never more.

    Raises
    ------
    FormatError
        The stream is corrupt, inflates to more or less than ``size``, or ``size`` is beyond
        ``MAX_INFLATED``.
    """
    check_declared(where, size, what)
    stream = zlib.decompressobj()
    try:
        # One byte more than declared: enough to tell a stream that inflates to more.
        out = stream.decompress(data, size + 1)
        if len(out) <= size:
            out += stream.flush()
    except zlib.error as exc:
        raise FormatError(where, f"{what} cannot be inflated ({exc})", "the file is corrupt; export it again") from None
    if len(out) != size:
        found = "more than the" if len(out) > size else f"{len(out):,} bytes, not the"
        raise FormatError(where, f"{what} inflates to {found} {size:,} bytes it declares",
                          "the file is corrupt; export it again")
    return out


def read_member(where: str, archive, info, what: str) -> bytes:
    """A zip member's bytes, bounded by the size the archive declares for it and by
    ``MAX_INFLATED`` (Python's zipfile stops at the declared size and then checks the CRC, so a
    member that inflates to more than it declares is an error, not a bomb).

    Raises
    ------
    FormatError
    """
    check_declared(where, info.file_size, what)
    with archive.open(info) as member:
        data = member.read(info.file_size + 1)
    if len(data) != info.file_size:
        raise FormatError(where, f"{what} holds {len(data):,} bytes, not the {info.file_size:,} the archive "
                          "declares", "the archive is corrupt; export it again")
    return data


def check_instances(where: str, instances: int, faces: int, what: str) -> None:
    """Refuse a scene that places more than ``MAX_INSTANCES`` mesh instances or more than
    ``MAX_PLACED_FACES`` triangles (counted over its graph, before anything is placed).

    Raises
    ------
    FormatError
    """
    if instances > MAX_INSTANCES:
        raise FormatError(where, f"its {what} place {instances:,} mesh instances, more than p3d places "
                          f"({MAX_INSTANCES:,})", "merge the instances into meshes, or check the file: a "
                          "graph that instances each level twice grows as 2^depth")
    if faces > MAX_PLACED_FACES:
        raise FormatError(where, f"its {what} place {faces:,} triangles, more than p3d places "
                          f"({MAX_PLACED_FACES:,})", "measure the meshes apart, or check the file's instancing")


#: Depth of nested 3MF components (an object made of objects made of objects...): deeper than
#: any real file. The walks are iterative; glTF node trees and XML elements are walked without
#: recursion too, and need no depth limit (a 20,000-deep node chain reads).
NESTING_DEPTH = 1000

#: Bytes of a ``.gltf`` file's JSON (a GLB's JSON chunk is bounded by the file itself).
GLTF_JSON_BYTES = 1 << 30
