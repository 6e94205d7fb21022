"""A small XML tree that remembers where each element is in the file's bytes.

Robot descriptions are read with the standard library's expat binding (no network, no external
entities: expat resolves none unless asked, and since 2.4 it stops entity expansion that
amplifies the input, the "billion laughs"), into ``Node`` objects that keep each element's
span. ``p3d robot fill`` then rewrites only the spans of the ``<inertial>`` elements it
changes (``Document.splice``), so every other byte of the file (comments, CDATA, processing
instructions, entity references, attribute order and quoting, whitespace, line endings, the
XML declaration) is left exactly as it was.

Encodings: a document is read in the encoding its byte order mark or XML declaration gives
(UTF-8 by default; UTF-16 and UTF-32 with or without a mark, ISO-8859-1, ...). Expat parses
a UTF-8 copy of it (the file's own bytes when it is UTF-8), and offsets index that copy;
``splice`` maps them back to the file's bytes and writes new text in the file's encoding.

Elements an entity reference brings in (``<!ENTITY inertial "<inertial .../>">``) have no
bytes of their own in the file: ``Node.expanded`` marks them, and ``fill`` leaves them alone.
"""

from __future__ import annotations

import codecs
import os
import re
import stat
import xml.parsers.expat
from dataclasses import dataclass, field
from typing import Iterator

from p3d_cli.errors import FormatError, InputError, ReadError

#: The largest description (or included file) read, in bytes: real ones are well under 10 MB.
MAX_FILE_BYTES = 256 << 20

