"""One 3MF model part (``3D/3dmodel.model`` and parts the production extension names), read
as a stream with expat: objects (a mesh, or components), build items, the unit, the required
extensions, and the constructs p3d refuses (beam lattices, boolean shapes, displacement
meshes, level sets).

Written from the 3MF Core Specification 1.3 (§3.4 model and unit, §4 object, mesh, vertex,
triangle, components; §5 build; transforms in §3.3.1) and the Production Extension 1.1 (the
``path`` attribute). The XML is never held whole: expat calls back per element, vertices and
triangles go to numpy in blocks, and element handlers are swapped inside ``<vertices>`` and
``<triangles>`` so that the millions of those elements each cost one Python call. A
``<!DOCTYPE>`` (which 3MF never uses, and which entity bombs need) is refused.
"""

from __future__ import annotations

import io
import re
from dataclasses import dataclass, field
from typing import IO
from xml.parsers import expat

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io import limits

CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
PRODUCTION = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06"
#: Extension elements that add or change geometry in ways p3d does not measure, by local name.
REFUSED = {"beamlattice": "a beam lattice (3MF Beam Lattice extension)",
           "booleanshape": "a boolean shape (3MF Boolean Operations extension)",
           "displacementmesh": "a displacement mesh (3MF Displacement extension)",
           "levelset": "a level set (3MF Volumetric extension)"}
#: Strings converted to numbers per block (bounds the memory of the text collected).
_BLOCK = 3 << 16
CORRUPT = "the file is corrupt; export it again"


@dataclass
class Object:
    """An ``<object>``: a mesh (vertices, faces) or components ``(objectid, path, transform)``."""

    id: str
    name: str
    type: str
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    components: list[tuple[str, str | None, np.ndarray]] = field(default_factory=list)
    refused: str = ""
    lowres: bool = False


@dataclass
class Model:
    """What one model part holds."""

    unit: str = "millimeter"
    required: list[str] = field(default_factory=list)
    objects: dict[str, Object] = field(default_factory=dict)
    items: list[tuple[str, str | None, np.ndarray]] = field(default_factory=list)
    #: Each item's ``partnumber`` ("" when it has none).
    partnumbers: list[str] = field(default_factory=list)


def transform(text: str | None, where: str) -> np.ndarray:
    """A 3MF ``transform`` (12 numbers m00 m01 m02 m10 ... m32, acting on row vectors: p' = p M,
    core §3.3.1) as the 4 x 4 matrix acting on column vectors."""
    out = np.eye(4)
    if text is None:
        return out
    try:
        values = [float(word) for word in text.split()]
    except ValueError:
        values = []
    if len(values) != 12 or not all(np.isfinite(values)):
        raise FormatError(where, f"a transform is not 12 finite numbers ({text[:60]!r})", CORRUPT)
    rows = np.array(values).reshape(4, 3)
    out[:3, :3] = rows[:3].T
    out[:3, 3] = rows[3]
    return out


