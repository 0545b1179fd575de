"""`armkit reach` and `armkit place`: numbers in the file's units, the map file the library
reads back, resuming, exit 1 with the reason when no base works, and bad input as one line."""

from __future__ import annotations

import json
import string
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import armkit
import armkit.io.scene
from armkit.cli import app
from armkit.io.reach_maps import ChunkFolder, read_map
from armkit.reach import reach_map

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
WATER = armkit.robot("water_supply")
TASK = {"units": {"length": "mm", "angle": "deg"},
        "poses": [{"name": "stop 1", "xyz": [1200, 900, 800], "yaw": -90},
                  {"name": "stop 2", "xyz": [1350, 900, 800], "yaw": -90}],
        "base": {"rail": {"from": [0, 0, 0], "to": [3000, 0, 0], "step": 20, "yaw": 90}}}


def run(*args: str):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def map_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("reach")
    result = run("reach", "water_supply", "--resolution", "100", "--orientations", "12",
                 "--out", out, "--json")
    assert result.exit_code == 0, result.output
    return out, json.loads(result.stdout)


def test_reach_writes_the_map_the_library_makes(map_folder):
    out, doc = map_folder
    m = reach_map(WATER, 0.1, 12)
    assert doc["units"] == {"length": "mm", "angle": "deg"} and doc["resolution"] == 100
    assert doc["voxels"] == len(m.voxels) and doc["ik_problems"] == 12 * len(m.voxels)
    assert doc["task"] == "position+yaw" and doc["method"] == "analytic"
    assert doc["reachable_voxels"] == int((m.count > 0).sum()) == doc["full_voxels"]
    assert doc["reachable_volume"] == pytest.approx(m.volume * 1e9)
    saved = read_map(doc["map"], WATER)
    for name in ("voxels", "count", "reached", "manipulability"):
        assert np.array_equal(getattr(saved, name), getattr(m, name))
    assert sorted(p.name for p in out.iterdir()) == [
        "water_supply_reach.html", "water_supply_reach.npz", "water_supply_reach.png"]


def test_reach_prints_a_summary(tmp_path):
    result = run("reach", "ur5", "--resolution", "0.25", "--orientations", "20", "--out",
                 tmp_path, "--si")
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert "voxels of 0.25 m x 20 orientations (" in text and "task pose): " in text
    assert "IK problems (analytic)" in text and "reachable: " in text
    assert f"map: {tmp_path / 'ur5_reach.npz'}" in text


def test_a_long_run_says_how_far_it_is_on_stderr(tmp_path, monkeypatch):
    import armkit.cli.reach as command

    monkeypatch.setattr(command, "QUIET_FOR", 0.0)
    result = run("reach", "water_supply", "--resolution", "100", "--orientations", "64",
                 "--out", tmp_path, "--json")
    assert result.exit_code == 0, result.output
    lines = result.stderr.splitlines()
    assert lines and all(line.startswith("solved ") and " voxels (" in line for line in lines)
    done = [int(line.split()[1].replace(",", "")) for line in lines]
    assert done == sorted(done) and 0 < done[0] < json.loads(result.stdout)["voxels"]


