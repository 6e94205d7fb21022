"""A small XML tree that remembers where each element is in the file's bytes.

Robot descriptions are read with the standard library's expat binding (no network, no external
entities: expat resolves none unless asked, and limits entity expansion), into ``Node`` objects
that keep each element's byte span. ``p3d robot fill`` then rewrites only the spans of the
``<inertial>`` elements it changes, so every other byte of the file (comments, attribute order
and quoting, whitespace, the XML declaration) is left exactly as it was.
"""

from __future__ import annotations

import xml.parsers.expat
from dataclasses import dataclass, field
from typing import Iterator

from p3d_cli.errors import FormatError, InputError


@dataclass
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
        Byte offset of the ``<`` of the start tag.
    end : int
        Byte offset just past the element (past ``/>`` or the end tag's ``>``).
    line : int
        Line of the start tag (from 1), for messages.
    """

    tag: str
    attrib: dict[str, str]
    children: list["Node"] = field(default_factory=list)
    text: str = ""
    start: int = 0
    end: int = 0
    line: int = 0
    parent: "Node | None" = field(default=None, repr=False)

    def find(self, tag: str) -> "Node | None":
        """The first child named ``tag``."""
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list["Node"]:
        """The children named ``tag``."""
        return [c for c in self.children if c.tag == tag]

    def iter(self, tag: str | None = None) -> Iterator["Node"]:
        """This element and its descendants (those named ``tag``), in document order."""
        if tag is None or self.tag == tag:
            yield self
        for child in self.children:
            yield from child.iter(tag)

    def child_text(self, tag: str) -> str | None:
        """The text of the first child named ``tag``, or None."""
        child = self.find(tag)
        return None if child is None else child.text


def _tag_end(data: bytes, start: int) -> int:
    """Offset just past the ``>`` closing the tag that begins at ``start`` (quotes respected)."""
    quote = 0
    i = start
    n = len(data)
    while i < n:
        c = data[i]
        if quote:
            if c == quote:
                quote = 0
        elif c in (0x22, 0x27):
            quote = c
        elif c == 0x3E:
            return i + 1
        i += 1
    return n


def parse_xml(data: bytes, where: str) -> Node:
    """The root ``Node`` of the XML document ``data``.

    Raises
    ------
    FormatError
        Not well-formed XML (with the line and column expat reports).
    InputError
        A document type declaration with entities (refused: robot descriptions need none).
    """
    parser = xml.parsers.expat.ParserCreate()
    stack: list[Node] = []
    texts: list[list[str]] = []
    root: list[Node] = []

    def start(tag, attrib):
        node = Node(tag, attrib, start=parser.CurrentByteIndex, line=parser.CurrentLineNumber)
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
        index = parser.CurrentByteIndex
        # An empty element (<a/>) reports its end at its own start; either way the element
        # ends at the '>' of the tag found at the index.
        node.end = _tag_end(data, index)

    def chars(text):
        if texts:
            texts[-1].append(text)

    def entity(*args):
        raise InputError(where, "declares XML entities", "expand them: a robot description needs none")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.EntityDeclHandler = entity
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise FormatError(where, f"is not well-formed XML ({exc})", "fix the file") from None
    if not root:
        raise FormatError(where, "has no root element", "fix the file")
    return root[0]


def read_xml(path: str) -> tuple[bytes, Node]:
    """The bytes of the file at ``path`` and their tree.

    Raises
    ------
    InputError, FormatError
    """
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise InputError(path, f"cannot be read ({exc.strerror or exc})", "check the path") from None
    return data, parse_xml(data, path)


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