class _Parser:
    def __init__(self, where: str, part: str) -> None:
        self.where = where
        self.part = part
        self.model = Model()
        self.parser = expat.ParserCreate(namespace_separator=" ")
        self.parser.buffer_text = True
        self.parser.StartElementHandler = self.start
        self.parser.StartDoctypeDeclHandler = self.doctype
        self.parser.StartNamespaceDeclHandler = self.namespace
        self.prefixes: dict[str, str] = {}
        self.object: Object | None = None
        self.in_build = False
        self.text: list[str] = []
        self.blocks: list[np.ndarray] = []
        self.element = ""
        self.rooted = False
        #: Blocks ``_extract`` read ahead, named by the ``FAST_MARK`` attribute it leaves.
        self.fast: list[np.ndarray] = []

    def error(self, what: str) -> FormatError:
        return FormatError(self.where, f"{self.part}: {what}", CORRUPT)

    def doctype(self, *args) -> None:
        raise FormatError(self.where, f"{self.part} declares a DOCTYPE, which 3MF never uses",
                          "the file is corrupt or hostile; export it again")

    def namespace(self, prefix: str | None, uri: str) -> None:
        self.prefixes.setdefault(prefix or "", uri)

    # -- structure -------------------------------------------------------------------------------

    def start(self, name: str, attrs: dict) -> None:
        namespace, _, local = name.rpartition(" ")
        if not self.rooted:
            self.rooted = True
            if local != "model" or namespace not in (CORE, ""):
                raise FormatError(self.where, f"{self.part} is not a 3MF model (its root element is <{local}> "
                                  f"in namespace {namespace or 'none'!r})", "export it again as 3MF")
        if namespace not in (CORE, ""):
            # An empty beam lattice adds nothing; its beams and balls would add volume.
            refused = "beamlattice" if local in ("beam", "ball") else local if local != "beamlattice" else ""
            if refused in REFUSED and self.object is not None:
                self.object.refused = self.object.refused or REFUSED[refused]
            return
        if local == "model":
            self.model.unit = attrs.get("unit", "millimeter")
            self.model.required = [self.prefixes.get(p, p) for p in attrs.get("requiredextensions", "").split()]
        elif local == "object":
            oid = attrs.get("id", "")
            if oid in self.model.objects:
                raise self.error(f"object id {oid!r} is used twice")
            self.object = Object(oid, attrs.get("name", ""), attrs.get("type", "model"))
            # The slice extension's s:meshresolution: "lowres" marks a mesh that only approximates
            # the slices, which are the part's real geometry.
            self.object.lowres = any(k.endswith("meshresolution") and v == "lowres" for k, v in attrs.items())
            self.model.objects[oid] = self.object
        elif local in ("vertices", "triangles") and self.fast and FAST_MARK in attrs:
            self._take(local, attrs[FAST_MARK])
        elif local == "vertices":
            self._collect(local, "vertex", ("x", "y", "z"))
        elif local == "triangles":
            self._collect(local, "triangle", ("v1", "v2", "v3"))
        elif local == "component" and self.object is not None:
            self.object.components.append(self._reference(attrs, "component"))
        elif local == "build":
            self.in_build = True
        elif local == "item" and self.in_build:
            self.model.items.append(self._reference(attrs, "item"))
            self.model.partnumbers.append(attrs.get("partnumber", ""))

    def _reference(self, attrs: dict, what: str) -> tuple[str, str | None, np.ndarray]:
        if "objectid" not in attrs:
            raise self.error(f"a {what} has no objectid")
        return attrs["objectid"], attrs.get(PRODUCTION + " path"), transform(attrs.get("transform"),
                                                                              f"{self.where}: {self.part}")

    # -- vertices and triangles, in blocks ----------------------------------------------------------

    def _take(self, container: str, mark: str) -> None:
        """A ``<vertices>`` or ``<triangles>`` whose content ``_extract`` read beforehand."""
        if self.object is None or not mark.isdigit() or int(mark) >= len(self.fast):
            raise self.error(f"<{container}> outside an object")
        values = self.fast[int(mark)]
        if container == "vertices":
            if self.object.vertices is not None:
                raise self.error(f"object {self.object.id} has a second <vertices>")
            self.object.vertices = values.reshape(-1, 3)
        else:
            if self.object.faces is not None:
                raise self.error(f"object {self.object.id} has a second <triangles>")
            self.object.faces = values.reshape(-1, 3)

    def _collect(self, container: str, element: str, keys: tuple[str, str, str]) -> None:
        if self.object is None:
            raise self.error(f"<{container}> outside an object")
        if (self.object.vertices if element == "vertex" else self.object.faces) is not None:
            raise self.error(f"object {self.object.id} has a second <{container}>")
        self.element = f"{CORE} {element}"
        self.text, self.blocks = [], []
        a, b, c = keys
        append = self.text.append

        def one(name: str, attrs: dict) -> None:
            if name != self.element:
                self._finish(element)
                self.parser.StartElementHandler = self.start
                self.start(name, attrs)
                return
            try:
                append(attrs[a])
                append(attrs[b])
                append(attrs[c])
            except KeyError as exc:
                raise self.error(f"a <{element}> lacks its {exc.args[0]} attribute") from None
            if len(self.text) >= _BLOCK:
                self._convert(element)

        self.parser.StartElementHandler = one

    def _convert(self, element: str) -> None:
        """The strings collected so far as one numpy block (float64 or int64)."""
        text = ",".join(self.text)
        count = len(self.text)
        self.text.clear()
        # np.fromstring with a separator stops at the first word that is not a number: a
        # count short of the strings' means a malformed value (empty, "1 2", "1e", "x").
        dtype = np.float64 if element == "vertex" else np.int64
        values = _parsed(text, dtype) if text else np.zeros(0, dtype)
        if values is None or len(values) != count:
            raise self.error(f"a <{element}> attribute is not a number")
        self.blocks.append(values)

    def _finish(self, element: str) -> None:
        if self.text:
            self._convert(element)
        values = np.concatenate(self.blocks) if self.blocks else np.zeros(0)
        self.blocks = []
        assert self.object is not None
        if element == "vertex":
            self.object.vertices = values.reshape(-1, 3)
        else:
            self.object.faces = values.astype(np.int64, copy=False).reshape(-1, 3)

    def feed(self, stream: IO[bytes], declared: int) -> Model:
        """Parse ``stream`` (at most ``declared`` bytes, the zip's size of the part)."""
        read = 0
        while True:
            chunk = stream.read(1 << 20)
            read += len(chunk)
            if read > declared:
                raise self.error(f"inflates past the {declared:,} bytes the archive declares")
            try:
                self.parser.Parse(chunk, not chunk)
            except expat.ExpatError as exc:
                raise FormatError(self.where, f"{self.part} is not well-formed XML ({exc})", CORRUPT) from None
            except FormatError:
                raise  # the handlers' own, a ValueError too: as it is
            except (LookupError, ValueError) as exc:
                # The XML declaration names an encoding Python lacks (LookupError) or one expat
                # cannot read ("multi-byte encodings are not supported": UTF-7, Shift-JIS).
                if isinstance(exc, ValueError) and "encoding" not in str(exc):
                    raise
                raise FormatError(self.where, f"{self.part} is in an encoding p3d cannot read ({exc})",
                                  CORRUPT) from None
            if not chunk:
                break
        if self.parser.StartElementHandler != self.start and self.object is not None:
            self._finish("vertex" if self.element.endswith("vertex") else "triangle")
        return self.model


