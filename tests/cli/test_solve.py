"""``p3d solve`` on the command line: examples, JSON keys, trajectory CSV, errors and exit codes."""

from __future__ import annotations

import csv
import json
import re
import shlex

import numpy as np
import pytest
from click.testing import CliRunner

from helpers.cli import run
from helpers.real_meshes import REPO
from p3d_cli.cli.main import cli

EXAMPLES = REPO / "examples"
DOCS = (REPO / "docs" / "solve.md").read_text()


@pytest.mark.parametrize("name, rank, equations", [
    ("pendulum", 1, 1), ("hinged_door", 5, 10), ("chain", 15, 15), ("four_bar", 17, 20)])
def test_examples_solve_with_the_documented_rank(name, rank, equations):
    done = run("solve", EXAMPLES / f"{name}.yaml", "--json")
    assert done.exit_code == 0, done.output
    record = json.loads(done.output)
    assert (record["rank"], record["equations"], record["redundant"]) == (rank, equations, equations - rank)
    assert {"bodies", "constraints", "rank", "redundant", "kinetic_energy", "momentum"} <= set(record)
    for body in record["bodies"].values():
        assert {"position", "rotation", "velocity", "angular_velocity"} <= set(body)
        assert len(body["rotation"]) == 4
    for c in record["constraints"]:
        assert {"type", "a", "b", "impulse", "error"} <= set(c)
        assert c["error"] < 1e-12
    assert record["kinetic_energy"]["after"] <= record["kinetic_energy"]["before"]
    assert set(record["momentum"]) == {"before", "after"}


def test_pendulum_example_keeps_only_the_swing():
    record = json.loads(run("solve", EXAMPLES / "pendulum.yaml", "--json").output)
    bob = record["bodies"]["bob"]
    # Bob at 30° on a 1 m bar, pushed with (1, 0, 0): the radial part (0.5) goes, the
    # tangential part (cos 30°, along (cos 30°, 0, sin 30°)) stays.
    np.testing.assert_allclose(bob["velocity"], [0.75, 0, 0.75 * np.tan(np.radians(30))], atol=1e-12)
    assert record["constraints"][0]["impulse"] == pytest.approx(-0.5)


def test_docs_examples_run():
    lines = re.findall(r"^\$ (p3d solve .*)$", DOCS, re.M)
    assert len(lines) >= 4
    for line in lines:
        words = shlex.split(line)[1:]
        words = [str(REPO / w) if w.startswith("examples/") else w for w in words]
        done = run(*words)
        assert done.exit_code == 0, f"{line}\n{done.output}"
        assert "rank" in done.output


def test_summary_mentions_redundancy():
    done = run("solve", EXAMPLES / "four_bar.yaml")
    assert done.exit_code == 0
    assert "rank 17 of 20 equations (3 redundant" in done.output
    assert "nan" not in done.output.lower()


def test_trajectory_has_one_row_per_body_per_step(tmp_path):
    out = tmp_path / "swing.csv"
    done = run("solve", EXAMPLES / "chain.yaml", "--steps", 25, "--dt", 0.002, "--trajectory", out, "--json")
    assert done.exit_code == 0, done.output
    rows = list(csv.reader(out.open()))
    assert rows[0] == "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz".split(",")
    assert len(rows) == 1 + 25 * 6
    assert [r[1] for r in rows[1:7]] == ["anchor", "link1", "link2", "link3", "link4", "link5"]
    assert float(rows[1][0]) == pytest.approx(0.002) and float(rows[-1][0]) == pytest.approx(0.05)
    last = {r[1]: r for r in rows[-6:]}
    record = json.loads(done.output)
    np.testing.assert_allclose([float(x) for x in last["link5"][9:12]], record["bodies"]["link5"]["velocity"])
    # x, y, z is the centre of mass: the links' centres are their frame origins.
    np.testing.assert_allclose([float(x) for x in last["link5"][2:5]], record["bodies"]["link5"]["position"])
    assert record["steps"] == 25 and record["max_position_error"] < 1e-9


@pytest.mark.parametrize("args, where", [
    (["--steps", "10"], "--dt"),
    (["--dt", "0.01"], "--dt"),
    (["--trajectory", "x.csv"], "--trajectory"),
])
def test_stepping_options_are_checked(args, where):
    done = run("solve", EXAMPLES / "pendulum.yaml", *args)
    assert done.exit_code == 2
    assert f"p3d: error: {where}:" in done.output


def test_bad_scene_gets_one_line_and_exit_2(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text((EXAMPLES / "chain.yaml").read_text().replace("b: link3,", "b: link33,"))
    done = run("solve", scene)
    assert done.exit_code == 2
    lines = done.output.strip().splitlines()
    assert len(lines) == 1
    assert lines[0] == (f"p3d: error: {scene}: constraints[2].b: no body named 'link33'; bodies are: "
                        "anchor, link1, link2, link3, link4, link5")


def test_missing_scene_file_is_a_usage_error(tmp_path):
    done = run("solve", tmp_path / "nope.yaml")
    assert done.exit_code == 2
    assert "cannot be read" in done.output


def test_help_shows_an_example():
    done = run("solve", "--help")
    assert done.exit_code == 0
    assert "p3d solve examples/pendulum.yaml" in done.output


def test_unwritable_trajectory_is_a_usage_error(tmp_path):
    scene = str(REPO / "examples" / "pendulum.yaml")
    target = str(tmp_path / "no-such-dir" / "swing.csv")
    result = CliRunner().invoke(cli, ["solve", scene, "--steps", "2", "--dt", "0.01", "--trajectory", target])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"p3d: error: {target}: cannot write the trajectory: the folder")
    assert result.stderr.count("\n") == 1


def test_trajectory_over_the_scene_is_refused_and_the_scene_kept(tmp_path):
    scene = tmp_path / "pendulum.yaml"
    scene.write_bytes((REPO / "examples" / "pendulum.yaml").read_bytes())
    before = scene.read_bytes()
    result = CliRunner().invoke(cli, ["solve", str(scene), "--steps", "2", "--dt", "0.01", "--trajectory", str(scene)])
    assert result.exit_code == 2 and "would overwrite the input" in result.stderr
    assert scene.read_bytes() == before
