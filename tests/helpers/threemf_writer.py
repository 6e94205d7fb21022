"""A small 3MF writer for tests, written by hand from the 3MF Core Specification and the
Production Extension (not from p3d's reader): model parts with mesh objects, components,
build items and transforms, ``p:path`` references, and any extra package member."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
PRODUCTION = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06"
MODEL_REL = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"


def transform_attr(matrix: np.ndarray | None) -> str:
    """A column-vector 4 x 4 matrix as 3MF's row-vector ``transform`` (m00 m01 m02 ... m32)."""
    if matrix is None:
        return ""
    rows = np.vstack([matrix[:3, :3].T, matrix[:3, 3]])
    return ' transform="' + " ".join(repr(float(x)) for x in rows.reshape(-1)) + '"'


def mesh_object(oid, vertices, faces, name: str = "", kind: str = "model", triangle_extra: str = "",
                extra: str = "") -> str:
    vs = "".join(f'<vertex x="{x!r}" y="{y!r}" z="{z!r}"/>' for x, y, z in np.asarray(vertices, float).tolist())
    ts = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"{triangle_extra}/>' for a, b, c in np.asarray(faces).tolist())
    named = f' name="{name}"' if name else ""
    return (f'<object id="{oid}" type="{kind}"{named}><mesh><vertices>{vs}</vertices><triangles>{ts}</triangles>'
            f"{extra}</mesh></object>")


def component_object(oid, components, name: str = "") -> str:
    """``components``: (objectid, matrix or None, path or None) triples."""
    named = f' name="{name}"' if name else ""
    body = "".join(f'<component objectid="{c}"{transform_attr(m)}' + (f' p:path="{p}"' if p else "") + "/>"
                   for c, m, p in components)
    return f'<object id="{oid}" type="model"{named}><components>{body}</components></object>'


def model(objects: list[str], items=(), unit: str | None = "millimeter", required: str = "",
          namespaces: str = "") -> str:
    """A model part; ``items``: (objectid, matrix or None, path or None) triples."""
    build = "".join(f'<item objectid="{o}"{transform_attr(m)}' + (f' p:path="{p}"' if p else "") + "/>"
                    for o, m, p in items)
    unit_attr = f' unit="{unit}"' if unit else ""
    req = f' requiredextensions="{required}"' if required else ""
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<model xmlns="{CORE}" xmlns:p="{PRODUCTION}"{namespaces}'
            f"{unit_attr}{req}><resources>{''.join(objects)}</resources><build>{build}</build></model>")


def package(path: Path, root: str, parts: dict[str, str | bytes] | None = None, root_name: str = "3D/3dmodel.model",
            compression=zipfile.ZIP_DEFLATED) -> Path:
    """Write a 3MF: ``root`` as the root model part, and ``parts`` (name -> text or bytes) beside it."""
    rels = (f'<?xml version="1.0" encoding="UTF-8"?><Relationships xmlns="http://schemas.openxmlformats.org/'
            f'package/2006/relationships"><Relationship Target="/{root_name}" Id="rel0" Type="{MODEL_REL}"/>'
            "</Relationships>")
    types = ('<?xml version="1.0" encoding="UTF-8"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/'
             'content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.'
             'relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.'
             '3dmanufacturing-3dmodel+xml"/></Types>')
    with zipfile.ZipFile(path, "w", compression) as archive:
        archive.writestr("[Content_Types].xml", types)
        archive.writestr("_rels/.rels", rels)
        archive.writestr(root_name, root)
        for name, data in (parts or {}).items():
            archive.writestr(name, data)
    return Path(path)
