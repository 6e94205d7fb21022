"""glTF 2.0's data layer: the JSON document, its buffers and its accessors, as numpy arrays.

Written from the glTF 2.0 specification (Khronos, 2021): §4.4 (GLB container), §3.6 (buffers,
buffer views, accessors, sparse accessors), §3.6.2.1 (component types), §3.11 (normalized
integers). Every index, offset, stride and count in the JSON is checked against what it points
to before use, so a hostile file ends in one ``FormatError`` naming the field (``accessors[3]:
...``), never in an ``IndexError`` or a read past a buffer.

Buffers are read on first use, and only the bytes a buffer declares (``byteLength``): an
external buffer file is opened without blocking and read only if it is a regular file (a FIFO
or a device named as a buffer is refused unopened for reading); a ``data:`` URI is decoded.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import os
import stat
import struct
import urllib.parse

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io import limits
from p3d_cli.io.raw import RawInput

GLB_MAGIC = b"glTF"
_JSON_CHUNK, _BIN_CHUNK = 0x4E4F534A, 0x004E4942
CORRUPT = "the file is corrupt or was cut short; export it again"

#: componentType -> numpy dtype (little-endian, §3.6.2.2).
COMPONENTS: dict[int, np.dtype] = {5120: np.dtype("<i1"), 5121: np.dtype("<u1"), 5122: np.dtype("<i2"),
                                   5123: np.dtype("<u2"), 5125: np.dtype("<u4"), 5126: np.dtype("<f4")}
#: Integer component types that may be normalized, and the divisor (§3.11: signed types clamp at -1).
_NORMALIZED = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
#: Extensions whose data p3d cannot decode; a buffer view or primitive that needs one is refused.
COMPRESSION = {"KHR_draco_mesh_compression": "Draco", "EXT_meshopt_compression": "meshopt",
               "KHR_meshopt_compression": "meshopt"}


def is_glb(head: bytes) -> bool:
    """The binary container's magic number (§4.4.3 "Header")."""
    return head[:4] == GLB_MAGIC


def corrupt(where: str, what: str) -> FormatError:
    return FormatError(where, what, CORRUPT)


def read_container(raw: RawInput) -> tuple[dict, memoryview | None]:
    """The JSON document, and a GLB's binary chunk (None for a ``.gltf``).

    Raises
    ------
    FormatError
        Not glTF: a bad GLB header or chunk, JSON that does not parse (or nests too deep for
        the parser), or a document that is not a JSON object.
    """
    binary: memoryview | None = None
    text: bytes | memoryview
    if is_glb(raw.head(4)):
        data = raw.read_all()
        if len(data) < 20:
            raise corrupt(raw.where, "is shorter than a GLB header (20 bytes)")
        version, total = struct.unpack_from("<II", data, 4)
        if version != 2:
            raise FormatError(raw.where, f"is a GLB of version {version}; p3d reads glTF 2.0",
                              "export the model as glTF 2.0")
        if total > len(data):
            raise corrupt(raw.where, f"its header declares {total} bytes but the file holds {len(data)}")
        chunks = _chunks(raw.where, data[:total])
        if not chunks or chunks[0][0] != _JSON_CHUNK:
            raise corrupt(raw.where, "its first chunk is not the JSON chunk")
        text = chunks[0][1]
        binary = next((body for kind, body in chunks[1:2] if kind == _BIN_CHUNK), None)
    else:
        if raw.size > limits.GLTF_JSON_BYTES:
            raise FormatError(raw.where, f"its JSON is {raw.size:,} bytes, more than p3d reads "
                              f"({limits.GLTF_JSON_BYTES:,})", "store the data in buffers (.bin) or as GLB")
        text = raw.read_all()
    try:
        document = json.loads(bytes(text).decode("utf-8-sig"))
    except RecursionError:
        raise corrupt(raw.where, "its JSON nests deeper than p3d's parser follows") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise FormatError(raw.where, f"is not a glTF file ({str(exc).splitlines()[0][:100]})",
                          "the file is corrupt or not glTF; export it again") from None
    if not isinstance(document, dict):
        raise FormatError(raw.where, "is not a glTF file (its JSON is not an object)", "export it again")
    return document, binary