def test_reach_with_a_scene_counts_collision_free_solutions(tmp_path):
    shelf = armkit.io.scene.read_scene(ROOT / "examples" / "shelf.scene.yaml")
    result = run("reach", "inspection_6dof", "--resolution", "300", "--orientations", "8",
                 "--scene", ROOT / "examples" / "shelf.scene.yaml", "--out", tmp_path, "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["obstacles"] == len(shelf) > 0
    arm = armkit.robot("inspection_6dof")
    m = read_map(doc["map"], arm)
    expected = reach_map(arm, 0.3, 8, scene=shelf)
    assert np.array_equal(m.count, expected.count)
    assert m.count.sum() < reach_map(arm, 0.3, 8).count.sum()


def test_reach_resumes_an_interrupted_map(tmp_path):
    # A run stopped after its first chunk (of three) leaves it in --out's chunk folder; the
    # command takes it up, solves the rest, and removes the folder once the map is written.
    folder = ChunkFolder(tmp_path / "water_supply_reach.chunks")

    def stop(done, total):
        if done > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        reach_map(WATER, 0.1, 12, checkpoint=folder, threads=1, progress=stop)
    assert len(list(folder.path.glob("chunk-*.npz"))) == 1
    result = run("reach", "water_supply", "--resolution", "100", "--orientations", "12",
                 "--out", tmp_path)
    assert result.exit_code == 0, result.output
    assert "resumed: 1 chunks were finished before" in result.stderr
    assert not folder.path.exists()
    m = read_map(tmp_path / "water_supply_reach.npz", WATER)
    assert np.array_equal(m.reached, reach_map(WATER, 0.1, 12).reached)


def test_place_finds_the_base_along_the_rail(map_folder, tmp_path):
    out, doc = map_folder
    task = tmp_path / "inlets.yaml"
    task.write_text(yaml.safe_dump(TASK))
    result = run("place", "water_supply", task, "--map", doc["map"], "--out", tmp_path,
                 "--json")
    assert result.exit_code == 0, result.output
    placed = json.loads(result.stdout)
    assert placed["success"] and placed["criterion"] == "reachability"
    assert placed["bases"] == 151 and 0 < placed["feasible"] < 151
    assert placed["units"] == {"length": "mm", "angle": "deg"} and placed["yaw"] == 90
    # The joint values reach each inlet from that base (file units in, file units out).
    T_world_base = armkit.spatial.pose_from_xyz_rpy(np.array(placed["position"]) / 1000,
                                                    [0, 0, np.pi / 2])
    for pose, spec in zip(placed["poses"], TASK["poses"]):
        tool = T_world_base @ armkit.fk(WATER, WATER.q_to_si(pose["q"]))
        np.testing.assert_allclose(tool[:3, 3] * 1000, spec["xyz"], atol=1e-6)
        assert pose["reachability"] == 1.0
    assert (tmp_path / "water_supply_placement.png").read_bytes()[:4] == b"\x89PNG"
    text = run("place", "water_supply", task).stdout
    assert "best base: x " in text and "stop 2" in text and "margin: " in text


def test_place_without_a_base_exits_1_with_the_reason(tmp_path):
    far = dict(TASK, poses=[{"name": "far inlet", "xyz": [1200, 9000, 800], "yaw": 0}])
    task = tmp_path / "far.yaml"
    task.write_text(yaml.safe_dump(far))
    result = run("place", "water_supply", task, "--json")
    assert result.exit_code == 1
    doc = json.loads(result.stdout)
    assert not doc["success"] and "pose 0 (far inlet) from none" in doc["reason"]
    text = run("place", "water_supply", task)
    assert text.exit_code == 1 and "no placement: no base of the grid" in text.stdout


@pytest.mark.parametrize("args, words", [
    (("reach", "water_supply", "--resolution", "0"), "--resolution: expected a number above 0"),
    (("reach", "water_supply", "--resolution", "nan"), "--resolution: expected a finite"),
    (("reach", "water_supply", "--resolution", "0.001"), "resolution: expected at least"),
    (("reach", "water_supply", "--orientations", "0"), "--orientations: expected a whole number"),
    (("reach", "water_supply", "--orientations", "1e9"), "--orientations: expected a whole"),
    (("reach", "water_supply", "--method", "ikfast"), "--method: expected one of auto"),
    (("reach", "panda", "--method", "analytic", "--resolution", "0.5"),
     "method: expected 'auto', 'lm' or 'newton' for panda"),
    (("reach", "water_supply", "--scheduler", "nowhere"), "scheduler: expected an address"),
    (("reach", "water_supply", "--scene", "missing.yaml"), "missing.yaml: expected a readable"),
    (("reach", "nosuch"), "robot: expected a built-in name"),
    (("place", "water_supply"), "TASKS: expected a value, found none"),
    (("place", "water_supply", "missing.yaml"), "missing.yaml: expected a readable file"),
    (("place", "water_supply", "{task}", "--map", "missing.npz"),
     "missing.npz: expected a readable map file"),
    (("place", "ur5", "{task}", "--map", "{map}"), "robot: expected a map of ur5"),
])
def test_bad_input_is_one_line(args, words, tmp_path, map_folder):
    task = tmp_path / "task.yaml"
    task.write_text(yaml.safe_dump(TASK))
    filled = [a.replace("{task}", str(task)).replace("{map}", map_folder[1]["map"])
              for a in args]
    result = run(*filled, "--out", tmp_path) if args[0] == "reach" else run(*filled)
    assert result.exit_code == 2, result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armkit: ") and words in lines[0], lines
    assert result.stdout == ""


def test_the_real_commands_end_to_end(tmp_path):
    task = tmp_path / "task.yaml"
    task.write_text(yaml.safe_dump(TASK))
    reach = subprocess.run([sys.executable, "-m", "armkit", "reach", "water_supply",
                            "--resolution", "200", "--orientations", "6", "--out",
                            str(tmp_path), "--json"], capture_output=True, text=True,
                           timeout=600)
    assert reach.returncode == 0, reach.stderr
    placed = subprocess.run([sys.executable, "-m", "armkit", "place", "water_supply",
                             str(task), "--map", json.loads(reach.stdout)["map"]],
                            capture_output=True, text=True, timeout=600)
    assert placed.returncode == 0, placed.stderr
    assert "best base:" in placed.stdout and placed.stderr == ""
    bad = subprocess.run([sys.executable, "-m", "armkit", "reach", "ur5", "--orientations",
                          "-3"], capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1
    assert "Traceback" not in bad.stderr


# --- every option against arbitrary text -------------------------------------------------------

TEXT = st.text(alphabet=string.printable, max_size=12) | st.sampled_from(
    ["0", "-1", "1e308", "nan", "inf", "1e-300", "3", "1.5", "", "--json", "tcp://", "x" * 300])
OPTIONS = ["--resolution", "--orientations", "--method", "--seed", "--scheduler", "--scene"]


def fuzz_reach(option: str, value: str, tmp_path) -> None:
    """One option of `armkit reach` set to `value`, the rest small: exit 0 with a map, or
    exit 2 with one line naming what was wrong; never a traceback."""
    args = {"--resolution": "400", "--orientations": "3", "--seed": "0"}
    args[option] = value
    line = ["reach", "water_supply", "--out", str(tmp_path)]
    for name, text in args.items():
        line += [name, text]
    result = runner.invoke(app, line)
    assert result.exit_code in (0, 2), (line, result.output, result.exception)
    assert not isinstance(result.exception, Exception) or \
        isinstance(result.exception, SystemExit), (line, result.exception)
    if result.exit_code == 2:
        lines = result.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith("armkit: "), (line, result.stderr)


@settings(max_examples=40)
@given(option=st.sampled_from(OPTIONS), value=TEXT)
def test_arbitrary_option_values_give_a_map_or_one_line(tmp_path_factory, option, value):
    fuzz_reach(option, value, tmp_path_factory.mktemp("fuzz"))


@pytest.mark.slow
@settings(max_examples=400)
@given(option=st.sampled_from(OPTIONS), value=TEXT)
def test_many_arbitrary_option_values_give_a_map_or_one_line(tmp_path_factory, option, value):
    fuzz_reach(option, value, tmp_path_factory.mktemp("fuzz"))
