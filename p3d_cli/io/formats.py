"""The one registry of mesh formats: a record per format, read by detection, directory search,
``format=`` (``--format``) and the error hints alike.

A record names the format, its extensions and aliases, the module that reads it (imported on
first use, so ``p3d props part.stl`` pays for the STL reader alone) and how its content is
recognised. Adding a format is one record here and one module under ``p3d_cli/io/``.

Detection, in order: an explicit format name; a file that is no mesh but says what it is (a
URDF, MJCF or SDF robot description, a STEP model: refused with what to do instead); a header
that names its format outright (``ply``, ``OFF``, ``glTF``, ``<COLLADA``, ``<amf``, VTK
PolyData), trusted over the extension; the extension of a format p3d reads itself; then the
content sniffers, in registry order (binary STL by size or ``solid`` text, any extension meshio
reads, OBJ statements for inputs without an extension).
"""

from __future__ import annotations

import importlib
import os
import re
from dataclasses import dataclass
from types import ModuleType
from typing import Callable

from p3d_cli.errors import InputError, UnknownFormatError
from p3d_cli.io.raw import RawInput, open_input

#: Bytes read from the start of an input to recognise its format.
HEAD = 512

#: Bytes read from the start of an XML input to find its root element past long comments.
XML_HEAD = 1 << 14

#: The first bytes of a STEP file (ISO 10303-21, clause 5: "ISO-10303-21;").
STEP_MAGIC = b"ISO-10303-21"

#: OFF and its variants (colours, normals, texture coordinates, other dimensions).
_OFF_KEYWORD = re.compile(rb"(ST)?C?N?4?n?OFF")


def _first_word(head: bytes) -> bytes:
    """The first word of the text after blank lines and ``#`` comments (b"" if none)."""
    for line in head.split(b"\n"):
        words = line.split(b"#", 1)[0].split()
        if words:
            return words[0]
    return b""


@dataclass(frozen=True)
class Format:
    """What p3d knows about one format.

    Attributes
    ----------
    name : str
        The ``format=`` value and the start of ``MeshSource.format``.
    extensions : tuple of str
        Lower-case, with the dot.
    module : str
        The reader module; its ``load(raw, *args)`` returns a ``MeshSource``.
    description : str
        For help and hints.
    aliases : tuple of str
        Other names accepted for ``format=``.
    header : callable, optional
        ``header(head: bytes) -> bool``: the content names this format outright.
    sniff : callable, optional
        ``sniff(raw: RawInput, ext: str) -> str | None``: the format name (this one's, or a
        sub-format such as ``meshio:vtu``) when the content or extension suggests it.
    writer : str, optional
        The function of ``p3d_cli.io.writers`` that writes this format (``p3d repair``'s
        outputs); None for formats p3d only reads.
    """

    name: str
    extensions: tuple[str, ...]
    module: str
    description: str
    aliases: tuple[str, ...] = ()
    header: Callable[[bytes], bool] | None = None
    sniff: Callable[[RawInput, str], str | None] | None = None
    writer: str | None = None

    def reader(self) -> ModuleType:
        """The reader module, imported on first use."""
        return importlib.import_module(self.module)


def _xml_head(raw: RawInput) -> bytes:
    """The start of an XML document past its declaration and comments (a licence comment can
    be long), lower-cased; b"" for content that is not XML."""
    head = raw.head(HEAD)
    if not head.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"<"):
        return b""
    text = raw.head(XML_HEAD)
    text = re.sub(rb"<!--.*?(-->|$)", b"", text, flags=re.DOTALL)
    text = re.sub(rb"<[?!][^>]*>", b"", text)
    return text.lower()


def _root(text: bytes) -> str:
    """The first element's name in ``_xml_head``'s text (without a namespace prefix), or ""."""
    found = re.match(rb"\s*<(?:[\w.-]+:)?([\w.-]+)", text)
    return found.group(1).decode("ascii", "replace") if found else ""


def _root_is(tag: bytes) -> Callable[[bytes], bool]:
    """A header test: the XML's first element is ``tag`` (any namespace prefix, any case)."""
    pattern = re.compile(rb"^\s*<(?:[\w.-]+:)?" + tag + rb"[\s>/]")
    return lambda text: pattern.match(text) is not None


