"""3MF (3D Manufacturing Format): the zip package slicers and CAD write today.

Read here (zip + a streaming XML parser, ``p3d_cli.io.threemf.model``) after the 3MF Core
Specification 1.3 and its Production Extension 1.1; no optional library is needed. What is
measured:

- the **build**: every ``<item>`` of the root model part (the one ``_rels/.rels`` names), placed
  by its ``transform``, through its object's ``<components>`` (each placed by its own
  transform, nested to any depth up to ``limits.NESTING_DEPTH``); every placed mesh object is
  one part, whatever its materials (a mesh object is one set of triangles);
- **production extension**: an item or a component with ``p:path`` names an object in another
  model part, read once however often it is referenced; the build sections of those parts
  are ignored, as the extension requires, so an external part referenced twice counts twice;
- the root model's ``unit`` (micron, millimeter, centimeter, inch, foot, meter; millimetre by
  default: core §3.4) is the length unit of every coordinate;
- transforms act on row vectors, ``p' = p M`` (core §3.3.1); one that mirrors reverses the
  faces (core §4.1, via ``p3d_cli.io.scene``).

Refused by name: beam lattices with beams or balls, boolean shapes, displacement meshes, level
sets (p3d measures triangles only), encrypted parts, zip members stored with a method other
than store or deflate (the only two OPC allows), and any extension the model lists in
``requiredextensions`` that p3d does not know, as the core specification requires (§2.3.1).
Only the model parts are read: thumbnails, textures and slicer settings are never inflated.
"""

from __future__ import annotations

import posixpath
import urllib.parse
import zipfile
import zlib
from xml.etree import ElementTree

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import limits
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, scene_source, unique_names
from p3d_cli.io.source import MeshSource
from p3d_cli.io.threemf.model import CORE, PRODUCTION, Model, Object, parse
from p3d_cli.warning_codes import CodedWarning

#: The ``unit`` values of the 3MF core specification, in metres.
UNITS = {"micron": 1e-6, "millimeter": 1e-3, "centimeter": 1e-2, "inch": 0.0254, "foot": 0.3048, "meter": 1.0}
MODEL_RELATIONSHIP = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"
_NS = "http://schemas.microsoft.com/3dmanufacturing/"
#: Extensions p3d reads or that change no measured geometry (materials, slices beside the mesh,
#: triangle sets, alternatives). Beam lattices are known: a lattice with beams is refused.
KNOWN_EXTENSIONS = {CORE, PRODUCTION, _NS + "material/2015/02", _NS + "slice/2015/07",
                    _NS + "beamlattice/2017/02", _NS + "beamlattice/balls/2020/07", _NS + "trianglesets/2021/07",
                    _NS + "production/alternatives/2021/04"}
SECURE_CONTENT = _NS + "securecontent/2019/04"
#: Bytes of ``_rels/.rels`` read at most (a real one is a few hundred).
RELS_BYTES = 1 << 20
CORRUPT = "the file is corrupt; export it again"

Key = tuple[str, str]   # (model part, object id)


class _Package:
    """The zip archive and the model parts read from it (each once)."""

    def __init__(self, where: str, archive: zipfile.ZipFile) -> None:
        self.where = where
        self.archive = archive
        self.names = {name.lower(): name for name in archive.namelist()}
        self.models: dict[str, Model] = {}

    def member(self, part: str) -> zipfile.ZipInfo:
        name = self.names.get(part.lower())
        if name is None:
            raise FormatError(self.where, f"the package lacks the part {part!r}", CORRUPT)
        info = self.archive.getinfo(name)
        if info.flag_bits & 1:
            raise FormatError(self.where, f"{part} is encrypted, which p3d does not read",
                              "export the 3MF without encryption")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise FormatError(self.where, f"{part} is compressed with zip method {info.compress_type}; "
                              "3MF (OPC) allows only store and deflate", "export the 3MF again")
        return info

    def root(self) -> str:
        """The root model part: the 3D model relationship of ``_rels/.rels`` (else the
        conventional ``3D/3dmodel.model``)."""
        if "_rels/.rels" in self.names:
            info = self.member("_rels/.rels")
            if info.file_size > RELS_BYTES:
                raise FormatError(self.where, f"_rels/.rels inflates to {info.file_size:,} bytes", CORRUPT)
            data = self._read(info)
            if b"<!DOCTYPE" in data:
                raise FormatError(self.where, "_rels/.rels declares a DOCTYPE, which OPC never uses", CORRUPT)
            try:
                rels = ElementTree.fromstring(data)
            except ElementTree.ParseError as exc:
                raise FormatError(self.where, f"_rels/.rels is not well-formed XML ({exc})", CORRUPT) from None
            for rel in rels:
                if rel.get("Type") == MODEL_RELATIONSHIP and rel.get("Target"):
                    return part_name(rel.get("Target", ""))
        if "3d/3dmodel.model" in self.names:
            return "3D/3dmodel.model"
        raise FormatError(self.where, "is not a 3MF package (no 3D model part)", "export it again as 3MF")

    def _read(self, info: zipfile.ZipInfo) -> bytes:
        try:
            return self.archive.read(info)
        except (zipfile.BadZipFile, zlib.error, EOFError, OSError) as exc:
            raise FormatError(self.where, f"{info.filename} cannot be inflated ({exc})", CORRUPT) from None

    def model(self, part: str) -> Model:
        key = part.lower()
        if key not in self.models:
            info = self.member(part)
            try:
                with self.archive.open(info) as stream:
                    self.models[key] = parse(stream, info.file_size, self.where, part)
            except (zipfile.BadZipFile, zlib.error, EOFError, OSError) as exc:
                raise FormatError(self.where, f"{part} cannot be inflated ({exc})", CORRUPT) from None
        return self.models[key]


