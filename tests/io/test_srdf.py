"""SRDF files: the published UR5 and Panda SRDFs read pair by pair (the pairs parsed again here
with the standard library as the reference), groups and end effectors, writing and reading back,
robots and robot files that name an SRDF, and hostile files: one ModelFileError each, never
another exception."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import armkit
from armkit.errors import ModelFileError
from armkit.io.srdf import read_srdf, write_srdf
from armkit.planning import CollisionModel, arm_geometry
from tests.model.test_real_urdfs import robot_file

UR5 = ("ur_description/urdf/ur5_robot.urdf", "ur_description/srdf/ur5.srdf", "ee_link")
PANDA = ("panda_description/urdf/panda.urdf", "panda_description/srdf/panda.srdf", "panda_hand")


def published_pairs(path):
    root = ET.parse(path).getroot()
    return [(e.get("link1"), e.get("link2"), e.get("reason", ""))
            for e in root.iter("disable_collisions")]


@pytest.mark.parametrize("arm, count", [(UR5, 10), (PANDA, 35)])
def test_published_srdf_pairs_by_name(arm, count):
    path = robot_file(arm[1])
    srdf = read_srdf(path)
    assert list(srdf.disabled) == published_pairs(path)
    assert len(srdf.disabled) == count
    assert ("wrist_1_link", "wrist_3_link") in srdf.disabled_pairs or arm is PANDA


def test_ur5_pairs_and_panda_groups_by_hand():
    ur5 = read_srdf(robot_file(UR5[1]))
    assert ur5.robot == "ur5"
    assert ur5.disabled[0] == ("base_link", "shoulder_link", "")
    assert ("forearm_link", "wrist_3_link") in ur5.disabled_pairs
    panda = read_srdf(robot_file(PANDA[1]))
    assert ("panda_hand", "panda_link3", "Never") in panda.disabled
    assert ("panda_link0", "panda_link1", "Adjacent") in panda.disabled
    assert panda.groups["arm"].joints == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert panda.groups["arm_and_hand"].groups == ("arm", "hand")
    assert panda.end_effectors == (("end_effector", "panda_hand_tcp", "arm"),)
    assert panda.tip("arm") is None                     # joints, no chain


def test_chains_give_a_tip(tmp_path):
    path = tmp_path / "chain.srdf"
    path.write_text('<robot name="r"><group name="arm"><chain base_link="base" tip_link="tool"/>'
                    '</group><group name="all"><group name="arm"/></group></robot>')
    srdf = read_srdf(path)
    assert srdf.tip("arm") == "tool" and srdf.tip("all") == "tool" and srdf.tip("x") is None


def test_write_and_read_back(tmp_path):
    pairs = [("a", "b", "Never"), ("c&d", 'e"f', "Adjacent")]
    path = tmp_path / "out.srdf"
    write_srdf(path, "my <robot>", pairs)
    srdf = read_srdf(path)
    assert srdf.robot == "my <robot>" and list(srdf.disabled) == pairs


@pytest.mark.parametrize("arm", [UR5, PANDA])
def test_a_robot_with_its_srdf_tests_every_pair_it_does_not_disable(arm):
    """MoveIt's rule: with an SRDF, every pair of links on different arm links that it does not
    disable is tested, adjacent or not; without it, armkit's (no adjacent links)."""
    urdf, srdf_path, tip = robot_file(arm[0]), robot_file(arm[1]), arm[2]
    robot = armkit.load_robot(urdf, tip=tip, srdf=srdf_path)
    geometry = arm_geometry(robot)
    assert geometry.adjacent
    off = {tuple(sorted(p)) for p in read_srdf(srdf_path).disabled_pairs}
    names, links = np.array(geometry.names), geometry.link
    tested = {tuple(sorted((names[i], names[j]))) for i, j in geometry.self_pairs()}
    expected = {tuple(sorted((a, b))) for a in set(names) for b in set(names)
                if a != b and links[names == a][0] != links[names == b][0]} - off
    assert tested == expected
    model = CollisionModel(robot, geometry)
    assert model.part_pairs == len(geometry.self_pairs())
    plain = arm_geometry(armkit.load_robot(urdf, tip=tip))
    assert not plain.adjacent and not plain.disabled