#: Parts up to this size are read whole, and their vertex and triangle lists are read by the
#: fast path below; larger parts are streamed element by element (flat memory, ~4x slower).
FAST_PART_BYTES = 1 << 28
#: The attribute the fast path leaves on a ``<vertices>``/``<triangles>`` it emptied.
FAST_MARK = "p3d-block"
_BLOCK_TAGS = ((b"<vertices>", b"</vertices>", "vertex"), (b"<triangles>", b"</triangles>", "triangle"))
#: What an element list may hold once its fixed markup is replaced: numbers and separators.
_NUMBER_BYTES = {"vertex": b"0123456789+-.eE,", "triangle": b"0123456789+,"}
_WHITESPACE = b" \t\r\n"
_MATERIAL_ATTRIBUTES = re.compile(rb'\s+p(?:id|1|2|3)\s*=\s*"[^"]*"')


def _numbers(span: bytes, kind: str) -> np.ndarray | None:
    """The numbers of an element list in the canonical form every writer seen uses
    (``<vertex x="1" y="2" z="3"/>``, ``<triangle v1="0" v2="1" v3="2" .../>``), by a few
    C-speed byte replacements and one numpy parse; None for anything else (other attribute
    order or quoting, entities, extension attributes), which expat then reads element by
    element. Each value must read as exactly one number: a value that is empty, holds a
    space or is malformed changes the count or stops the parse, and the list goes to expat."""
    if b"," in span:   # the separator below: a value holding one is not a number anyway
        return None
    element = b"<" + kind.encode()
    keys = (b"x", b"y", b"z") if kind == "vertex" else (b"v1", b"v2", b"v3")
    count = span.count(element)
    if kind == "triangle" and b" p" in span:
        span = _MATERIAL_ATTRIBUTES.sub(b"", span)
    text = span.replace(element + b" " + keys[0] + b'="', b",")
    for key in keys[1:]:
        text = text.replace(b'" ' + key + b'="', b",")
    text = text.replace(b'" />', b"").replace(b'"/>', b"").strip(_WHITESPACE)
    if text.translate(None, _NUMBER_BYTES[kind] + _WHITESPACE) or not text.startswith(b"," if count else b""):
        return None
    dtype = np.float64 if kind == "vertex" else np.int64
    values = _parsed(text[1:], dtype) if count else np.zeros(0, dtype)
    return values if values is not None and len(values) == 3 * count else None


