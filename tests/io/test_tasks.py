"""Task files: every mistake one ModelFileError naming the file and the field; mutated files
never crash, hang or load a changed task silently."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from armkit.errors import ArmkitError, ModelFileError
from armkit.io.tasks import load_task
from armkit.planning import Box, Cylinder

EXAMPLES = Path(__file__).parents[2] / "examples" / "tasks"
DEMO = (EXAMPLES / "water_supply.task.yaml").read_text()


def _write(tmp_path, text: str) -> Path:
    path = tmp_path / "task.yaml"
    path.write_text(text)
    return path


def test_the_demo_task_in_si(tmp_path):
    task = load_task(_write(tmp_path, DEMO))
    assert task.robot.name == "water_supply" and task.motion.waypoints == 10
    np.testing.assert_allclose(task.T_base_camera[:3, 3], [0.6, -0.2, 2.2])
    np.testing.assert_allclose(task.start, [0.05, 0, np.deg2rad(30), np.deg2rad(-30)])
    np.testing.assert_allclose((task.T_base_camera @ task.target.T_camera_target)[:3, 3],
                               [1.0, 0.3, 0.8], atol=1e-12)
    (post,) = task.scene.obstacles
    assert isinstance(post, Cylinder) and post.radius == pytest.approx(0.05)
    assert task.planner.resolution == pytest.approx(0.005) and task.drive.host is None
    assert task.drive.register_map.robot is task.robot          # the shipped water_supply map


def test_units_in_metres_and_radians(tmp_path):
    doc = yaml.safe_load(DEMO)
    doc.update(units={"length": "m", "angle": "rad"}, camera={"xyz": [0.6, -0.2, 2.2],
                                                              "rpy": [np.pi, 0, np.pi / 2]},
               target={"xyz": [0.5, 0.4, 1.4], "yaw": 1.0}, start=[0.05, 0, 0.5, -0.5])
    doc["scene"] = {"obstacles": [{"type": "box", "xyz": [1, 0, 0.3], "size": [0.1, 0.2, 0.6]}]}
    task = load_task(_write(tmp_path, yaml.safe_dump(doc)))
    (box,) = task.scene.obstacles
    assert isinstance(box, Box)
    np.testing.assert_allclose(box.size, [0.1, 0.2, 0.6])
    np.testing.assert_allclose(task.start, [0.05, 0, 0.5, -0.5])


def test_a_camera_file_fixed_or_on_the_gripper(tmp_path):
    (tmp_path / "fixed.yaml").write_text("units: {length: mm, angle: deg}\n"
                                         "camera_to_base: {xyz: [600, -200, 2200], "
                                         "rpy: [180, 0, 90]}\n")
    doc = yaml.safe_load(DEMO)
    doc["camera"] = {"file": "fixed.yaml"}
    task = load_task(_write(tmp_path, yaml.safe_dump(doc)))
    np.testing.assert_allclose(task.T_base_camera, load_task(_write(tmp_path, DEMO)).T_base_camera,
                               atol=1e-12)
    # A camera on the gripper (eye-in-hand result): T_base_camera = FK(q when it measured) X.
    (tmp_path / "hand.yaml").write_text(
        "units: {length: mm, angle: deg}\nhandeye:\n  mode: eye_in_hand\n"
        "  X: {xyz: [0, 50, 100], rpy: [180, 0, 0]}\n")
    doc["camera"] = {"file": "hand.yaml", "q": [100, 10, 20, 30]}
    task = load_task(_write(tmp_path, yaml.safe_dump(doc)))
    import armkit
    from armkit.spatial import pose_from_xyz_rpy
    robot = armkit.robot("water_supply")
    expected = armkit.fk(robot, robot.q_to_si([100, 10, 20, 30])) @ pose_from_xyz_rpy(
        [0, 0.05, 0.1], [np.pi, 0, 0])
    np.testing.assert_allclose(task.T_base_camera, expected, atol=1e-12)
    doc["camera"] = {"file": "hand.yaml"}
    with pytest.raises(ModelFileError, match="camera.q: expected the 4 joint values"):
        load_task(_write(tmp_path, yaml.safe_dump(doc)))


def test_a_scene_file_beside_the_task(tmp_path):
    (tmp_path / "cell.scene.yaml").write_text(
        "units: {length: mm, angle: deg}\nobstacles:\n"
        "  - {type: sphere, name: ball, center: [900, 0, 700], radius: 100}\n")
    doc = yaml.safe_load(DEMO)
    doc["scene"] = {"file": "cell.scene.yaml"}
    task = load_task(_write(tmp_path, yaml.safe_dump(doc)))
    assert task.scene.obstacles[0].radius == pytest.approx(0.1)


BAD = [
    # (change to the demo document, field named, words expected in the message)
    ({"robot": "nobody"}, "robot", "nobody"),
    ({"units": {"length": "cm", "angle": "deg"}}, "units.length", "cm"),
    ({"camera": None}, "camera", "camera's pose"),
    ({"camera": {"xyz": [1, 2]}}, "camera.xyz", "at least 3"),
    ({"target": {"xyz": [0, 0, 0], "rpy": [0, 0, 0], "yaw": 3}}, "target", "not both"),
    ({"target": {"xyz": [0, 0, ".inf"]}}, "target.xyz", ""),
    ({"target": {"xyz": [0, 0, 1e12]}}, "target.xyz", "from -1e+09 to 1e+09, found 1e+12"),
    ({"start": [0, 0, 0]}, "start", "4 joint values"),
    ({"start": [900, 0, 0, 0]}, "start[0]", "lift's limits"),
    ({"planner": {"name": "prm"}}, "planner.name", "prm"),
    ({"planner": {"seeed": 1}}, "planner", "did you mean 'seed'"),
    ({"motion": {"waypoints": 1}}, "motion.waypoints", "a whole number from 2 to 10000"),
    ({"motion": {"speed": 2}}, "motion.speed", "a number above 0 and at most 1, found 2"),
    ({"drive": {"host": "127.0.0.1", "port": 70000}}, "drive.port", "65535"),
    ({"drive": {"host": "127.0.0.1"}}, "drive.map", "register map"),
    ({"scene": {"obstacles": [{"type": "box", "xyz": [0, 0, 0]}]}}, "scene.obstacles[0]",
     "min and max corners or size"),
    ({"scene": {"obstacles": [{"type": "cone"}]}}, "scene.obstacles[0]", "cone"),
    ({"scene": {"file": "missing.scene.yaml"}}, "", "readable file"),
    ({"camera": {"file": "nowhere.yaml"}}, "", "readable file"),
    ({"camera": {"xyz": [0, 0, 0], "file": "mount.yaml"}}, "camera", "one of them"),
    ({"camera": {"xyz": [0, 0, 0], "q": [0, 0, 0, 0]}}, "camera.q", "eye-in-hand"),
    ({"target": {"cloud": "scan.pcd", "xyz": [0, 0, 0]}}, "target", "not both"),
    ({"target": {"rpy": [0, 0, 0]}}, "target.xyz", "cloud: FILE"),
    ({"target": {"xyz": [0, 0, 0], "mask": "elbow"}}, "target.mask", "position+yaw"),
    ({"targte": {}}, "top level", "did you mean 'target'"),
]


@pytest.mark.parametrize("change, field, words", BAD)
def test_each_mistake_names_its_field(tmp_path, change, field, words):
    doc = yaml.safe_load(DEMO)
    doc.update(change)
    path = _write(tmp_path, yaml.safe_dump(doc))
    with pytest.raises(ModelFileError) as err:
        load_task(path)
    text = str(err.value)
    assert "\n" not in text
    assert field in text and words in text
    named = [f for f in ("missing.scene.yaml", "nowhere.yaml") if f in str(change)]
    assert (named[0] if named else str(path)) in text      # the file at fault


@pytest.mark.parametrize("text", ["", "[1, 2]", "just text", "a: [", "\xff"])
def test_not_a_task(tmp_path, text):
    path = tmp_path / "task.yaml"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(ModelFileError, match=str(path)):
        load_task(path)


def test_mutated_task_files(tmp_path):
    """A seeded mutation of every scalar and key of the demo task: each either loads a valid
    task or gives one ModelFileError naming the file; nothing else escapes."""
    rng = np.random.default_rng(20261123)
    lines = DEMO.splitlines()
    replacements = ["-1", "0", "1e308", "nan", ".inf", "true", "[]", "{}", "null", "'x'",
                    "[1, 2, 3]", "-1e-300", "99999", "&a 1", "*a"]
    outcomes = {"loaded": 0, "refused": 0}
    for i in range(300):
        mutated = list(lines)
        k = int(rng.integers(len(mutated)))
        line = mutated[k]
        if ":" in line and not line.lstrip().startswith("#"):
            head, _, _ = line.partition(":")
            mutated[k] = f"{head}: {replacements[int(rng.integers(len(replacements)))]}"
        else:
            mutated[k] = line[: int(rng.integers(len(line) + 1))]
        path = tmp_path / f"m{i}.yaml"
        path.write_text("\n".join(mutated))
        try:
            task = load_task(path)
        except ModelFileError as err:
            assert str(path) in str(err) and "\n" not in str(err)
            outcomes["refused"] += 1
        except ArmkitError as err:       # a scene value the planning layer refuses
            assert "\n" not in str(err)
            outcomes["refused"] += 1
        else:
            assert np.isfinite(task.T_base_camera).all()
            assert np.isfinite(task.target.T_camera_target).all()
            outcomes["loaded"] += 1
    assert outcomes["refused"] > 50 and outcomes["loaded"] > 20