def part_name(path: str) -> str:
    """An OPC part name (``/3D/part.model``, percent-encoded) as a zip member name."""
    return posixpath.normpath(urllib.parse.unquote(path)).lstrip("/")


class _Build:
    """Resolves items and components to placed mesh objects (iteratively, each object counted
    once however often it is referenced)."""

    def __init__(self, package: _Package, root: str) -> None:
        self.package = package
        self.root = root
        self.where = package.where
        #: Per object: the faces, vertices and mesh instances it places, and its nesting depth.
        self.sizes: dict[Key, tuple[int, int, int, int]] = {}

    def object(self, key: Key) -> Object:
        model = self.package.model(key[0])
        if key[1] not in model.objects:
            raise FormatError(self.where, f"{key[0]}: a build item or component names object {key[1]!r}, "
                              "which the part lacks", CORRUPT)
        return model.objects[key[1]]

    def children(self, key: Key) -> list[tuple[Key, np.ndarray]]:
        out = []
        for oid, path, matrix in self.object(key).components:
            if path and key[0].lower() != self.root.lower() and part_name(path).lower() != key[0].lower():
                # Production extension §3.2: only the root model's components may name other parts.
                raise FormatError(self.where, f"{key[0]}: a component names another part ({path!r}); only the "
                                  "root model's components may", CORRUPT)
            out.append(((part_name(path) if path else key[0], oid), matrix))
        return out

    def size(self, start: Key) -> tuple[int, int, int, int]:
        """Triangles, vertices and mesh instances ``start`` places, and its nesting depth,
        without expanding."""
        stack: list[tuple[Key, bool]] = [(start, False)]
        visiting: set[Key] = set()
        while stack:
            key, done = stack.pop()
            if key in self.sizes:
                continue
            obj = self.object(key)
            kids = self.children(key)
            if done:
                visiting.discard(key)
                sub = [self.sizes[k] for k, _ in kids]
                faces = (0 if obj.faces is None else len(obj.faces)) + sum(s[0] for s in sub)
                vertices = (0 if obj.vertices is None else len(obj.vertices)) + sum(s[1] for s in sub)
                own = obj.faces is not None and len(obj.faces) > 0
                instances = int(own) + sum(s[2] for s in sub)
                depth = 1 + max((s[3] for s in sub), default=0)
                if depth > limits.NESTING_DEPTH:
                    raise FormatError(self.where, f"object {key[1]} nests components {depth} deep, deeper than "
                                      f"p3d follows ({limits.NESTING_DEPTH})", CORRUPT)
                self.sizes[key] = (faces, vertices, instances, depth)
                continue
            if key in visiting:
                raise FormatError(self.where, f"object {key[1]} is its own component (a cycle)", CORRUPT)
            visiting.add(key)
            stack.append((key, True))
            stack.extend((k, False) for k, _ in kids if k not in self.sizes)
        return self.sizes[start]

    def placed(self, start: Key, matrix: np.ndarray):
        """Every mesh object under ``start`` with its whole transform, in document order."""
        stack = [(start, matrix)]
        while stack:
            key, outer = stack.pop()
            obj = self.object(key)
            if obj.faces is not None and len(obj.faces) or obj.refused:
                yield key, obj, outer
            stack.extend((k, outer @ m) for k, m in reversed(self.children(key)))


