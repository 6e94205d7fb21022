"""Pictures of parts, defects and inertia: headless, numpy only (``p3d render``; docs/render.md).

- ``picture``: ``picture(thing, view=..., show=...) -> Picture`` and the ``Picture`` value;
- ``geometry``: the triangles of a mesh, shape or assembly in one frame;
- ``camera``: named views, azimuth/elevation, the orthographic fit;
- ``raster``: the z-buffer; ``shade``: lighting and outlines;
- ``overlays``, ``defects``, ``draw``: what is drawn over the part and how;
- ``legend``, ``font``: the title and legend in a built-in bitmap font;
- ``png``, ``svg``, ``files``: the writers (PNG with the standard library's zlib);
- ``notebook``: how results show themselves in Jupyter.

Names are imported on first use, as in the package's face: ``import p3d_cli.render`` is cheap.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

_API = {
    "picture": "p3d_cli.render.picture",
    "Picture": "p3d_cli.render.image",
    "write_picture": "p3d_cli.render.files",
    "VIEWS": "p3d_cli.render.camera",
    "SHOW": "p3d_cli.render.overlays",
    "encode_png": "p3d_cli.render.png",
    "decode_png": "p3d_cli.render.png",
}

__all__ = ["picture", "Picture", "write_picture", "VIEWS", "SHOW", "encode_png", "decode_png"]


def __getattr__(name: str) -> Any:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'p3d_cli.render' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


if TYPE_CHECKING:
    from p3d_cli.render.camera import VIEWS
    from p3d_cli.render.files import write_picture
    from p3d_cli.render.overlays import SHOW
    from p3d_cli.render.image import Picture
    from p3d_cli.render.picture import picture
    from p3d_cli.render.png import decode_png, encode_png
