"""Documented limits of the scene readers (glTF/GLB, 3MF): what a file may make p3d read,
inflate and expand, whatever it declares.

A file is refused with one error naming the limit when it would pass one. The limits are far
above any real model (the largest real glTF seen holds 7.7 million placed triangles) and low
enough that a hostile file cannot exhaust the memory of a 24 GB machine or hold it for minutes.
They are module constants, so a test can lower them to make a bomb small: a bound that trips
at 1 MB trips at 1 GB.
"""

from __future__ import annotations

#: Triangles after every placement, instance and component is expanded (one file). Each costs
#: about 40 bytes while it is measured (its placed corners and its face), so this is ~4 GB.
PLACED_TRIANGLES = 100_000_000

#: Bytes of one 3MF model part once inflated (the XML text); the zip's declared size is
#: checked before anything is inflated, and the inflated bytes are counted as they come.
MODEL_PART_BYTES = 1 << 31

#: Depth of nested 3MF components (an object made of objects made of objects...): deeper than
#: any real file. The walks are iterative; glTF node trees and XML elements are walked without
#: recursion too, and need no depth limit (a 20,000-deep node chain reads).
NESTING_DEPTH = 1000

#: Bytes of a ``.gltf`` file's JSON (a GLB's JSON chunk is bounded by the file itself).
GLTF_JSON_BYTES = 1 << 30


def too_many_triangles(count: int) -> str:
    """The ``what`` of the error for a file that expands past ``PLACED_TRIANGLES``."""
    return (f"its instances and components place {count:,} triangles, more than p3d reads from one file "
            f"({PLACED_TRIANGLES:,})")
