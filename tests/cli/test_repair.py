"""``p3d repair`` on the command line: exit statuses, records, batches and where outputs go."""

from __future__ import annotations

import csv
import io
import json

import numpy as np

import p3d_cli as p3d
from helpers.cli import run
from helpers.meshes import CUBE_FACES, CUBE_VERTICES, write_binary_stl

CUBE = CUBE_VERTICES[CUBE_FACES]
BENT = np.delete(CUBE, [0, 4], axis=0)        # a hole across the cube's edge: not flat, left


def test_fixed_not_fixed_and_usage_exit_statuses(tmp_path):
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    write_binary_stl(tmp_path / "bent.stl", BENT)
    result = run("repair", tmp_path / "open.stl", "-o", tmp_path / "fixed.stl")
    assert result.exit_code == 0, result.output
    assert "fixed (written)" in result.output and "holes: 1 hole filled with 2 new faces" in result.output
    assert p3d.check(str(tmp_path / "fixed.stl")).ok
    result = run("repair", tmp_path / "bent.stl", "-o", tmp_path / "bent-out.stl")
    assert result.exit_code == 1
    assert "NOT FIXED" in result.output and "not flat" in result.output
    assert "not fixed: closed: 4 boundary edges remain" in result.output
    result = run("repair", tmp_path / "open.stl")
    assert result.exit_code == 2
    assert "no output given; give one of -o PATH, --in-place or --dry-run" in result.output
    result = run("repair", tmp_path / "open.stl", "-o", tmp_path / "x.stl", "--in-place")
    assert result.exit_code == 2 and "both -o/--output and --in-place" in result.output


def test_json_record_says_every_change(tmp_path):
    broken = CUBE[:, [0, 2, 1]].copy()
    broken[0] = CUBE[0]
    write_binary_stl(tmp_path / "in.stl", np.concatenate([broken, broken[[5]]]))
    result = run("repair", tmp_path / "in.stl", "-o", tmp_path / "out.ply", "--json")
    assert result.exit_code == 0, result.output
    record = json.loads(result.output)
    assert record["ok"] and record["fixed"] and record["changed"] and record["written"] == "written"
    assert record["before"]["failed"] == ["closed", "oriented", "outward", "manifold", "no-duplicate"]
    assert record["after"]["failed"] == []
    steps = {s["step"]: s for s in record["steps"]}
    assert list(steps) == ["weld", "degenerate", "duplicate", "orient", "holes", "outward"]
    assert not steps["weld"]["ran"]
    assert steps["duplicate"]["faces"] == [[12, 12]] and steps["duplicate"]["places"] == [{"face": 12, "repeats": 5}]
    assert steps["orient"]["faces"] == [[0, 0]]
    assert steps["outward"]["faces"] == [[0, 11]]           # runs of face numbers, first and last
    assert steps["outward"]["counts"]["faces_flipped"] == 12
    assert record["mass"]["after"]["volume"] == 1.0 and record["mass"]["relative_volume_change"] >= 0
    assert set(record["mass"]["before"]) == {"volume", "center_of_mass", "inertia"}


def test_max_volume_change_gates_ci(tmp_path):
    write_binary_stl(tmp_path / "open.stl", np.delete(CUBE, [2, 3], axis=0))
    result = run("repair", tmp_path / "open.stl", "-o", tmp_path / "out.stl", "--max-volume-change", "1e-6")
    assert result.exit_code == 1 and not (tmp_path / "out.stl").exists()
    assert "over the volume limit (nothing written)" in result.output
    write_binary_stl(tmp_path / "inward.stl", CUBE[:, [0, 2, 1]])
    result = run("repair", tmp_path / "inward.stl", "-o", tmp_path / "out.stl", "--max-volume-change", "1e-6")
    assert result.exit_code == 0 and (tmp_path / "out.stl").exists()


def test_a_folder_is_mirrored_and_one_bad_file_loses_no_other(tmp_path):
    tree = tmp_path / "parts"
    (tree / "sub").mkdir(parents=True)
    write_binary_stl(tree / "open.stl", CUBE[2:])
    write_binary_stl(tree / "sub" / "inward.stl", CUBE[:, [0, 2, 1]])
    write_binary_stl(tree / "sub" / "good.stl", CUBE)
    (tree / "sub" / "broken.stl").write_bytes(b"solid x\n facet normal 0 0 1\n")
    out = tmp_path / "fixed"
    result = run("repair", tree, "-o", out, "--jobs", "2", "--csv")
    assert result.exit_code == 2, result.output
    rows = {row["source"]: row for row in csv.DictReader(io.StringIO(result.stdout))}
    assert rows[str(tree / "sub" / "broken.stl")]["error"]
    assert rows[str(tree / "open.stl")]["holes_filled"] == "1"
    assert rows[str(tree / "sub" / "good.stl")]["written"] == "copied"
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*.stl")) == [
        "open.stl", "sub/good.stl", "sub/inward.stl"]
    assert (out / "sub" / "good.stl").read_bytes() == (tree / "sub" / "good.stl").read_bytes()
    for path in out.rglob("*.stl"):
        assert p3d.check(str(path)).ok
    assert "4 files: 3 ok, 1 error" in result.stderr


