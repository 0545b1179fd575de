"""Task-pose files for `armkit place`: read in their units; every mistake and every mutated
file is one ModelFileError naming the file and the field, or a task that loads whole."""

from __future__ import annotations

import copy
import math
import random

import numpy as np
import pytest
import yaml

from armkit.errors import ModelFileError
from armkit.io.task_poses import read_task_poses
from armkit.spatial import pose_from_xyz_rpy

GOOD = {
    "units": {"length": "mm", "angle": "deg"},
    "poses": [{"name": "stop 1", "xyz": [1200, 900, 800], "rpy": [0, 0, -90]},
              {"xyz": [1350, 900, 800], "yaw": -90}],
    "base": {"floor": {"x": [-500, 500], "y": [0, 200], "z": 100, "step": 50,
                       "yaw": [-90, 90], "yaw_step": 30}},
    "mask": "position+yaw",
}


def write(tmp_path, document, name="task.yaml"):
    path = tmp_path / name
    path.write_text(document if isinstance(document, str) else yaml.safe_dump(document))
    return path


def test_a_task_file_reads_in_si(tmp_path):
    task = read_task_poses(write(tmp_path, GOOD))
    np.testing.assert_allclose(task.poses, [
        pose_from_xyz_rpy([1.2, 0.9, 0.8], [0, 0, -math.pi / 2]),
        pose_from_xyz_rpy([1.35, 0.9, 0.8], [0, 0, -math.pi / 2])], atol=1e-15)
    assert task.names == ("stop 1", "pose 1") and task.mask == "position+yaw"
    assert task.criterion is None and task.grid.kind == "floor"
    assert task.grid.shape == (5, 21, 7)
    np.testing.assert_allclose(task.grid.axes["x"][[0, -1]], [-0.5, 0.5])
    np.testing.assert_allclose(task.grid.axes["yaw"], np.radians(np.arange(-90, 91, 30)))
    assert task.grid.positions[:, 2].max() == pytest.approx(0.1)
    rail = copy.deepcopy(GOOD)
    rail["base"] = {"rail": {"from": [0, 0, 0], "to": [3000, 0, 0], "step": 10, "yaw": 90}}
    task = read_task_poses(write(tmp_path, rail))
    assert task.grid.kind == "rail" and task.grid.shape == (301, 1)
    np.testing.assert_allclose(task.grid.yaws, math.pi / 2)


@pytest.mark.parametrize("change, field, expected", [
    (lambda d: d.pop("poses"), "poses", "a value"),
    (lambda d: d.update(poses=[]), "poses", "at least 1"),
    (lambda d: d["poses"][0].update(xyz=[1, 2]), "poses[0].xyz", "at least 3"),
    (lambda d: d["poses"][0].update(xyz=[1, 2, True]), "poses[0].xyz[2]", "a valid number"),
    (lambda d: d["poses"][0].update(xyz=[1, 2, 1e300]), "poses[0].xyz",
     "numbers from -1e+09 to 1e+09"),
    (lambda d: d["poses"][1].update(rpy=[0, 0, 0]), "poses[1]", "rpy or yaw"),
    (lambda d: d["poses"][0].update(colour="red"), "poses[0]", "one of name, xyz, rpy, yaw"),
    (lambda d: d["base"].update(rail={"from": [0, 0, 0], "to": [1, 0, 0], "step": 1}), "base",
     "floor or rail, found both"),
    (lambda d: d["base"]["floor"].update(step=0), "base.floor.step", "a positive length"),
    (lambda d: d["base"]["floor"].update(x=[5, -5]), "base.floor.x", "a range low .. high"),
    (lambda d: d["base"]["floor"].update(step=0.1), "base.floor.step", "at most 1,000,000"),
    (lambda d: d["base"]["floor"].update(yaw_step=-1), "base.floor.yaw_step", "above 0"),
    (lambda d: d.update(mask="pos"), "mask", "'pose', 'position'"),
    (lambda d: d.update(criterion="speed"), "criterion", "'reachability' or 'manipulability'"),
    (lambda d: d.update(units={"length": "in", "angle": "deg"}), "units.length", "'mm' or 'm'"),
])
def test_each_mistake_names_its_field(tmp_path, change, field, expected):
    document = copy.deepcopy(GOOD)
    change(document)
    path = write(tmp_path, document)
    with pytest.raises(ModelFileError) as caught:
        read_task_poses(path)
    assert str(caught.value).startswith(f"{path}: {field}: expected"), str(caught.value)
    assert expected in str(caught.value)


@pytest.mark.parametrize("text", ["", "[1, 2]", "poses: {", "a: 1\na: 2", "x: &a 1\ny: *a"])
def test_files_that_are_not_task_files(tmp_path, text):
    path = write(tmp_path, text)
    with pytest.raises(ModelFileError, match=f"^{path}: "):
        read_task_poses(path)
    with pytest.raises(ModelFileError, match="expected a readable file"):
        read_task_poses(tmp_path / "missing.yaml")


WRONG = [True, "7", None, [], {}, [1, 2, 3], -1, 0, 1e308, -1e308, "nan", 10**400]


def _leaves(node, prefix=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, prefix + (i,))
    yield prefix


def mutant(rng: random.Random) -> str:
    """The good file with one value replaced, a key dropped or added, or its text damaged."""
    document = copy.deepcopy(GOOD)
    paths = [p for p in _leaves(document) if p]
    kind = rng.randrange(4)
    if kind < 3:
        path = rng.choice(paths)
        parent = document
        for key in path[:-1]:
            parent = parent[key]
        if kind == 0:
            parent[path[-1]] = rng.choice(WRONG)
        elif kind == 1 and isinstance(parent, dict):
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[rng.choice(["extra", "Step", "from", "yaw"])] = rng.choice(WRONG)
        return yaml.safe_dump(document)
    text = bytearray(yaml.safe_dump(document).encode())
    for _ in range(rng.randint(1, 6)):
        at = rng.randrange(len(text))
        text[at] = rng.choice(b" :-[]{},\n0123456789.e\"'&*!#\x00\xff")
    return text.decode("utf-8", errors="replace")


def fuzz(tmp_path, count: int, seed: int) -> None:
    rng = random.Random(seed)
    path = tmp_path / "mutant.yaml"
    for _ in range(count):
        path.write_text(mutant(rng), encoding="utf-8")
        try:
            task = read_task_poses(path)
        except ModelFileError as err:
            assert str(err).startswith(f"{path}"), str(err)
            continue
        assert np.isfinite(task.poses).all() and np.isfinite(task.grid.poses).all()
        assert len(task.poses) == len(task.names) >= 1


def test_mutated_files_load_whole_or_say_why(tmp_path):
    fuzz(tmp_path, 300, seed=1)


@pytest.mark.slow
def test_many_mutated_files_load_whole_or_say_why(tmp_path):
    fuzz(tmp_path, 5000, seed=2)
