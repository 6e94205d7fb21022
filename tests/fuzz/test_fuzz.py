"""Short fuzz runs of every reader and of the scene loader, and the corpus of inputs that once
broke one of them, replayed as regression tests.

The runs mutate the bundled samples (byte flips, insertions, deletions, repeated or cut spans,
numbers replaced by extreme ones) and feed the result to each target (``targets.py``): every
input must give a result or a ``P3DError``. The example count follows the hypothesis profile
(``ci`` by default: ``FUZZ_EXAMPLES`` per target); docs/fuzzing.md tells how to run for hours.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from targets import MAX_INPUT, TARGETS, seeds

CORPUS = Path(__file__).resolve().parent / "corpus"
EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "150"))

#: Numbers that break parsers and arithmetic: huge, tiny, signed, special, malformed.
NASTY = [b"1e308", b"-1e308", b"1e-320", b"inf", b"nan", b"-0", b"1e400", b"4294967296", b"2147483648",
         b"-2147483649", b"9223372036854775808", b"1073741823", b"1_0", b"0x10", b"+", b"-", b"1e", b".",
         b"", b"\r", b"\x00", b"\xff\xfe", b"#", b"/", b"//"]
_NUMBER = re.compile(rb"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


@st.composite
def mutated(draw, target: str) -> bytes:
    data = bytearray(draw(st.sampled_from(seeds(target))))
    for _ in range(draw(st.integers(1, 6))):
        kind = draw(st.sampled_from(["flip", "insert", "delete", "repeat", "cut", "number", "nasty"]))
        at = draw(st.integers(0, max(len(data) - 1, 0)))
        if kind == "flip" and data:
            data[at] ^= 1 << draw(st.integers(0, 7))
        elif kind == "insert":
            data[at:at] = draw(st.binary(min_size=1, max_size=8))
        elif kind == "delete":
            del data[at:at + draw(st.integers(1, 16))]
        elif kind == "repeat":
            span = data[at:at + draw(st.integers(1, 64))]
            data[at:at] = span * draw(st.integers(1, 4))
        elif kind == "cut":
            del data[at:]
        elif kind in ("number", "nasty"):
            numbers = list(_NUMBER.finditer(bytes(data)))
            replacement = draw(st.sampled_from(NASTY))
            if kind == "number" and numbers:
                m = numbers[draw(st.integers(0, len(numbers) - 1))]
                data[m.start():m.end()] = replacement
            else:
                data[at:at] = replacement
    return bytes(data[:MAX_INPUT])


def _fuzz(target: str):
    @settings(max_examples=EXAMPLES, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(data=mutated(target))
    def run(data):
        TARGETS[target](data)
    return run


@pytest.mark.parametrize("target", sorted(TARGETS))
def test_fuzz(target):
    _fuzz(target)()


def corpus_files() -> list[Path]:
    return sorted(p for p in CORPUS.glob("*/*") if p.is_file())


@pytest.mark.parametrize("path", corpus_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_corpus_case_is_a_result_or_a_p3d_error(path):
    TARGETS[path.parent.name](path.read_bytes())


def test_every_seed_is_a_valid_input():
    # Mutations start from inputs p3d reads: each seed gives a result, not a refusal.
    for name, target in TARGETS.items():
        for data in seeds(name):
            result = target(data)
            assert result is not None, name
            if name in ("urdf", "mjcf", "sdf"):
                assert result and all(c.link for c in result), name
            elif name == "robot_fill":
                assert any(link.status == "filled" for link in result.links), name
            elif not name.startswith("scene"):
                assert result.properties.volume > 0, name
