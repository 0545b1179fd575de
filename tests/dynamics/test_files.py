"""Inertias from files: robot files' ``inertia:`` section and joints' torque, friction and
armature (file units converted, every mistake one error naming file and field), URDF
``<inertial>``, ``<limit effort>`` and ``<dynamics>``; saved and loaded back unchanged; mutated
files either load to finite dynamics or are refused by name."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armkit
from armkit.dynamics import inverse_dynamics, mass_matrix
from armkit.errors import ArmkitError, ModelFileError
from tests.dynamics.reference import robot_file

ARM_M = """name: arm
units: {length: m, angle: rad}
convention: dh
joints:
  - {type: revolute, alpha: 1.5707963267948966, a: 0, d: 0.3, theta: 0, limits: [-3, 3], torque: 80}
  - {type: revolute, alpha: 0, a: 0.4, d: 0, theta: 0, limits: [-3, 3], torque: 60, viscous: 0.5, coulomb: 0.2, armature: 0.01}
  - {type: prismatic, alpha: 0, a: 0, d: 0.1, theta: 0, limits: [0, 0.3], torque: 200}
inertia:
  links:
    - {mass: 3.0, com: [0, -0.05, 0], inertia: [0.02, 0.01, 0.02, 0, 0, 0]}
    - {mass: 2.0, com: [-0.2, 0, 0], inertia: [0.002, 0.03, 0.03, 0, 0.001, 0]}
    - {mass: 1.0, com: [0, 0, -0.05], inertia: [0.004, 0.004, 0.001, 0, 0, 0]}
  payload: {mass: 0.5, com: [0, 0, 0.02]}
