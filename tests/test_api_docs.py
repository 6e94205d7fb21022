"""docs/api.md and the one list of public names (``p3d_cli.__all__``) cannot drift apart: every
public name is documented, every ``p3d.NAME`` the page shows is public, and every signature it
shows is the function's (or class's) own."""

from __future__ import annotations

import inspect
import re

import pytest

import p3d_cli as p3d

from helpers.real_meshes import REPO

PAGE = (REPO / "docs" / "api.md").read_text()
REFERENCE = PAGE[PAGE.index("## Reference"):]
PUBLIC = set(p3d.__all__)


def code_spans(text: str) -> list[str]:
    """The page's inline code, a span that wraps lines joined by one space (as Markdown does),
    fenced blocks left out."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return [" ".join(span.split()) for span in re.findall(r"`([^`]+)`", text)]


def shown(text: str) -> dict[str, list[str | None]]:
    """``p3d.NAME`` -> the parameter lists the reference's entries show for it (None: shown
    bare). An entry is a paragraph that starts with a name; its description (``: ...``) and
    the examples in it are not entries."""
    entries = [para for para in re.split(r"\n\s*\n", text) if para.startswith("`p3d.")]
    out: dict[str, list[str | None]] = {}
    for span in code_spans("\n\n".join(entries)):
        match = re.fullmatch(r"p3d\.(\w+)(\(.*\))?", span)
        if match:
            out.setdefault(match.group(1), []).append(match.group(2))
    return out


def signature(obj) -> str:
    """``(a, b=1, *, c='x')``: the parameters as the page writes them (no annotations; names
    starting with ``_`` are private and left out)."""
    sig = inspect.signature(obj)
    params = [p.replace(annotation=inspect.Parameter.empty) for p in sig.parameters.values()
              if not p.name.startswith("_")]
    return str(sig.replace(parameters=params, return_annotation=inspect.Signature.empty))


def test_every_public_name_is_in_the_reference():
    missing = sorted(PUBLIC - set(shown(REFERENCE)))
    assert not missing, f"public names docs/api.md's reference does not show: {missing}"


def test_every_name_the_page_shows_is_public():
    everywhere = set(re.findall(r"\bp3d\.([A-Za-z_]\w*)", PAGE))
    stray = sorted(everywhere - PUBLIC)
    assert not stray, f"docs/api.md shows p3d.{stray}, which p3d_cli.__all__ does not have"


@pytest.mark.parametrize("name", sorted(PUBLIC - {"__version__"}))
def test_each_signature_shown_is_the_real_one(name):
    obj = getattr(p3d, name)
    forms = shown(REFERENCE).get(name, [])
    if inspect.isfunction(obj):
        assert any(form is not None for form in forms), f"p3d.{name} is a function: show its signature"
    for form in forms:
        if form is not None:
            assert form.replace('"', "'") == signature(obj), f"docs/api.md shows p3d.{name}{form}"


def test_the_check_fails_on_drift():
    """The checks above see a missing name, a stray name and a changed signature."""
    page = ("`p3d.props(thing, placement=None)`\n\n`p3d.bounds`\n\n`p3d.no_such_thing`\n\n"
            ": an example, no entry: `p3d.check(\"part.stl\")`")
    names = shown(page)
    assert names == {"props": ["(thing, placement=None)"], "bounds": [None], "no_such_thing": [None]}
    assert names["props"][0] != signature(p3d.props)
    assert "check" not in names and "no_such_thing" not in PUBLIC
    wrapped = shown("`p3d.check(thing, *,\n  require=None)`")
    assert wrapped == {"check": ["(thing, *, require=None)"]}