#: Files that are not meshes but say what they are: (test, what it is, what to do).
NOT_MESHES: tuple[tuple[Callable[[bytes], bool], str, str], ...] = (
    (_root_is(b"robot"), "is a URDF robot description, not a mesh",
     "measure its links with the p3d robot commands (p3d robot check / fill), or pass the meshes it names"),
    (_root_is(b"mujoco"), "is a MuJoCo MJCF model, not a mesh",
     "measure its bodies with the p3d robot commands (p3d robot check / fill), or pass the meshes it names"),
    (_root_is(b"sdf"), "is an SDF (Gazebo) model, not a mesh",
     "measure its links with the p3d robot commands (p3d robot check / fill), or pass the meshes it names"),
)


def refuse_non_mesh(raw: RawInput) -> None:
    """Raise a clear error for a robot description or a CAD model given as a mesh.

    Raises
    ------
    UnknownFormatError
    """
    if raw.head(len(STEP_MAGIC)) == STEP_MAGIC:
        raise UnknownFormatError(raw.where, "is a STEP (ISO 10303-21) CAD model, not a mesh",
                                 "export a mesh from the CAD program (STL, 3MF or OBJ) and measure that")
    text = _xml_head(raw)
    if text:
        for test, what, hint in NOT_MESHES:
            if test(text):
                raise UnknownFormatError(raw.where, what, hint)


def _is_polydata(head: bytes) -> bool:
    """VTK PolyData, XML or legacy (meshio reads neither; its legacy reader takes other datasets)."""
    if b"PolyData" not in head and b"POLYDATA" not in head.upper():
        return False
    return importlib.import_module("p3d_cli.io.vtp").is_polydata(head)


def _meshio() -> ModuleType:
    return importlib.import_module("p3d_cli.io.meshio_backend")


def _sniff_stl(raw: RawInput, ext: str) -> str | None:
    return "stl" if importlib.import_module("p3d_cli.io.stl").looks_like_stl(raw) else None


def _sniff_meshio(raw: RawInput, ext: str) -> str | None:
    if ext and _meshio().knows_extension(ext):
        return "meshio:" + _meshio().format_for_extension(ext)
    return None


def _sniff_obj(raw: RawInput, ext: str) -> str | None:
    return "obj" if importlib.import_module("p3d_cli.io.obj").looks_like_obj(raw.head(HEAD)) else None


#: Every format, in sniffing order. ``meshio`` stands for every other format meshio reads.
FORMATS: dict[str, Format] = {f.name: f for f in (
    Format("stl", (".stl",), "p3d_cli.io.stl", "STL, binary or ASCII", sniff=_sniff_stl,
           writer="write_stl"),
    Format("ply", (".ply",), "p3d_cli.io.ply", "PLY, ASCII or binary",
           header=lambda head: head.lstrip().startswith(b"ply"), writer="write_ply"),
    Format("off", (".off",), "p3d_cli.io.off", "OFF and its variants (COFF, NOFF, ...)",
           header=lambda head: _OFF_KEYWORD.fullmatch(_first_word(head)) is not None, writer="write_off"),
    Format("gltf", (".glb", ".gltf"), "p3d_cli.io.gltf", "glTF 2.0 (.gltf with its buffers, .glb), in metres",
           aliases=("glb", "gltf2"), header=lambda head: head[:4] == b"glTF"),
    Format("3mf", (".3mf",), "p3d_cli.io.threemf", "3MF packages, in their declared unit", aliases=("threemf",)),
    Format("dae", (".dae",), "p3d_cli.io.dae", "COLLADA, in its declared unit", aliases=("collada",),
           header=lambda head: b"<collada" in head[:HEAD].lower()),
    Format("amf", (".amf",), "p3d_cli.io.amf", "AMF (plain or zipped), in its declared unit",
           header=lambda head: _root_is(b"amf")(re.sub(rb"<[?!][^>]*>", b"", head).lower())),
    Format("vtp", (".vtp",), "p3d_cli.io.vtp", "VTK PolyData (XML .vtp, legacy .vtk POLYDATA)",
           aliases=("vtk-polydata",), header=_is_polydata),
    Format("meshio", (), "p3d_cli.io.meshio_backend", "any other format meshio reads (VTU, Gmsh, ...)",
           sniff=_sniff_meshio),
    Format("obj", (".obj",), "p3d_cli.io.obj", "Wavefront OBJ", sniff=_sniff_obj, writer="write_obj"),
)}