def _check_required(where: str, models: list[Model]) -> None:
    for model in models:
        for uri in model.required:
            if uri == SECURE_CONTENT:
                raise FormatError(where, "it requires the 3MF Secure Content extension (encrypted parts), "
                                  "which p3d does not read", "export the 3MF without encryption")
            if uri not in KNOWN_EXTENSIONS:
                raise FormatError(where, f"it requires the extension {uri[:100]!r}, which p3d does not know; "
                                  "the 3MF specification says a consumer must then refuse the file",
                                  "export the 3MF without that extension")


def load(raw: RawInput) -> MeshSource:
    """Read a 3MF package (see the module's description).

    Raises
    ------
    FormatError
        Not a 3MF package, a unit the specification does not define, a required extension or
        a construct p3d does not measure, a broken reference, or an expansion past
        ``p3d_cli.io.limits``.
    InputError
        No triangles.
    """
    if raw.head(2) != b"PK":
        raise FormatError(raw.where, "is not a 3MF package (not a zip archive)", "export it again as 3MF")
    try:
        with raw.open() as stream, zipfile.ZipFile(stream) as archive:
            return _load(raw, _Package(raw.where, archive))
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError) as exc:
        raise FormatError(raw.where, f"is not a readable 3MF package ({exc})", "export it again as 3MF") from None


def _load(raw: RawInput, package: _Package) -> MeshSource:
    root = package.root()
    model = package.model(root)
    _check_required(raw.where, [model])
    unit = model.unit.strip().lower()
    if unit not in UNITS:
        raise FormatError(raw.where, f"declares unit {unit!r}, which 3MF does not define",
                          "use one of " + ", ".join(UNITS))
    build = _Build(package, root)
    items = [((part_name(path) if path else root, oid), matrix) for oid, path, matrix in model.items]
    faces = vertices = instances = 0
    for key, _ in items:
        size = build.size(key)
        faces, vertices, instances = faces + size[0], vertices + size[1], instances + size[2]
    limits.check_instances(raw.where, instances, faces, "build items and components")
    if vertices > 3 * limits.MAX_PLACED_FACES:
        raise FormatError(raw.where, f"its build items and components place {vertices:,} vertices, more than p3d "
                          f"places ({3 * limits.MAX_PLACED_FACES:,})", "measure the objects apart")
    _check_required(raw.where, list(package.models.values()))
    found: list[tuple[str, Object, np.ndarray]] = []
    kinds: dict[str, int] = {}
    lowres = 0
    for item, partnumber in zip(items, model.partnumbers):
        for key, obj, matrix in build.placed(*item):
            if obj.refused:
                raise FormatError(raw.where, f"object {obj.id} ({obj.name or 'unnamed'}) is {obj.refused}, "
                                  "which p3d does not measure", "export the lattice or shape as a triangle mesh")
            if obj.type not in ("model", "solidsupport"):
                kinds[obj.type] = kinds.get(obj.type, 0) + 1
            lowres += obj.lowres
            # An item's own mesh is named by the item's partnumber where it has one.
            name = partnumber if key == item[0] and partnumber else obj.name
            found.append((name or f"object {obj.id}", obj, matrix))
    if not items:
        raise InputError(raw.where, "its build lists no items (the package prints nothing)",
                         "export the 3MF with the objects placed on the build plate")
    notes = [CodedWarning(f"{count} placed objects are of type {kind!r}; they are measured with the rest", "reader")
             for kind, count in sorted(kinds.items())]
    if lowres:
        notes.append(CodedWarning(f"{lowres} placed meshes are marked low resolution (their slices are the real "
                                  "geometry)", "reader"))
    units = {m.unit.strip().lower() for m in package.models.values()}
    if len(units) > 1:
        notes.append(CodedWarning(f"the model parts declare different units ({', '.join(sorted(units))}); the root "
                                  f"part's {unit} is used for all", "unit-slip"))
    names = unique_names([name for name, _, _ in found])
    empty = np.zeros((0, 3))
    # scene_source checks every face against its object's vertices before anything is placed.
    objects = [SceneObject(n, empty if obj.vertices is None else obj.vertices, obj.faces, matrix)
               for n, (_, obj, matrix) in zip(names, found)]
    return scene_source("3mf", raw.where, objects, UNITS[unit], "objects (build items and their components)",
                        tuple(notes))