def test_files_from_and_output_format(tmp_path):
    write_binary_stl(tmp_path / "a.stl", CUBE[2:])
    write_binary_stl(tmp_path / "b.stl", CUBE[:, [0, 2, 1]])
    listing = tmp_path / "list.txt"
    listing.write_text(f"{tmp_path / 'a.stl'}\n{tmp_path / 'b.stl'}\n")
    out = tmp_path / "out"
    result = run("repair", "--files-from", listing, "-o", out, "--output-format", "obj", "--only-if-needed")
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["a.obj", "b.obj"]     # absolute paths: by name


def test_in_place_batch_replaces_only_what_needs_it(tmp_path):
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    write_binary_stl(tmp_path / "good.stl", CUBE)
    good = (tmp_path / "good.stl").read_bytes()
    result = run("repair", tmp_path, "--in-place")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "good.stl").read_bytes() == good
    assert p3d.check(str(tmp_path / "open.stl")).ok
    assert "left unchanged" in result.output


def test_steps_and_weld_options(tmp_path):
    split = CUBE.copy()
    split[0, 0] += [1e-9, 0, 0]
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    result = run("repair", tmp_path / "open.stl", "--dry-run", "--steps", "-holes")
    assert result.exit_code == 1 and "the holes step was not asked for" in result.output
    result = run("repair", tmp_path / "open.stl", "--dry-run", "--steps", "orient,bogus")
    assert result.exit_code == 2 and "--steps: no repair step named 'bogus'" in result.output
    result = run("repair", tmp_path / "open.stl", "--dry-run", "--steps", "weld")
    assert result.exit_code == 2 and "--steps: the weld step needs a tolerance; give --weld TOL" in result.output
    write_binary_stl(tmp_path / "split.stl", split)          # vertex 0 of face 0 off by 1e-9
    result = run("repair", tmp_path / "split.stl", "-o", tmp_path / "exact.stl", "--json")
    record = json.loads(result.output)
    assert result.exit_code == 1 and not record["fixed"]
    assert [s["ran"] for s in record["steps"] if s["step"] == "weld"] == [False]
    result = run("repair", tmp_path / "split.stl", "-o", tmp_path / "welded.stl", "--weld", "1e-6", "--json")
    assert result.exit_code == 0, result.output
    weld = [s for s in json.loads(result.output)["steps"] if s["step"] == "weld"][0]
    assert weld["counts"]["vertices_merged"] == 1
    assert p3d.check(str(tmp_path / "welded.stl")).ok


def test_help_has_examples_and_every_step():
    result = run("repair", "--help")
    assert result.exit_code == 0
    assert "p3d repair part.stl -o fixed.stl" in result.output
    for step in ("weld", "degenerate", "duplicate", "orient", "holes", "outward"):
        assert step in result.output


def test_ci_reports_name_what_was_not_fixed(tmp_path):
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    write_binary_stl(tmp_path / "bent.stl", BENT)
    junit, summary = tmp_path / "repair.xml", tmp_path / "summary.json"
    result = run("repair", tmp_path / "open.stl", tmp_path / "bent.stl", "-o", tmp_path / "out",
                 "--report", f"junit:{junit}", "--summary", f"json:{summary}")
    assert result.exit_code == 1
    xml = junit.read_text()
    assert xml.count("<testcase") == 2 and xml.count("<failure") == 1
    assert 'type="not-fixed"' in xml and "4 boundary edges remain" in xml
    record = json.loads(summary.read_text())
    assert record["command"] == "p3d repair" and record["ok"] == 1 and record["failed"] == 1
    assert "2 files: 1 ok, 1 not fixed" in result.stderr


def test_records_carry_the_schema_version_and_validate(tmp_path):
    from helpers import record_schemas
    from p3d_cli.cli import output

    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    (tmp_path / "bad.stl").write_bytes(b"not a mesh at all")
    before = record_schemas.VALIDATED["repair"]
    result = run("repair", tmp_path / "open.stl", tmp_path / "bad.stl", "--dry-run", "--json", "--jobs", "1")
    lines = result.stdout.splitlines()
    assert len(lines) == 2 and all(json.loads(line)["schema_version"] == output.SCHEMA_VERSION for line in lines)
    assert json.loads(lines[1])["error"] and record_schemas.VALIDATED["repair"] == before + 2