#: Extension -> the format p3d reads it with itself.
EXTENSIONS = {ext: f.name for f in FORMATS.values() for ext in f.extensions}

#: Files that sit beside meshes in export folders and that no reader takes: a directory search
#: skips them without importing meshio to ask (0.1-0.3 s, more than a small batch's work).
NEVER_MESHES = frozenset({"", ".txt", ".md", ".rst", ".csv", ".tsv", ".json", ".jsonl", ".yaml", ".yml",
                          ".log", ".mtl", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pdf",
                          ".step", ".stp", ".iges", ".igs", ".zip", ".py", ".html", ".bin", ".urdf",
                          ".xacro", ".sdf", ".launch", ".world", ".material", ".dds"})


def format_names() -> str:
    """The ``format=`` values, for hints: p3d's own (with their aliases), then meshio's."""
    own = sorted((f for f in FORMATS.values() if f.name != "meshio"), key=lambda f: f.name)
    listed = [f.name + (f" ({', '.join(f.aliases)})" if f.aliases else "") for f in own]
    return ", ".join(listed) + ", or a format name meshio knows (vtu, gmsh, ...)"


def is_mesh_path(path: str) -> bool:
    """True when the file name has an extension p3d reads (used to search directories)."""
    ext = os.path.splitext(path)[1].lower()
    if ext in EXTENSIONS:
        return True
    return ext not in NEVER_MESHES and _meshio().knows_extension(ext)


def is_mesh_file(path: str) -> bool:
    """``is_mesh_path``, and for ``.xml`` (robot models, package manifests and launch files
    share it with DOLFIN XML meshes) content that ``detect_format`` reads as a mesh (DOLFIN XML,
    COLLADA, AMF, VTK PolyData): what a directory search takes. A file that is not a regular
    file (a FIFO would block the read) or cannot be read is taken, and its error reported at
    its turn."""
    if not is_mesh_path(path):
        return False
    if os.path.splitext(path)[1].lower() != ".xml" or not os.path.isfile(path):
        return True
    try:
        detect_format(open_input(path))
    except UnknownFormatError:
        return False
    except InputError:
        return True
    return True


def _named(override: str) -> str:
    name = override.lower()
    for f in FORMATS.values():
        if f.name != "meshio" and (name == f.name or name in f.aliases):
            return f.name
    if _meshio().knows_format(name):
        return "meshio:" + name
    raise UnknownFormatError("format", f"unknown format {override!r}", "use one of " + format_names())


def detect_format(raw: RawInput, override: str | None = None) -> str:
    """The format to read ``raw`` with: ``override``, else the content's, else the extension's.

    Returns
    -------
    str
        A key of ``FORMATS``, or ``meshio:<name>`` for a meshio format.

    Raises
    ------
    UnknownFormatError
        ``override`` names no format, or nothing identifies the input's format.
    """
    if override:
        return _named(override)
    refuse_non_mesh(raw)
    head = raw.head(HEAD)
    for f in FORMATS.values():
        if f.header is not None and f.header(head):
            return f.name
    ext = os.path.splitext(raw.path or "")[1].lower()
    if ext in EXTENSIONS:
        return EXTENSIONS[ext]
    root = _root(_xml_head(raw)) if ext == ".xml" else ""
    if ext == ".xml" and root != "dolfin":
        # meshio's one .xml format; robot packages hold many other XML files.
        what = f"an XML file whose root element is <{root}>" if root else "not XML"
        raise UnknownFormatError(raw.where, f"is {what}, not a mesh (the XML meshes read are DOLFIN XML, COLLADA, "
                                 "AMF and VTK PolyData)",
                                 "pass the mesh files it names, or --format NAME for a mesh in another format")
    for f in FORMATS.values():
        found = f.sniff(raw, ext) if f.sniff is not None else None
        if found is not None:
            return found
    what = f"cannot tell the format of {'this extension' if ext else 'an input without an extension'}"
    raise UnknownFormatError(raw.where, what, "give the format (" + format_names() + ")")


def read(raw: RawInput, name: str):
    """Read ``raw`` as format ``name`` (a ``detect_format`` answer) with its record's module."""
    family, _, sub = name.partition(":")
    reader = FORMATS[family].reader()
    return reader.load(raw, sub) if sub else reader.load(raw)
