"""One rule for a robot named in any file (task, scene, register map, hand-eye poses): a
built-in name is the built-in robot, anything else a file relative to the naming file."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

import armkit
from armkit.errors import ModelFileError
from armkit.io.handeye import read_handeye_poses
from armkit.io.register_maps import load_register_map
from armkit.io.scene import read_planning_problem
from armkit.io.tasks import load_task

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ROOT / "src" / "armkit" / "model" / "robots"


def _own_water_supply(folder: Path, filename: str) -> Path:
    """A robot file beside the naming files: the water-supply arm renamed "mine"."""
    doc = yaml.safe_load((ROBOTS / "water_supply.yaml").read_text())
    doc["name"] = "mine"
    path = folder / filename
    path.write_text(yaml.safe_dump(doc))
    return path


def _readers(folder: Path, robot: str) -> dict:
    """Each reader that names a robot, given `robot` in its file in `folder`; the robot each
    loaded."""
    task = yaml.safe_load((ROOT / "examples" / "tasks" / "water_supply.task.yaml").read_text())
    task["robot"] = robot
    (folder / "t.task.yaml").write_text(yaml.safe_dump(task))
    drive = yaml.safe_load((ROOT / "examples" / "drives" / "water_supply.map.yaml").read_text())
    drive["robot"] = robot
    (folder / "d.map.yaml").write_text(yaml.safe_dump(drive))
    scene = {"units": {"length": "mm", "angle": "deg"}, "robot": robot,
             "start": [100, 0, 0, 0], "goal": [200, 10, 10, 10], "obstacles": []}
    (folder / "s.scene.yaml").write_text(yaml.safe_dump(scene))
    poses = {"units": {"length": "mm", "angle": "deg"}, "mode": "eye_in_hand", "robot": robot,
             "poses": [{"q": [100, 10 * i, -5 * i, 3 * i],
                        "camera": {"xyz": [0, 0, 400], "rpy": [0, 0, 0]}} for i in range(3)]}
    (folder / "h.yaml").write_text(yaml.safe_dump(poses))
    return {"task": lambda: load_task(folder / "t.task.yaml").robot,
            "register map": lambda: load_register_map(folder / "d.map.yaml").robot,
            "scene": lambda: read_planning_problem(folder / "s.scene.yaml").robot,
            "hand-eye": lambda: read_handeye_poses(folder / "h.yaml")}


@pytest.mark.parametrize("reader", ["task", "register map", "scene"])
def test_a_built_in_name_is_the_built_in_robot_even_beside_a_file_of_that_name(reader,
                                                                                 tmp_path):
    _own_water_supply(tmp_path, "water_supply")          # a file named as the built-in one
    assert _readers(tmp_path, "water_supply")[reader]().name == "water_supply"
    assert _readers(tmp_path, "./water_supply")[reader]().name == "mine"


@pytest.mark.parametrize("reader", ["task", "register map", "scene"])
def test_a_file_is_taken_from_the_naming_files_folder(reader, tmp_path, monkeypatch):
    _own_water_supply(tmp_path, "arm.yaml")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)                         # not from the working directory
    assert _readers(tmp_path, "arm.yaml")[reader]().name == "mine"


@pytest.mark.parametrize("reader", ["task", "register map", "scene", "hand-eye"])
def test_an_unknown_robot_is_one_error_naming_the_file_and_field(reader, tmp_path):
    with pytest.raises(ModelFileError) as err:
        _readers(tmp_path, "water_suply")[reader]()
    message = str(err.value)
    assert "robot: expected a built-in robot name or a robot file, found 'water_suply'" in message
    assert "did you mean 'water_supply'?" in message and "\n" not in message


def test_the_rule_for_names_given_to_armkit_robot(tmp_path, monkeypatch):
    _own_water_supply(tmp_path, "ur5")
    monkeypatch.chdir(tmp_path)
    assert armkit.robot("ur5").name == "ur5"             # the built-in one
    assert armkit.robot("./ur5").name == "mine"
    assert armkit.robot("ur5", tmp_path).name == "ur5"
    shutil.copy(tmp_path / "ur5", tmp_path / "arm.yaml")
    assert armkit.robot("arm.yaml", tmp_path).name == "mine"