def test_standard_input_in_and_standard_output_refused(tmp_path):
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    data = (tmp_path / "open.stl").read_bytes()
    result = run("repair", "-", "-o", tmp_path / "out.stl", input=data)
    assert result.exit_code == 0 and p3d.check(str(tmp_path / "out.stl")).ok
    result = run("repair", tmp_path / "open.stl", "-o", "-")
    assert result.exit_code == 2 and "standard output holds the report" in result.stderr
    result = run("repair", "-", "--in-place", input=data)
    assert result.exit_code == 2 and "standard input cannot be repaired in place" in result.stderr


def test_an_earlier_run_s_outputs_inside_the_inputs_are_not_repaired_again(tmp_path):
    tree = tmp_path / "parts"
    tree.mkdir()
    write_binary_stl(tree / "open.stl", CUBE[2:])
    assert run("repair", tree, "-o", tree / "fixed").exit_code == 0
    result = run("repair", tree, "-o", tree / "fixed")
    assert result.exit_code == 2 and "lies in the output folder" in result.stderr
    assert sorted(p.relative_to(tree).as_posix() for p in tree.rglob("*.stl")) == ["fixed/open.stl", "open.stl"]


def test_bad_input_and_output_paths_get_one_error_line_and_status_2(tmp_path):
    """Each: exit 2, one ``p3d: error: <where>: ...`` line on stderr, no traceback, nothing written."""
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    (tmp_path / "garbage.stl").write_bytes(b"\x01" * 500)
    (tmp_path / "a-file").write_text("")
    (tmp_path / "tree").mkdir()
    write_binary_stl(tmp_path / "tree" / "open.stl", CUBE[2:])
    cases = {
        "no such file": (tmp_path / "missing.stl", "-o", tmp_path / "o1.stl"),
        "is truncated or not an STL": (tmp_path / "garbage.stl", "-o", tmp_path / "o2.stl"),
        "cannot be read (Not a directory)": (tmp_path / "a-file" / "x.stl", "-o", tmp_path / "o3.stl"),
        "would overwrite the input": (tmp_path / "open.stl", "-o", tmp_path / "." / "open.stl"),
        "the folder": (tmp_path / "open.stl", "-o", tmp_path / "nowhere" / "o4.stl"),
        "an empty path": (tmp_path / "open.stl", "-o", ""),
        "is a file, but the input is a folder": (tmp_path / "tree", "-o", tmp_path / "a-file"),
        "cannot write a mesh to extension '.md'": (tmp_path / "open.stl", "-o", tmp_path / "o5.md"),
    }
    for what, args in cases.items():
        result = run("repair", *args)
        lines = result.stderr.strip().splitlines()
        assert result.exit_code == 2, (what, result.output)
        assert len(lines) == 1 and lines[0].startswith("p3d: error: ") and what in lines[0], (what, lines)
        assert lines[0].split(": ")[2] != "", lines              # a <where> before the message
        assert "output_format" not in lines[0]                   # the library's name, not an option
        assert "Traceback" not in result.output and result.exception is None or isinstance(
            result.exception, SystemExit)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file", "garbage.stl", "open.stl", "tree"]


def test_an_output_slot_taken_by_a_folder_loses_only_that_file(tmp_path):
    tree = tmp_path / "parts"
    tree.mkdir()
    write_binary_stl(tree / "a.stl", CUBE[2:])
    write_binary_stl(tree / "b.stl", CUBE[:, [0, 2, 1]])
    (tmp_path / "out" / "a.stl").mkdir(parents=True)                # where a.stl's repair would go
    result = run("repair", tree, "-o", tmp_path / "out")
    assert result.exit_code == 2
    assert f"p3d: error: {tmp_path / 'out' / 'a.stl'}: cannot write the repaired mesh: it exists and is not a " \
           "regular file" in result.stderr
    assert p3d.check(str(tmp_path / "out" / "b.stl")).ok
    assert "2 files: 1 ok, 1 error" in result.stderr


def test_one_input_named_twice_is_repaired_into_its_one_place(tmp_path):
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    write_binary_stl(tmp_path / "b.stl", CUBE[2:])
    (tmp_path / "sub").mkdir()
    write_binary_stl(tmp_path / "sub" / "b.stl", CUBE[2:])
    out = tmp_path / "out"
    result = run("repair", tmp_path / "open.stl", tmp_path / "open.stl", tmp_path / "b.stl", tmp_path / "sub" / "b.stl",
                 "-o", out, "--csv")
    assert result.exit_code == 2, result.output
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert [(row["source"], bool(row["error"])) for row in rows] == [
        (str(tmp_path / "open.stl"), False), (str(tmp_path / "open.stl"), False),
        (str(tmp_path / "b.stl"), False), (str(tmp_path / "sub" / "b.stl"), True)]   # two files, one name
    assert "is already the output of" in rows[3]["error"]
    assert sorted(p.name for p in out.iterdir()) == ["b.stl", "open.stl"]
    assert p3d.check(str(out / "open.stl")).ok and p3d.props(str(out / "open.stl")).volume == 1
    assert "4 files: 3 ok, 1 error" in result.stderr