#: The end of a tag that starts at a match position: attribute values may hold '>' in quotes.
_TAG = re.compile(rb"""<(?:[^>"']|"[^"]*"|'[^']*')*>""")
_DECLARED = re.compile(rb"""<\?xml[^>]*?encoding\s*=\s*["']([A-Za-z][A-Za-z0-9._-]*)["']""")
#: Byte order marks (longest first: UTF-32 LE's starts with UTF-16 LE's).
_BOMS = ((codecs.BOM_UTF8, "utf-8"), (codecs.BOM_UTF32_LE, "utf-32-le"), (codecs.BOM_UTF32_BE, "utf-32-be"),
         (codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be"))
#: The first characters "<?" of a document without a mark, in the wide encodings.
_WIDE = ((b"<\x00\x00\x00?\x00\x00\x00", "utf-32-le"), (b"\x00\x00\x00<\x00\x00\x00?", "utf-32-be"),
         (b"<\x00?\x00", "utf-16-le"), (b"\x00<\x00?", "utf-16-be"))


@dataclass(eq=False)
class Document:
    """One XML file as read.

    Attributes
    ----------
    path : str
    data : bytes
        The file's bytes, as read.
    encoding : str
        The Python codec of the file (``utf-8``, ``utf-16-le``, ...).
    bom : bytes
        The byte order mark that starts the file (empty: none).
    text : bytes
        The document as UTF-8, after the mark: ``data`` itself for a UTF-8 file without one.
        Every ``Node`` offset indexes this.
    """

    path: str
    data: bytes
    encoding: str = "utf-8"
    bom: bytes = b""
    text: bytes = b""

    @property
    def newline(self) -> bytes:
        """The file's line ending (UTF-8): a Windows file keeps its CRLF."""
        return b"\r\n" if b"\r\n" in self.text else b"\n"

    def splice(self, edits: list[tuple[int, int, bytes]]) -> bytes:
        """The file's bytes with each ``(start, end, new)`` edit made: offsets index ``text``,
        ``new`` is UTF-8 and is written in the file's encoding; all else is the file's own bytes.

        Raises
        ------
        InputError
            The file's encoding does not give its bytes back piece by piece (a stateful
            encoding such as ISO-2022), so it cannot be rewritten byte for byte.
        """
        edits = sorted(edits)
        for (_, end, _), (start, _, _) in zip(edits, edits[1:]):
            if start < end:
                raise ValueError("overlapping edits")
        if self.encoding == "utf-8":
            out, at = [self.data[:len(self.bom)]], 0
            for start, end, new in edits:
                out += [self.text[at:start], new]
                at = end
            out.append(self.text[at:])
            return b"".join(out)
        # Another encoding: walk the file, turning each UTF-8 piece into the file's bytes.
        # Unchanged pieces are copied from the file itself, after checking that they are what
        # encoding them gives (so a byte-for-byte copy is guaranteed, or the fill refused).
        out, at, offset = [self.bom], 0, len(self.bom)
        for start, end, new in [*edits, (len(self.text), len(self.text), None)]:
            size = len(self.text[at:start].decode("utf-8").encode(self.encoding))
            out.append(self.data[offset:offset + size])
            offset += size
            if new is None:
                break
            out.append(new.decode("utf-8").encode(self.encoding))
            offset += len(self.text[start:end].decode("utf-8").encode(self.encoding))
            at = end
        joined = b"".join(out)
        if offset != len(self.data) or not _same_text(joined, self, edits):
            raise InputError(self.path, f"its encoding ({self.encoding}) cannot be rewritten byte for byte",
                             "convert the file to UTF-8 first")
        return joined


def _same_text(joined: bytes, doc: Document, edits) -> bool:
    """Whether ``joined`` decodes to the document's text with the edits made."""
    expected, at = [], 0
    for start, end, new in edits:
        expected += [doc.text[at:start], new]
        at = end
    expected.append(doc.text[at:])
    try:
        return joined[len(doc.bom):].decode(doc.encoding).encode("utf-8") == b"".join(expected)
    except UnicodeError:
        return False


@dataclass(eq=False)
class Node:
    """One element.

    Attributes
    ----------
    tag : str
    attrib : dict of str to str
    children : list of Node
    text : str
        The character data directly inside the element (stripped).
    start : int
        Offset (in ``doc.text``) of the ``<`` of the start tag.
    end : int
        Offset just past the element (past ``/>`` or the end tag's ``>``).
    tag_end : int
        Offset just past the start tag's ``>``.
    empty : bool
        Written as one tag, ``<a/>``.
    expanded : bool
        Brought in by an entity reference: its offsets are the reference's, not its own.
    line : int
        Line of the start tag (from 1), for messages.
    doc : Document or None
        The file the element is written in.
    """

    tag: str
    attrib: dict[str, str]
    children: list["Node"] = field(default_factory=list)
    text: str = ""
    start: int = 0
    end: int = 0
    tag_end: int = 0
    empty: bool = False
    expanded: bool = False
    line: int = 0
    parent: "Node | None" = field(default=None, repr=False)
    doc: Document | None = field(default=None, repr=False)

    def find(self, tag: str) -> "Node | None":
        """The first child named ``tag``."""
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list["Node"]:
        """The children named ``tag``."""
        return [c for c in self.children if c.tag == tag]

    def iter(self, tag: str | None = None) -> Iterator["Node"]:
        """This element and its descendants (those named ``tag``), in document order.

        A stack, not recursion: a deep but valid document cannot exhaust Python's stack."""
        stack = [self]
        while stack:
            node = stack.pop()
            if tag is None or node.tag == tag:
                yield node
            stack.extend(reversed(node.children))

    def child_text(self, tag: str) -> str | None:
        """The text of the first child named ``tag``, or None."""
        child = self.find(tag)
        return None if child is None else child.text

    @property
    def where(self) -> str:
        """``file: line N``, for messages."""
        return f"{self.doc.path if self.doc else '<xml>'}: line {self.line}"


def encoding_of(data: bytes, where: str) -> tuple[str, bytes]:
    """The codec and the byte order mark of an XML document (UTF-8 when it says nothing).

    Raises
    ------
    FormatError
        An encoding Python does not know.
    """
    for bom, codec in _BOMS:
        if data.startswith(bom):
            return codec, bom
    for start, codec in _WIDE:
        if data.startswith(start):
            return codec, b""
    declared = _DECLARED.match(data[:256])
    if declared is None:
        return "utf-8", b""
    name = declared.group(1).decode("ascii")
    try:
        codec = codecs.lookup(name).name
    except LookupError:
        raise FormatError(where, f"declares the encoding {name!r}, which p3d does not know",
                          "convert the file to UTF-8") from None
    if codec in ("utf-16", "utf-32"):  # declared so, but without a mark and not wide: wrong
        raise FormatError(where, f"declares {name} but is not written in it", "fix the declaration")
    return ("utf-8" if codec == "utf-8-sig" else codec), b""


def parse_xml(data: bytes, where: str) -> Node:
    """The root ``Node`` of the XML document ``data`` (its ``doc`` holds the bytes).

    Raises
    ------
    FormatError
        Not well-formed XML (with the line and column expat reports), or not in the encoding
        it declares.
    """
    codec, bom = encoding_of(data, where)
    if codec == "utf-8":
        text = data[len(bom):] if bom else data  # expat checks that it is UTF-8
    else:
        try:
            text = data[len(bom):].decode(codec).encode("utf-8")
        except UnicodeDecodeError as exc:
            raise FormatError(where, f"is not valid {codec} ({exc.reason} at byte {exc.start + len(bom)})",
                              "fix the file or its encoding declaration") from None
    doc = Document(where, data, codec, bom, text)
    # The protocol encoding overrides the declaration: expat reads the UTF-8 copy as UTF-8.
    parser = xml.parsers.expat.ParserCreate("utf-8")
    stack: list[Node] = []
    texts: list[list[str]] = []
    root: list[Node] = []

    def start(tag, attrib):
        index = parser.CurrentByteIndex
        node = Node(tag, attrib, start=index, line=parser.CurrentLineNumber, doc=doc)
        match = _TAG.match(text, index) if text[index:index + 1] == b"<" else None
        if match is None:  # inside an entity's replacement text: the offset is the reference's
            node.expanded = True
        else:
            node.tag_end = match.end()
            node.empty = text[node.tag_end - 2:node.tag_end] == b"/>"
            if node.empty:
                node.end = node.tag_end
        if stack:
            node.parent = stack[-1]
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)
        texts.append([])

    def end(tag):
        node = stack.pop()
        node.text = "".join(texts.pop()).strip()
        if node.expanded or node.empty:
            return
        # The index is at the '<' of the end tag (</a >: spaces allowed before its '>').
        match = _TAG.match(text, parser.CurrentByteIndex)
        node.end = match.end() if match else len(text)

    def chars(data):
        if texts:
            texts[-1].append(data)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as exc:
        raise FormatError(where, f"is not well-formed XML ({exc})", "fix the file") from None
    if not root:
        raise FormatError(where, "has no root element", "fix the file")
    return root[0]


def regular_file(path: str, where: str, what: str = "file") -> os.stat_result:
    """The status of ``path``, refusing anything but a regular file (a FIFO or device would block
    a read or never end).

    Raises
    ------
    InputError
    """
    try:
        info = os.stat(path)
    except OSError as exc:
        raise ReadError(where, f"{what} {path}: {exc.strerror or exc}", "check the path") from None
    if not stat.S_ISREG(info.st_mode):
        raise ReadError(where, f"{what} {path} is not a regular file (a folder, FIFO or device)",
                         "name a regular file")
    return info


def read_xml(path: str, where: str | None = None) -> Node:
    """The tree of the XML file at ``path`` (its bytes in ``root.doc``).

    Raises
    ------
    InputError, FormatError
        Not a regular file, larger than ``MAX_FILE_BYTES``, unreadable, not XML.
    """
    try:
        info = os.stat(path)
    except OSError as exc:
        raise ReadError(where or path, f"{'' if where is None else path + ' '}cannot be read "
                         f"({exc.strerror or exc})", "check the path") from None
    if not stat.S_ISREG(info.st_mode):
        raise ReadError(where or path, f"{'' if where is None else path + ' '}is not a regular file (a folder, "
                         "FIFO or device)", "name a regular file")
    if info.st_size > MAX_FILE_BYTES:
        raise InputError(where or path, f"{path} holds {info.st_size} bytes, more than p3d reads "
                         f"({MAX_FILE_BYTES} bytes)", "give a robot description, not a data file")
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ReadError(where or path, f"{path} cannot be read ({exc.strerror or exc})", "check the path") from None
    if len(data) > MAX_FILE_BYTES:
        raise InputError(where or path, f"{path} grew past {MAX_FILE_BYTES} bytes while read", "give a robot "
                         "description")
    return parse_xml(data, path)


def numbers(text: str | None, count: int | tuple[int, ...], where: str, default=None) -> list[float] | None:
    """The ``count`` numbers of an attribute's text (None and no default: None).

    Raises
    ------
    InputError
        Not that many finite numbers, naming ``where``.
    """
    import math

    if text is None:
        return default
    counts = (count,) if isinstance(count, int) else count
    try:
        values = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        values = []
    if len(values) not in counts or not all(math.isfinite(v) for v in values):
        raise InputError(where, f"{text!r} is not {' or '.join(map(str, counts))} finite numbers",
                         "write numbers separated by spaces")
    return values