"""


def arm_in_mm() -> str:
    """ARM_M in mm and deg: lengths times 1000, inertias times 1e6, angles in degrees."""
    doc = yaml.safe_load(ARM_M)
    doc["units"] = {"length": "mm", "angle": "deg"}
    for row in doc["joints"]:
        row["alpha"] = float(np.rad2deg(row["alpha"]))
        row["d"] *= 1000
        row["a"] *= 1000
        row["limits"] = ([float(x) for x in np.rad2deg(row["limits"])]
                         if row["type"] == "revolute" else [x * 1000 for x in row["limits"]])
    for body in doc["inertia"]["links"] + [doc["inertia"]["payload"]]:
        body["com"] = [x * 1000 for x in body["com"]]
        if "inertia" in body:
            body["inertia"] = [x * 1e6 for x in body["inertia"]]
    return yaml.safe_dump(doc)


def write(tmp_path: Path, text: str, name: str = "arm.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_file_units_convert(tmp_path):
    """The same arm in m/rad and in mm/deg: the same dynamics."""
    a = armkit.load_robot(write(tmp_path, ARM_M))
    b = armkit.load_robot(write(tmp_path, arm_in_mm(), "arm_mm.yaml"))
    rng = np.random.default_rng(0)
    q = rng.uniform(a.lower, a.upper, (20, 3))
    qd, qdd = rng.uniform(-1, 1, (2, 20, 3))
    np.testing.assert_allclose(inverse_dynamics(b, q, qd, qdd), inverse_dynamics(a, q, qd, qdd),
                               rtol=1e-12, atol=1e-12)
    assert a.torque_limits.tolist() == [80, 60, 200] == b.torque_limits.tolist()
    assert a.inertia.viscous.tolist() == [0, 0.5, 0] and a.inertia.armature[1] == 0.01
    assert a.inertia.payload.mass == 0.5


def test_saved_and_loaded_back(tmp_path):
    robot = armkit.load_robot(write(tmp_path, arm_in_mm()))
    armkit.save_robot(robot, tmp_path / "copy.yaml")
    again = armkit.load_robot(tmp_path / "copy.yaml")
    q = np.random.default_rng(1).uniform(robot.lower, robot.upper, (10, 3))
    np.testing.assert_array_equal(mass_matrix(again, q), mass_matrix(robot, q))
    np.testing.assert_array_equal(inverse_dynamics(again, q, q, q),
                                  inverse_dynamics(robot, q, q, q))
    assert np.array_equal(again.torque_limits, robot.torque_limits)


@pytest.mark.parametrize("change, field, words", [
    (lambda d: d["inertia"]["links"].pop(), "inertia.links", "3 bodies, one per moving joint"),
    (lambda d: d["inertia"]["links"][1].update(mass=-1), "inertia.links[1].mass",
     "greater than or equal to 0"),
    (lambda d: d["inertia"]["links"][0].update(inertia=[1, 1, 1, 5, 0, 0]),
     "inertia.links[0].inertia", "principal moments >= 0"),
    (lambda d: d["inertia"]["links"][0].update(inertia=[1, 1]), "inertia.links[0].inertia",
     "at least 6"),
    (lambda d: d["inertia"]["links"][0].update(com=[0, 0, "x"]), "inertia.links[0].com",
     "valid number"),
    (lambda d: d["inertia"]["links"][0].update(mass=1e300), "inertia.links[0].mass",
     "at most 1e+06"),
    (lambda d: d["inertia"].update(gravity=[0, 0, -9810]), "inertia.gravity", "0.1 .. 100"),
    (lambda d: [d["inertia"].pop("links"), d["joints"][1].pop("viscous"),
                d["joints"][1].pop("coulomb"), d["joints"][1].pop("armature")],
     "inertia.links", "3 bodies"),
    (lambda d: d["inertia"].update(extra=1), "inertia", "unknown field 'extra'"),
    (lambda d: d["joints"][0].update(torque=0), "joints[0].torque", "greater than 0"),
    (lambda d: d["joints"][0].update(torque=True), "joints[0].torque", "valid number"),
    (lambda d: d["joints"][1].update(viscous=-1), "joints[1].viscous",
     "greater than or equal to 0"),
    (lambda d: d["joints"][1].update(armature=1e300), "joints[1].armature", "at most"),
    (lambda d: d.pop("inertia"), "joints[1].armature", "an inertia: section with links"),
])
def test_mistakes_name_the_field(tmp_path, change, field, words):
    doc = yaml.safe_load(ARM_M)
    change(doc)
    path = write(tmp_path, yaml.safe_dump(doc))
    with pytest.raises(ModelFileError) as err:
        armkit.load_robot(path)
    message = str(err.value)
    assert message.startswith(f"{path}: {field}"), message
    assert words in message


def test_fixed_rows_take_no_dynamics(tmp_path):
    doc = yaml.safe_load(ARM_M)
    doc["joints"].append({"type": "fixed", "alpha": 0, "a": 0, "d": 0.1, "theta": 0,
                          "torque": 5})
    with pytest.raises(ModelFileError, match=r"joints\[3\].*expected none of limits"):
        armkit.load_robot(write(tmp_path, yaml.safe_dump(doc)))


def test_screw_file_gives_bodies_in_the_base_frame_at_home():
    """The tool changer's file gives each centre of mass in the base frame at home: the
    links' centres at home (forward kinematics' link frames) are those numbers."""
    robot = armkit.robot("tool_changer_6dof")
    doc = yaml.safe_load(Path(armkit.io.robot_files.__file__).parent.parent.joinpath(
        "model/robots/tool_changer_6dof.yaml").read_text())
    from armkit.model.inertia import home_link_frames

    frames = home_link_frames(robot.chain)
    for body, T, given_ in zip(robot.inertia.links, frames, doc["inertia"]["links"]):
        np.testing.assert_allclose((T[:3, :3] @ body.com + T[:3, 3]) * 1000, given_["com"],
                                   atol=1e-9)


def test_urdf_robot_file_adds_a_payload_and_gravity(tmp_path):
    urdf = robot_file("ur_description/urdf/ur5_robot.urdf")
    text = (f"name: ur5u\nunits: {{length: mm, angle: deg}}\nconvention: urdf\nurdf: {urdf}\n"
            "tip: tool0\ninertia: {payload: {mass: 2, com: [0, 0, 50]}, gravity: [0, 0, -1620]}\n")
    robot = armkit.load_robot(write(tmp_path, text))
    assert robot.inertia.payload.mass == 2 and robot.inertia.payload.com[2] == 0.05
    np.testing.assert_allclose(robot.inertia.gravity, [0, 0, -1.62])
    bad = text.replace("inertia: {", "inertia: {links: [], ")
    with pytest.raises(ModelFileError, match="inertia.links: expected none for a URDF robot"):
        armkit.load_robot(write(tmp_path, bad, "bad.yaml"))


# --- URDF ------------------------------------------------------------------------------------

URDF = """<robot name="two">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0 0 0.1" rpy="0 0.3 0"/><mass value="2"/>
      <inertia ixx="0.02" iyy="0.03" izz="0.01" ixy="0.001" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="l2">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.002" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
  <link name="tool">
    <inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="40"/><dynamics damping="0.4" friction="0.1"/>
  </joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.3" rpy="1.5707963267948966 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" velocity="2" effort="20"/>
  </joint>
  <joint name="fix" type="fixed"><parent link="l2"/><child link="tool"/>
    <origin xyz="0.4 0 0"/></joint>