def _parsed(text: bytes | str, dtype) -> np.ndarray | None:
    """Comma-separated numbers; None where numpy stops early (it warns, or raises, by version)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        try:
            return np.fromstring(text, dtype=dtype, sep=",")
        except (ValueError, DeprecationWarning):
            return None


def _extract(data: bytes) -> tuple[bytes, list[np.ndarray]]:
    """``data`` with the content of each ``<vertices>`` and ``<triangles>`` that ``_numbers``
    reads replaced by a ``FAST_MARK`` naming its block, and the blocks. Not done in a part
    with comments, CDATA or processing instructions, where such a tag might not be markup
    (anywhere else a literal ``<`` is markup: XML escapes it in text and attributes), nor in one
    that already holds the mark (which is then an ordinary attribute, ignored)."""
    if b"<!--" in data or b"<![CDATA[" in data or data.count(b"<?") > 1 or FAST_MARK.encode() in data:
        return data, []
    pieces: list[bytes] = []
    blocks: list[np.ndarray] = []
    at = 0
    while True:
        found = [(data.find(open_tag, at), open_tag, close_tag, kind) for open_tag, close_tag, kind in _BLOCK_TAGS]
        found = [f for f in found if f[0] >= 0]
        if not found:
            break
        start, open_tag, close_tag, kind = min(found)
        body = start + len(open_tag)
        end = data.find(close_tag, body)
        if end < 0:
            break
        values = _numbers(data[body:end], kind)
        if values is None:
            pieces.append(data[at:end])
        else:
            pieces += [data[at:start], open_tag[:-1], f' {FAST_MARK}="{len(blocks)}">'.encode()]
            blocks.append(values)
        at = end
    pieces.append(data[at:])
    return b"".join(pieces), blocks


def parse(stream: IO[bytes], declared: int, where: str, part: str) -> Model:
    """Read one model part.

    Parameters
    ----------
    stream : binary stream
        The part's inflated bytes (a ``zipfile`` member).
    declared : int
        Its size as the archive declares it (checked here against ``limits.MAX_INFLATED``).

    Raises
    ------
    FormatError
        Not well-formed XML, a DOCTYPE, a malformed number or transform, a duplicate object id,
        more bytes than declared.
    """
    limits.check_declared(where, declared, part)
    parser = _Parser(where, part)
    if declared > FAST_PART_BYTES:
        return parser.feed(stream, declared)
    data = stream.read(declared + 1)
    if len(data) > declared:
        raise parser.error(f"inflates past the {declared:,} bytes the archive declares")
    data, parser.fast = _extract(data)
    return parser.feed(io.BytesIO(data), len(data))