def test_robot_file_names_its_srdf_and_skips_by_name(tmp_path):
    urdf, srdf_path, tip = robot_file(UR5[0]), robot_file(UR5[1]), UR5[2]
    path = tmp_path / "ur5.yaml"
    path.write_text(f"name: ur5\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                    f"urdf: {urdf}\ntip: {tip}\nsrdf: {srdf_path}\n"
                    f"collision:\n  skip: [[wrist_2_link, ee_link], [0, 2]]\n")
    robot = armkit.robot(str(path))
    assert robot.collision.adjacent
    assert ("wrist_2_link", "ee_link") in robot.collision.disabled
    assert ("base_link", "shoulder_link") in robot.collision.disabled
    assert robot.collision.skip == ((0, 2),)
    saved = tmp_path / "saved.yaml"
    armkit.save_robot(robot, saved)
    again = armkit.robot(str(saved))
    assert set(again.collision.disabled) == set(robot.collision.disabled)
    assert again.collision.adjacent and again.collision.skip == ((0, 2),)


@pytest.mark.parametrize("text, field, found", [
    ("srdf: nowhere.srdf\n", "srdf", "'nowhere.srdf', which is not a file"),
    ("collision:\n  skip: [[wrist_2_link, no_such_link]]\n", "collision.skip[0]",
     "'no_such_link'"),
    ("collision:\n  shapes:\n    - {link: no_such_link, a: [0, 0, 0], radius: 5}\n",
     "collision.shapes[0].link", "'no_such_link'"),
])
def test_robot_file_bad_names(tmp_path, text, field, found):
    urdf, tip = robot_file(UR5[0]), UR5[2]
    path = tmp_path / "ur5.yaml"
    path.write_text(f"name: ur5\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                    f"urdf: {urdf}\ntip: {tip}\n" + text)
    with pytest.raises(ModelFileError) as err:
        armkit.robot(str(path))
    assert err.value.field == field and found in str(err.value)


@pytest.mark.parametrize("text, field, expected", [
    ("not xml", "", "a readable SRDF (XML) file"),
    ("<robot><disable_collisions link1='a'/></robot>", "<disable_collisions>[0] link2",
     "a name"),
    ("<robot><disable_collisions link1='' link2='b'/></robot>",
     "<disable_collisions>[0] link1", "a name"),
    ("<urdf/>", "", "a <robot> root element"),
    ("<!DOCTYPE r [<!ENTITY a 'b'>]><robot/>", "", "without entity declarations"),
    ("<robot><group><joint name='j'/></group></robot>", "<group>[0] name", "a name"),
    ("<robot><group name='g'><chain base_link='a'/></group></robot>",
     "group g <chain> tip_link", "a name"),
])
def test_bad_srdf_one_error(tmp_path, text, field, expected):
    path = tmp_path / "bad.srdf"
    path.write_text(text)
    with pytest.raises(ModelFileError) as err:
        read_srdf(path)
    assert err.value.field == field and expected in err.value.expected


def test_pairs_must_name_links_of_the_urdf(tmp_path):
    path = tmp_path / "typo.srdf"
    path.write_text("<robot><disable_collisions link1='base_link' link2='wrist_9'/></robot>")
    with pytest.raises(ModelFileError, match="link2: expected a link of the URDF, found "
                                             "'wrist_9'"):
        armkit.load_robot(robot_file(UR5[0]), tip=UR5[2], srdf=path)
    with pytest.raises(armkit.InputError, match="srdf: expected none for a robot file"):
        armkit.load_robot(tmp_path / "x.yaml", srdf=path)


@given(st.binary(max_size=300) | st.text(max_size=300).map(lambda s: s.encode()))
def test_fuzz_srdf_bytes(data):
    """Any bytes: read, or one ModelFileError."""
    import tempfile

    with tempfile.NamedTemporaryFile(suffix=".srdf") as f:
        f.write(data)
        f.flush()
        try:
            read_srdf(f.name)
        except ModelFileError:
            pass


@pytest.mark.slow
@given(st.data())
def test_fuzz_mutated_published_srdf(data):
    """The Panda's SRDF with characters cut, repeated or replaced: read, or one
    ModelFileError naming the file."""
    import tempfile

    text = open(robot_file(PANDA[1]), encoding="utf-8").read()
    for _ in range(data.draw(st.integers(1, 6))):
        i = data.draw(st.integers(0, len(text) - 1))
        cut = data.draw(st.integers(0, 20))
        text = text[:i] + data.draw(st.sampled_from(["", "<", ">", "'", '"', "=", " ", "x"])) \
            + text[i + cut:]
    with tempfile.NamedTemporaryFile(suffix=".srdf", mode="w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        try:
            read_srdf(f.name)
        except ModelFileError as err:
            assert err.file == f.name