</robot>
"""


def test_urdf_inertials_effort_and_friction(tmp_path):
    robot = armkit.load_robot(write(tmp_path, URDF, "two.urdf"))
    assert robot.torque_limits.tolist() == [40, 20]
    assert robot.inertia.viscous.tolist() == [0.4, 0] and robot.inertia.coulomb.tolist() == [0.1, 0]
    # The tool link is fixed to l2: merged into joint 2's body.
    assert robot.inertia.links[1].mass == 1.5
    np.testing.assert_allclose(robot.inertia.links[1].com, [0.4 * 0.5 / 1.5, 0, 0.05 * 0.5 / 1.5])


@pytest.mark.parametrize("old, new, field", [
    ('<mass value="2"/>', '<mass value="-2"/>', "<mass> value"),
    ('<mass value="2"/>', '<mass value="two"/>', "<mass> value"),
    ('<mass value="2"/>', '', "<mass>"),
    ('ixx="0.02"', 'ixx="nan"', "<inertia> ixx"),
    ('ixx="0.02"', '', "<inertia>"),
    ('ixx="0.02" iyy="0.03"', 'ixx="0.02" iyy="-0.5"', "<inertia>"),
    ('effort="40"', 'effort="0"', "<limit> effort"),
    ('effort="40"', 'effort="-1"', "<limit> effort"),
    ('damping="0.4"', 'damping="-0.4"', "<dynamics> damping"),
    ('friction="0.1"', 'friction="1e99"', "<dynamics> friction"),
])
def test_urdf_mistakes_name_the_element(tmp_path, old, new, field):
    path = write(tmp_path, URDF.replace(old, new, 1), "two.urdf")
    with pytest.raises(ModelFileError) as err:
        armkit.load_robot(path)
    assert str(err.value).startswith(str(path)) and field in str(err.value), str(err.value)


def test_urdf_without_inertials_has_no_dynamics(tmp_path):
    bare = re.sub(r"<inertial>.*?</inertial>", "", URDF, flags=re.S)
    robot = armkit.load_robot(write(tmp_path, bare, "bare.urdf"))
    assert robot.inertia is None and robot.dynamics is None


def test_a_finger_off_the_chain_is_not_counted():
    """The Panda to its hand: the fingers' joints are off the chain, so their links' masses
    are not part of the arm's bodies (a payload can stand for them)."""
    path = robot_file("panda_description/urdf/panda.urdf")
    robot = armkit.load_robot(path, tip="panda_hand")
    assert set(robot.table.carried) == {"panda_leftfinger", "panda_rightfinger"}
    hand = armkit.load_robot(path, tip="panda_leftfinger")
    assert hand.inertia.mass > robot.inertia.mass


# --- fuzz ------------------------------------------------------------------------------------

VALUES = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**20, 10**20),
                   st.booleans(), st.none(), st.text(max_size=5),
                   st.lists(st.floats(-10, 10), max_size=7))


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data())
def test_mutated_inertia_sections_load_or_are_refused_by_name(tmp_path, data):
    load_mutated(tmp_path, data)


@pytest.mark.slow
@settings(max_examples=1000, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data())
def test_many_mutated_inertia_sections(tmp_path, data):
    load_mutated(tmp_path, data)


def load_mutated(tmp_path, data) -> None:
    """ARM_M with one to three fields of its inertia section or joints replaced by any value:
    it loads to finite dynamics, or is refused with the file's path and the field."""
    doc = yaml.safe_load(ARM_M)
    for _ in range(data.draw(st.integers(1, 3))):
        where = data.draw(st.sampled_from(["link", "payload", "gravity", "joint"]))
        value = data.draw(VALUES)
        if where == "link":
            body = doc["inertia"]["links"][data.draw(st.integers(0, 2))]
            body[data.draw(st.sampled_from(["mass", "com", "inertia", "spin"]))] = value
        elif where == "payload":
            doc["inertia"]["payload"][data.draw(st.sampled_from(["mass", "com", "inertia"]))] = value
        elif where == "gravity":
            doc["inertia"]["gravity"] = value
        else:
            joint = doc["joints"][data.draw(st.integers(0, 2))]
            joint[data.draw(st.sampled_from(["torque", "viscous", "coulomb", "armature"]))] = value
    path = write(tmp_path, yaml.safe_dump(doc))
    try:
        robot = armkit.load_robot(path)
    except ModelFileError as err:
        assert str(err).startswith(f"{path}: "), str(err)
        return
    q = np.zeros(3)
    assert np.isfinite(inverse_dynamics(robot, q, q + 0.1, q + 0.1)).all()


@settings(max_examples=150, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(re.findall(r'(?:value|ixx|iyy|izz|ixy|ixz|iyz|effort|damping|friction'
                                  r'|xyz|rpy)="[^"]*"', URDF)),
       st.text(alphabet=st.sampled_from(list("0123456789.-eE +naif")), max_size=12))
def test_mutated_urdf_inertials_load_or_are_refused_by_name(tmp_path, attribute, text):
    key = attribute.split("=")[0]
    path = write(tmp_path, URDF.replace(attribute, f'{key}="{text}"', 1), "two.urdf")
    try:
        robot = armkit.load_robot(path)
    except ModelFileError as err:
        assert str(err).startswith(f"{path}: "), str(err)
        return
    except ArmkitError as err:          # pragma: no cover - any other error is a failure
        raise AssertionError(f"not a ModelFileError: {err!r}") from None
    if robot.inertia is not None:
        q = np.zeros(robot.n)
        assert np.isfinite(inverse_dynamics(robot, q, q + 0.1, q + 0.1)).all()
