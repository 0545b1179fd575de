"""Robot files: YAML round trip, and one precise message per mistake (file, field, expected, found)."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
import yaml

import armkit
from armkit.errors import InputError, ModelFileError
from armkit.io.robot_files import load_robot, robot_document, save_robot
from tests.helpers import random_q

GOOD = """\
name: arm
units: {length: mm, angle: deg}
convention: dh
joints:
  - {name: a, type: revolute, alpha: 90, a: 0, d: 100, theta: 0, limits: [-90, 90]}
  - {name: b, type: revolute, alpha: 0, a: 300, d: 0, theta: 0, limits: [-90, 90]}
  - {name: c, type: prismatic, alpha: 0, a: 0, d: 0, theta: 0, limits: [0, 200]}
"""


def test_round_trip_of_every_builtin(any_robot, tmp_path):
    path = tmp_path / "robot.yaml"
    save_robot(any_robot, path)
    again = load_robot(path)
    assert robot_document(again) == robot_document(any_robot)
    Q = random_q(any_robot, 50)
    np.testing.assert_allclose(armkit.fk(again, Q), armkit.fk(any_robot, Q), atol=1e-13)
    for key in ("lower", "upper", "velocity_limits", "acceleration_limits"):
        np.testing.assert_allclose(getattr(again.chain, key), getattr(any_robot.chain, key),
                                   rtol=1e-12)


def test_saved_file_keeps_the_file_units_and_values(tmp_path):
    path = tmp_path / "ws.yaml"
    save_robot(armkit.robot("water_supply"), path)
    doc = yaml.safe_load(path.read_text())
    assert doc["units"] == {"length": "mm", "angle": "deg"}
    assert doc["joints"][0]["d"] == 525.5                  # not 525.5000000000001
    assert doc["joints"][4]["a"] == 352.5 and doc["joints"][4]["limits"] == [-180, 180]


def test_units_convert_to_si(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(GOOD)
    robot = load_robot(path)
    assert robot.upper == pytest.approx([np.pi / 2, np.pi / 2, 0.2])
    np.testing.assert_allclose(robot.q_to_si([90, 45, 150]), [np.pi / 2, np.pi / 4, 0.15])
    np.testing.assert_allclose(robot.q_from_si(robot.q_to_si([90, 45, 150])), [90, 45, 150])


def write(tmp_path, text: str):
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent(text))
    return path


def broken(tmp_path, old: str, new: str):
    assert old in GOOD
    return write(tmp_path, GOOD.replace(old, new))


@pytest.mark.parametrize("old, new, field, words", [
    ("units: {length: mm, angle: deg}\n", "", "units", "expected a value, found nothing"),
    ("length: mm", "length: inch", "units.length", "'mm' or 'm', found 'inch'"),
    ("convention: dh", "convention: xyz", "convention", "one of dh, mdh, poe, urdf"),
    ("a: 300", "a: three hundred", "joints[1].a", "a valid number, found 'three hundred'"),
    ("limits: [-90, 90]}\n  - {name: b", "limits: [90, -90]}\n  - {name: b", "joints[0].limits",
     "lower < upper, found [90.0, -90.0]"),
    ("limits: [0, 200]", "velocity: 10", "joints[2]", "limits [lower, upper] for a prismatic"),
    ("theta: 0, limits: [0, 200]", "theta: 0, limts: [0, 200]", "joints[2]",
     "unknown field 'limts'"),
    ("type: prismatic", "type: spherical", "joints[2].type",
     "'revolute', 'prismatic' or 'fixed'"),
    ("name: arm\n", "", "name", "a value"),
    ("joints:\n", "joints: 3\nx:\n", "", ""),
])
def test_each_mistake_names_its_field(tmp_path, old, new, field, words):
    path = broken(tmp_path, old, new)
    with pytest.raises(ModelFileError) as err:
        load_robot(path)
    message = str(err.value)
    assert message.startswith(str(path)), message
    assert f": {field}:" in message or not field, message
    assert words in message, message


def test_unknown_field_suggests_the_near_one(tmp_path):
    with pytest.raises(ModelFileError, match=r"did you mean 'limits'\?"):
        load_robot(broken(tmp_path, "theta: 0, limits: [0, 200]", "theta: 0, limts: [0, 200]"))


def test_yaml_syntax_error_names_the_line(tmp_path):
    with pytest.raises(ModelFileError, match=r"bad.yaml: line 3: expected valid YAML, found expected ',' or '}'"):
        load_robot(write(tmp_path, "name: a\nunits: {length: mm\nconvention: dh\njoints: [\n"))


def test_duplicate_key_is_refused(tmp_path):
    with pytest.raises(ModelFileError, match="key 'name' given twice"):
        load_robot(write(tmp_path, GOOD + "name: again\n"))


def test_not_a_mapping(tmp_path):
    with pytest.raises(ModelFileError, match="expected a mapping of fields .*found a list"):
        load_robot(write(tmp_path, "- 1\n- 2\n"))


def test_missing_file():
    with pytest.raises(ModelFileError, match="nowhere.yaml: expected a readable file"):
        load_robot("nowhere.yaml")


def test_only_fixed_rows(tmp_path):
    text = GOOD.split("joints:")[0] + "joints:\n  - {type: fixed, alpha: 0, a: 0, d: 1, theta: 0}\n"
    with pytest.raises(ModelFileError, match="joints: expected at least one revolute or prismatic"):
        load_robot(write(tmp_path, text))


@pytest.mark.parametrize("joint, field, words", [
    ("{type: revolute, axis: [0, 0, 1], limits: [-1, 1]}", "joints[0]", "a point on the axis"),
    ("{type: revolute, axis: [0, 0, 0], point: [0, 0, 0]}", "joints[0]", "a non-zero axis"),
    ("{type: revolute, axis: [0, 1], point: [0, 0, 0]}", "joints[0].axis", "at least 3 item(s), found 2"),
])
def test_screw_file_mistakes(tmp_path, joint, field, words):
    text = ("name: s\nunits: {length: mm, angle: deg}\nconvention: poe\n"
            f"home: {{xyz: [1, 0, 0]}}\njoints:\n  - {joint}\n")
    with pytest.raises(ModelFileError) as err:
        load_robot(write(tmp_path, text))
    assert f": {field}: expected" in str(err.value) and words in str(err.value), str(err.value)


def test_unknown_builtin_name_suggests_one():
    with pytest.raises(InputError, match=r"found 'ur6' \(did you mean 'ur5'\?\)"):
        armkit.robot("ur6")


@pytest.mark.parametrize("text, words", [
    (GOOD.replace("a: 300", "a: .nan"), "joints[1].a: expected a finite number"),
    (GOOD.replace("d: 100", "d: .inf"), "joints[0].d: expected a finite number"),
    ("? [a, b]\n: 1\n", "expected valid YAML, found a key that is a list"),
])
def test_non_finite_numbers_and_odd_keys(tmp_path, text, words):
    with pytest.raises(ModelFileError) as err:
        load_robot(write(tmp_path, text))
    assert words in str(err.value), str(err.value)


def test_a_file_that_is_not_utf8(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_bytes(GOOD.encode() + b"\xff\xfe")
    with pytest.raises(ModelFileError, match="bad.yaml: expected a UTF-8 text file, found byte 0xff"):
        load_robot(path)


def test_unnamed_joints_are_numbered_among_the_moving_ones(tmp_path):
    text = GOOD.split("joints:")[0] + ("joints:\n  - {type: fixed, alpha: 0, a: 0, d: 1, theta: 0}\n"
                                       "  - {type: revolute, alpha: 0, a: 1, d: 0, theta: 0}\n"
                                       "  - {type: revolute, alpha: 0, a: 1, d: 0, theta: 0}\n")
    robot = load_robot(write(tmp_path, text))
    assert robot.joint_names == ("q1", "q2")
    again = tmp_path / "again.yaml"
    save_robot(robot, again)
    assert load_robot(again).joint_names == ("q1", "q2")


def test_robot_tables_are_read_only(any_robot):
    table = any_robot.table
    for name in ("T_base", "T_tool", "T_home"):
        if hasattr(table, name):
            with pytest.raises(ValueError):
                getattr(table, name)[0, 3] = 9.0


def test_an_empty_joint_list(tmp_path):
    with pytest.raises(ModelFileError, match=r"joints: expected at least 1 item\(s\), found 0"):
        load_robot(write(tmp_path, GOOD.split("joints:")[0] + "joints: []\n"))


@pytest.mark.parametrize("old, new, field, words", [
    ("a: 300", "a: true", "joints[1].a", "expected a valid number, found True"),
    ("alpha: 90", "alpha: '90'", "joints[0].alpha", "expected a valid number, found '90'"),
    ("limits: [0, 200]", "limits: [false, 200]", "joints[2].limits[0]",
     "expected a valid number, found False"),
    ("a: 300", "a: 1e308", "joints[1].a", "expected a length of at most 1000 m, found 1e+308 mm"),
    ("a: 300", "a: -2e6", "joints[1].a", "expected a length of at most 1000 m, found -2e+06 mm"),
    ("d: 100", "d: 1" + "0" * 400, "joints[0].d", ("expected a finite number, found an integer "
     "of about 400 digits")),
    ("alpha: 90", "alpha: 1e9", "joints[0].alpha", ("expected an angle of at most 1000 rad, "
     "found 1e+09 deg")),
    ("limits: [-90, 90]}\n  - {name: b", "limits: [-1e300, 90]}\n  - {name: b",
     "joints[0].limits", "an angle of at most 1000 rad, found -1e+300 deg"),
    ("limits: [0, 200]", "limits: [0, 200], velocity: 1e300", "joints[2].velocity",
     "expected a velocity limit of at most 1e+06 m/s, found 1e+300 mm/s"),
    ("convention: dh", "convention: [dh]", "convention",
     "expected one of dh, mdh, poe, urdf, found ['dh']"),
    ("convention: dh", "convention: {dh: 1}", "convention", "found {'dh': 1}"),
    ("name: b,", "name: a,", "joints[1].name",
     "expected a name no other joint has, found 'a', the name of joints[0]"),
    ("{name: c, ", "{name: q1, ", "joints[2].name", "found 'q1', the name of joints[0]"),
    ("name: arm", "name: [arm]", "name", "a valid string"),
])
def test_strict_types_ranges_and_names(tmp_path, old, new, field, words):
    if old == "{name: c, ":                     # q1 clashes with an unnamed first joint
        text = GOOD.replace("{name: a, ", "{").replace(old, new)
    else:
        text = GOOD.replace(old, new)
    assert text != GOOD
    path = write(tmp_path, text)
    with pytest.raises(ModelFileError) as err:
        load_robot(path)
    message = str(err.value)
    assert message.startswith(f"{path}: {field}: "), message
    assert words in message, message


@pytest.mark.parametrize("text, words", [
    ("", ("expected a mapping of fields (name, units, convention, ...), found nothing (an empty "
         "document)")),
    ("# only a comment\n", "found nothing (an empty document)"),
    ("42\n", "found an int"),
])
def test_empty_and_scalar_files(tmp_path, text, words):
    path = write(tmp_path, text)
    with pytest.raises(ModelFileError) as err:
        load_robot(path)
    assert str(err.value) == f"{path}: {words}" or words in str(err.value), str(err.value)


@pytest.mark.parametrize("joint, field, words", [
    ("{type: revolute, axis: [0, 0, 1e308], point: [0, 0, 0]}", "joints[0].axis",
     "a direction component of at most 1000"),
    ("{type: revolute, axis: [0, 0, 1], point: [0, 0, 1e7]}", "joints[0].point",
     "a length of at most 1000 m, found 1e+07 mm"),
    ("{type: revolute, axis: [0, 0, true], point: [0, 0, 0]}", "joints[0].axis[2]",
     "expected a valid number, found True"),
])
def test_screw_file_ranges(tmp_path, joint, field, words):
    text = ("name: s\nunits: {length: mm, angle: deg}\nconvention: poe\n"
            f"home: {{xyz: [1, 0, 0]}}\njoints:\n  - {joint}\n")
    with pytest.raises(ModelFileError) as err:
        load_robot(write(tmp_path, text))
    assert f": {field}: expected" in str(err.value) and words in str(err.value), str(err.value)


def test_huge_pose_values(tmp_path):
    with pytest.raises(ModelFileError, match=r"home.xyz: expected a length of at most 1000 m, "
                                             r"found 5e\+200 mm"):
        load_robot(write(tmp_path, "name: s\nunits: {length: mm, angle: deg}\nconvention: poe\n"
                                   "home: {xyz: [5e200, 0, 0]}\njoints:\n"
                                   "  - {type: revolute, axis: [0, 0, 1], point: [0, 0, 0]}\n"))
    with pytest.raises(ModelFileError, match=r"tool.rpy: expected an angle of at most 1000 rad"):
        load_robot(write(tmp_path, GOOD + "tool: {rpy: [0, 0, 1e6]}\n"))


def test_billion_laughs_is_refused_at_once(tmp_path):
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)]
    path = write(tmp_path, GOOD + "\n".join(lines) + "\n")
    with pytest.raises(ModelFileError, match=r"line 9: expected valid YAML, found an alias "
                                             r"\(\*a0\); anchors and aliases are not supported"):
        load_robot(path)


def test_deep_nesting_is_refused(tmp_path):
    path = write(tmp_path, GOOD.replace("a: 300", "a: " + "[" * 900 + "]" * 900))
    with pytest.raises(ModelFileError, match="expected valid YAML, found nesting deeper than 64"):
        load_robot(path)


def test_a_file_too_large_to_be_a_robot(tmp_path):
    path = write(tmp_path, GOOD + "#" * 2**20 + "\n")
    with pytest.raises(ModelFileError, match="expected a file of at most 1048576 bytes"):
        load_robot(path)


def test_a_tip_is_for_urdf_files_only(tmp_path):
    with pytest.raises(InputError, match="tip: expected none for a robot file"):
        load_robot(write(tmp_path, GOOD), tip="hand")