def _chunks(where: str, data: bytes) -> list[tuple[int, memoryview]]:
    view = memoryview(data)
    out, at = [], 12
    while at + 8 <= len(data):
        length, kind = struct.unpack_from("<II", data, at)
        if at + 8 + length > len(data):
            raise corrupt(where, f"a chunk at byte {at} declares {length} bytes, past the end of the file")
        out.append((kind, view[at + 8:at + 8 + length]))
        at += 8 + length + (-length % 4)
    return out


def is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


class Document:
    """The JSON document with checked access, and the buffers it names (read on first use).

    Parameters
    ----------
    raw : RawInput
        The glTF or GLB input (external buffers are found beside its path).
    document : dict
    binary : bytes-like or None
        A GLB's binary chunk.
    """

    def __init__(self, raw: RawInput, document: dict, binary) -> None:
        self.where = raw.where
        self.path = raw.path
        self.json = document
        self.binary = binary
        self._buffers: dict[int, memoryview] = {}

    # -- checked JSON access ------------------------------------------------------------------

    def error(self, path: str, what: str) -> FormatError:
        return corrupt(self.where, f"{path} {what}")

    def items(self, key: str, owner: dict | None = None, path: str = "") -> list:
        """``owner[key]`` (the document's by default) as a list; missing is empty."""
        value = (self.json if owner is None else owner).get(key, [])
        if not isinstance(value, list):
            raise self.error(f"{path}{key}", "is not a list")
        return value

    def entry(self, key: str, index, path: str) -> dict:
        """Element ``index`` of the top-level list ``key`` (``accessors``, ``nodes``, ...), checked."""
        array = self.items(key)
        if not is_int(index) or not 0 <= index < len(array):
            raise self.error(path, f"names {key}[{index!r}], which the file lacks ({len(array)} {key})")
        value = array[index]
        if not isinstance(value, dict):
            raise self.error(f"{key}[{index}]", "is not a JSON object")
        return value

    def integer(self, owner: dict, key: str, path: str, default: int | None = None, minimum: int = 0) -> int:
        value = owner.get(key, default)
        if not is_int(value) or value < minimum:
            raise self.error(f"{path}.{key}", f"is {value!r}, not an integer of at least {minimum}")
        return value

    def numbers(self, owner: dict, key: str, count: int, path: str, default: list[float]) -> np.ndarray:
        """``owner[key]``: ``count`` finite numbers (float64)."""
        value = owner.get(key, default)
        if (not isinstance(value, list) or len(value) != count
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                           for x in value)):
            raise self.error(f"{path}.{key}", f"is not a list of {count} finite numbers")
        return np.array(value, dtype=np.float64)

    # -- buffers ------------------------------------------------------------------------------

    def buffer(self, index: int, path: str) -> memoryview:
        """The bytes of ``buffers[index]``: exactly its ``byteLength``, read on first use."""
        if index not in self._buffers:
            spec = self.entry("buffers", index, path)
            where = f"buffers[{index}]"
            length = self.integer(spec, "byteLength", where, minimum=1)
            uri = spec.get("uri")
            if uri is None:
                data = self._glb_buffer(index, spec, where)
            elif not isinstance(uri, str):
                raise self.error(f"{where}.uri", "is not a string")
            elif uri.startswith("data:"):
                data = self._data_uri(uri, length, where)
            else:
                data = self._file(uri, length, where)
            if len(data) < length:
                raise self.error(where, f"declares {length} bytes but its data holds {len(data)}")
            self._buffers[index] = memoryview(data)[:length]
        return self._buffers[index]

    def _glb_buffer(self, index: int, spec: dict, where: str):
        extensions = spec.get("extensions")
        if isinstance(extensions, dict) and any(name in extensions for name in COMPRESSION):
            name = next(name for name in COMPRESSION if name in extensions)
            raise FormatError(self.where, f"{where} holds only data compressed with {name} "
                              f"({COMPRESSION[name]}), which p3d does not decode",
                              "export the glTF without mesh compression (gltf-transform, Blender)")
        if index != 0 or self.binary is None:
            raise self.error(where, "has no uri and is not a GLB's binary chunk")
        return self.binary

    def _data_uri(self, uri: str, length: int, where: str) -> bytes:
        head, comma, payload = uri.partition(",")
        if not comma:
            raise self.error(f"{where}.uri", "is a data: URI without a comma")
        try:
            if head.endswith(";base64"):
                # A base64 text of n characters holds at most 3n/4 bytes: the JSON bounds it.
                return base64.b64decode(payload, validate=True)
            return urllib.parse.unquote_to_bytes(payload)
        except (binascii.Error, ValueError):
            raise self.error(f"{where}.uri", "is a data: URI whose base64 text is malformed") from None

    def _file(self, uri: str, length: int, where: str) -> bytes:
        relative = urllib.parse.unquote(uri)
        if urllib.parse.urlsplit(uri).scheme or os.path.isabs(relative) or "\x00" in relative:
            raise FormatError(self.where, f"{where} names {uri[:80]!r}: p3d reads buffers beside the file only "
                              "(relative paths and data: URIs)", "store the buffer beside the .gltf, or export as GLB")
        if self.path is None:
            raise FormatError(self.where, f"{where} names the file {relative[:80]!r}, which a glTF read from "
                              "standard input cannot reach", "name the .gltf file instead, or export as GLB")
        target = os.path.join(os.path.dirname(self.path), relative)
        try:
            # Opened without blocking (a FIFO's open would wait for a writer), and read only
            # once fstat says it is a regular file: a FIFO or device is never read.
            fd = os.open(target, os.O_RDONLY | os.O_NONBLOCK)
        except OSError as exc:
            raise FormatError(self.where, f"{where} names {relative[:80]!r}, which cannot be read "
                              f"({exc.strerror or exc})", "put the buffer file beside the .gltf") from None
        with os.fdopen(fd, "rb") as stream:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode):
                raise FormatError(self.where, f"{where} names {relative[:80]!r}, which is not a regular file "
                                  "(a FIFO, socket or device)", "name a buffer file")
            if info.st_size < length:
                raise self.error(where, f"declares {length} bytes but {relative[:80]!r} holds {info.st_size}")
            os.set_blocking(fd, True)
            return stream.read(length)

    # -- accessors ----------------------------------------------------------------------------

    def view(self, index, path: str) -> tuple[memoryview, int | None]:
        """A buffer view's bytes and its byteStride (None when tightly packed)."""
        spec = self.entry("bufferViews", index, path)
        where = f"bufferViews[{index}]"
        extensions = spec.get("extensions")
        compressed = [n for n in COMPRESSION if isinstance(extensions, dict) and n in extensions]
        buffer_index = self.integer(spec, "buffer", where)
        try:
            data = self.buffer(buffer_index, f"{where}.buffer")
        except FormatError:
            if compressed:   # the fallback buffer is empty: the data exist only compressed
                raise FormatError(self.where, f"{where} is compressed with {compressed[0]} "
                                  f"({COMPRESSION[compressed[0]]}), which p3d does not decode",
                                  "export the glTF without mesh compression (gltf-transform, Blender)") from None
            raise
        offset = self.integer(spec, "byteOffset", where, default=0)
        length = self.integer(spec, "byteLength", where, minimum=1)
        if offset + length > len(data):
            raise self.error(where, f"spans bytes {offset}..{offset + length} of a buffer of {len(data)}")
        stride = spec.get("byteStride")
        if stride is not None and (not is_int(stride) or not 4 <= stride <= 252):
            raise self.error(f"{where}.byteStride", f"is {stride!r}, not an integer in 4..252")
        return data[offset:offset + length], stride

    def accessor(self, index, path: str, types: tuple[str, ...]) -> tuple[np.ndarray, int, bool]:
        """Accessor ``index`` as a ``(count, width)`` array of its stored component type (sparse
        substitution applied), its componentType, and whether it is normalized.

        Raises
        ------
        FormatError
            A type outside ``types``, an unknown component type, or data outside its view.
        """
        spec = self.entry("accessors", index, path)
        where = f"accessors[{index}]"
        kind = spec.get("type")
        if kind not in types:
            raise self.error(f"{where}.type", f"is {kind!r}; {path} needs {' or '.join(types)}")
        component = spec.get("componentType")
        if component not in COMPONENTS:
            raise self.error(f"{where}.componentType", f"is {component!r}, not a glTF component type")
        normalized = spec.get("normalized", False) is True and component in _NORMALIZED
        count = self.integer(spec, "count", where, minimum=1)
        width, dtype = WIDTHS[kind], COMPONENTS[component]
        limit = limits.MAX_PLACED_FACES * 3
        if count > limit:
            raise FormatError(self.where, f"{where} declares {count:,} elements, more than p3d reads ({limit:,})",
                              "split the model")
        if "bufferView" in spec:
            data, stride = self.view(spec["bufferView"], f"{where}.bufferView")
            offset = self.integer(spec, "byteOffset", where, default=0)
            element = width * dtype.itemsize
            stride = stride or element
            if stride < element and count > 1:
                raise self.error(where, f"has elements of {element} bytes but a stride of {stride}")
            if offset + stride * (count - 1) + element > len(data):
                raise self.error(where, f"reads {count} elements past the end of its buffer view "
                                 f"({len(data)} bytes)")
            values = np.ndarray((count, width), dtype, data, offset, (stride, dtype.itemsize))
        else:
            values = np.zeros((count, width), dtype)   # §3.6.2.3: no buffer view means zeros
        if "sparse" in spec:
            values = self._sparse(spec["sparse"], values, dtype, where)
        return values, component, normalized

    def _sparse(self, sparse, values: np.ndarray, dtype: np.dtype, where: str) -> np.ndarray:
        """``values`` with the sparse substitution of §3.6.2.3 applied (a copy)."""
        where = f"{where}.sparse"
        if not isinstance(sparse, dict):
            raise self.error(where, "is not a JSON object")
        count = self.integer(sparse, "count", where, minimum=1)
        indices_spec, values_spec = sparse.get("indices"), sparse.get("values")
        if not isinstance(indices_spec, dict) or not isinstance(values_spec, dict):
            raise self.error(where, "lacks its indices or values object")
        kind = indices_spec.get("componentType")
        if kind not in (5121, 5123, 5125):
            raise self.error(f"{where}.indices.componentType", f"is {kind!r}, not an unsigned integer type")
        indices = self._packed(indices_spec, count, 1, COMPONENTS[kind], f"{where}.indices")[:, 0]
        if count > len(values):
            raise self.error(where, f"substitutes {count} elements in an accessor of {len(values)}")
        if indices.max() >= len(values) or (count > 1 and np.any(np.diff(indices.astype(np.int64)) <= 0)):
            raise self.error(f"{where}.indices", f"are not strictly increasing indices below {len(values)}")
        substitutes = self._packed(values_spec, count, values.shape[1], dtype, f"{where}.values")
        out = values.copy()
        out[indices.astype(np.intp)] = substitutes
        return out

    def _packed(self, spec: dict, count: int, width: int, dtype: np.dtype, where: str) -> np.ndarray:
        """``count`` tightly packed elements from a sparse accessor's indices or values view."""
        data, _ = self.view(spec.get("bufferView"), f"{where}.bufferView")
        offset = self.integer(spec, "byteOffset", where, default=0)
        size = count * width * dtype.itemsize
        if offset + size > len(data):
            raise self.error(where, f"reads {count} elements past the end of its buffer view ({len(data)} bytes)")
        return np.frombuffer(data, dtype, count * width, offset).reshape(count, width)


def as_float(values: np.ndarray, component: int, normalized: bool) -> np.ndarray:
    """Stored components as numbers: float32 as stored; normalized integers scaled to [-1, 1]
    or [0, 1] (§3.11, signed types clamped at -1); other integers as their values (float64)."""
    if component == 5126:
        return values
    out = values.astype(np.float64)
    if normalized:
        out /= _NORMALIZED[component]
        if component in (5120, 5122):
            np.maximum(out, -1.0, out=out)
    return out
