"""Arm geometry from a URDF's <collision> primitives: exact capsules for a hand-written file,
precedence, meshes, `armkit show`, a fuzz of mutated collision elements, and containment: points
inside every URDF primitive, placed by Pinocchio (an independent reference), lie inside the
arm's capsules at random configurations, for the hand-written file and real URDFs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import armkit
from armkit.errors import ArmkitError, ModelFileError
from armkit.planning import CollisionChecker, Scene, arm_geometry
from armkit.planning.collision import arm_capsules
from armkit.planning.geometry import primitive_capsule
from tests.model.test_real_urdfs import robot_file
from tests.model.urdf_collision_files import ARM, TIP

H = np.hypot(0.05, 0.01)                   # the sensor box's capsule: half its 0.1 x 0.02 diagonal


@pytest.fixture
def arm_file(tmp_path):
    path = tmp_path / "hand.urdf"
    path.write_text(ARM)
    return path


def capsules_by_label(geometry):
    return {label: (int(k), a, b, float(r)) for label, k, a, b, r in
            zip(geometry.labels, geometry.link, geometry.a, geometry.b, geometry.radius)}


def assert_capsules(geometry, expected):
    found = capsules_by_label(geometry)
    assert sorted(found) == sorted(expected)
    for label, (k, a, b, r) in expected.items():
        assert found[label][0] == k, label
        np.testing.assert_allclose(found[label][1], a, atol=1e-15, err_msg=label)
        np.testing.assert_allclose(found[label][2], b, atol=1e-15, err_msg=label)
        assert found[label][3] == pytest.approx(r, abs=1e-15), label


def test_hand_written_urdf_capsules_by_hand(arm_file):
    g = arm_geometry(armkit.load_robot(arm_file, tip=TIP))
    assert g.source == "URDF collision primitives"
    assert_capsules(g, {
        "URDF base[0] sphere": (0, [0, 0, 0.05], [0, 0, 0.05], 0.1),
        # The cylinder along l1's x (turned by its origin's pitch): from 0 to 0.4 m.
        "URDF l1[0] cylinder": (1, [0, 0, 0], [0.4, 0, 0], 0.05),
        # The sensor's box, merged into l1 through the fixed joint (x 0.4 m, yaw 90 deg): its
        # longest edge (0.3 m along the sensor's y) lies along l1's x, from 0.45 back to 0.15.
        "URDF sensor[0] box": (1, [0.45, 0, 0], [0.15, 0, 0], H),
        # Link 2 is the tool frame, 0.15 m past l2 (the fixed tool joint).
        "URDF l2[0] sphere": (2, [-0.05, 0, 0], [-0.05, 0, 0], 0.03),
        "URDF tool[0] cylinder": (2, [0, 0, -0.03], [0, 0, 0.03], 0.02),
    })
    assert g.skip == ()                                 # only adjacent links: 0 and 2 are apart
    pairs = {(int(g.link[i]), int(g.link[j])) for i, j in g.self_pairs()}
    assert pairs == {(0, 2)}
    assert any("finger" in note for note in g.notes)    # off the chain: not part of the arm


def test_a_tool_offset_moves_the_last_links_capsules(arm_file, tmp_path):
    wrapper = tmp_path / "arm.yaml"
    wrapper.write_text(f"name: hand\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                       f"urdf: {arm_file.name}\ntip: {TIP}\ntool: {{xyz: [0, 0, 100]}}\n")
    g = arm_geometry(armkit.robot(str(wrapper)))
    found = capsules_by_label(g)
    np.testing.assert_allclose(found["URDF l2[0] sphere"][1], [-0.05, 0, -0.1], atol=1e-15)
    np.testing.assert_allclose(found["URDF tool[0] cylinder"][1], [0, 0, -0.13], atol=1e-15)
    np.testing.assert_allclose(found["URDF tool[0] cylinder"][2], [0, 0, -0.07], atol=1e-15)


def test_primitive_capsules_by_hand():
    a, b, r = primitive_capsule("box", [0.2, 0.6, 0.1])
    np.testing.assert_array_equal([a, b], [[0, -0.3, 0], [0, 0.3, 0]])
    assert r == pytest.approx(np.hypot(0.1, 0.05), abs=1e-16)
    a, b, r = primitive_capsule("cylinder", [0.05, 0.4])
    np.testing.assert_array_equal([a, b, [r, 0, 0]], [[0, 0, -0.2], [0, 0, 0.2], [0.05, 0, 0]])
    a, b, r = primitive_capsule("sphere", [0.07])
    assert np.array_equal(a, b) and not a.any() and r == 0.07


@pytest.mark.parametrize("section, source, radius", [
    ("collision:\n  shapes:\n    - {link: 1, a: [0, 0, 0], b: [400, 0, 0], radius: 60}\n",
     "robot file", [0.06]),
    ("collision:\n  radius: 30\n", "default: segments between joint origins", 0.03),
    ("collision:\n  skip: [[0, 2]]\n", "URDF collision primitives", None),
    ("", "URDF collision primitives", None),
])
def test_precedence(arm_file, tmp_path, section, source, radius):
    """The robot file's own collision section first, then the URDF's primitives, then the
    default capsules."""
    wrapper = tmp_path / "arm.yaml"
    wrapper.write_text(f"name: hand\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                       f"urdf: {arm_file.name}\ntip: {TIP}\n" + section)
    g = arm_geometry(armkit.robot(str(wrapper)))
    assert g.source == source
    if radius is not None:
        np.testing.assert_allclose(g.radius, np.broadcast_to(radius, g.radius.shape))
    if "skip" in section:
        assert g.skip == ((0, 2),) and len(g.self_pairs()) == 0
    assert arm_geometry(armkit.robot(str(wrapper)), radius=0.02).source.startswith("default")


def test_meshes(tmp_path):
    """A link with only a mesh gets its arm link's default capsule; a file with nothing but
    meshes gets the default geometry."""
    path = tmp_path / "mesh.urdf"
    path.write_text(ARM.replace('<cylinder radius="0.05" length="0.4"/>',
                                '<mesh filename="package://nowhere/l1.stl"/>'))
    g = arm_geometry(armkit.load_robot(path, tip=TIP))
    found = capsules_by_label(g)
    assert "URDF l1[0] cylinder" not in found and "URDF sensor[0] box" in found
    k, a, b, r = found["default: joint 1 to joint 2"]
    assert k == 1 and r == 0.04
    np.testing.assert_allclose([a, b], [[0, 0, 0], [0.5, 0, 0]], atol=1e-15)
    assert any("mesh collisions not read (links l1: its file 'package://nowhere/l1.stl' was "
               "not found)" in note for note in g.notes)
    only = tmp_path / "only.urdf"
    text = ARM
    for shape in ('<sphere radius="0.1"/>', '<cylinder radius="0.05" length="0.4"/>',
                  '<box size="0.1 0.3 0.02"/>', '<sphere radius="0.03"/>',
                  '<cylinder radius="0.02" length="0.06"/>'):
        text = text.replace(shape, '<mesh filename="x.stl"/>')
    only.write_text(text)
    assert arm_geometry(armkit.load_robot(only, tip=TIP)).source.startswith("default")


def test_show_lists_the_urdf_geometry(arm_file):
    run = subprocess.run([sys.executable, "-m", "armkit", "show", str(arm_file), "--json"],
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 2 and "tip" in run.stderr          # the tree has several tips
    wrapper = arm_file.parent / "arm.yaml"
    wrapper.write_text(f"name: hand\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                       f"urdf: {arm_file.name}\ntip: {TIP}\n")
    run = subprocess.run([sys.executable, "-m", "armkit", "show", str(wrapper), "--json"],
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)["collision"]
    assert doc["source"] == "URDF collision primitives"
    sensor = [c for c in doc["capsules"] if c["from"] == "URDF sensor[0] box"]
    assert len(sensor) == 1 and sensor[0]["link"] == 1
    np.testing.assert_allclose(sensor[0]["a"], [450, 0, 0], atol=1e-9)        # in mm
    np.testing.assert_allclose(sensor[0]["radius"], H * 1e3)
    assert any("finger" in note for note in doc["notes"])
    run = subprocess.run([sys.executable, "-m", "armkit", "show", str(wrapper)],
                         capture_output=True, text=True, timeout=120,
                         env={**os.environ, "COLUMNS": "200"}, check=False)
    assert run.returncode == 0, run.stderr
    assert "collision capsules in link frames (URDF collision primitives)" in run.stdout
    assert "URDF sensor[0] box" in run.stdout and "note: links moved by joints off" in run.stdout


# --- containment, with Pinocchio placing the URDF's primitives ---------------------------------

def inside_points(geometry, rng, count: int = 60) -> np.ndarray:
    """Points (k, 3) in a coal primitive's frame: its corners or rims and random inner ones."""
    kind = type(geometry).__name__
    if kind == "Box":
        h = np.asarray(geometry.halfSide)
        corners = np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T * h
        return np.vstack([corners, rng.uniform(-h, h, (count, 3))])
    if kind == "Cylinder":
        r, h = geometry.radius, geometry.halfLength
        phi = rng.uniform(0, 2 * np.pi, count)
        rim = np.column_stack([r * np.cos(phi), r * np.sin(phi), h * rng.choice([-1, 1], count)])
        rho = r * np.sqrt(rng.uniform(0, 1, count))
        inner = np.column_stack([rho * np.cos(phi), rho * np.sin(phi),
                                 rng.uniform(-h, h, count)])
        return np.vstack([rim, inner])
    assert kind == "Sphere", kind
    u = rng.normal(size=(count, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return np.vstack([geometry.radius * u, geometry.radius * rng.uniform(0, 1, (count, 1)) * u])


def segment_gap(p, a, b, r):
    """Distance from points p (k, 3) past the capsule a-b of radius r (negative inside)."""
    d = b - a
    dd = d @ d
    t = np.zeros(len(p)) if dd == 0 else np.clip((p - a) @ d / dd, 0, 1)
    return np.linalg.norm(p - a - t[:, None] * d, axis=1) - r


def assert_contained(path, robot, configurations: int = 8, seed: int = 0):
    """Every URDF primitive on the arm, placed by Pinocchio at random configurations, lies inside
    the capsules of the arm link it is merged into (to 1e-9 m)."""
    geometry = arm_geometry(robot)
    table = robot.table
    chain_link = {f"{c.link}_{c.index}": c.chain_link for c in table.collisions}
    model = pin.buildModelFromUrdf(path)
    share = path[:path.index("/robots/")] + "/.." if "/robots/" in path else "."
    collision = pin.buildGeomFromUrdf(model, path, pin.GeometryType.COLLISION,
                                      package_dirs=[share])
    data, gdata = model.createData(), collision.createData()
    rng = np.random.default_rng(seed)
    lo, hi = robot.sampling_limits
    checked = 0
    for q in rng.uniform(lo, hi, (configurations, robot.n)):
        values = dict(zip(robot.joint_names, q))
        for joint in robot.chain.joints:                  # a mimic joint follows its leader
            if joint.leader is not None:
                values[joint.name] = joint.multiplier * values[joint.leader] + joint.mimic_offset
        qp = pin.neutral(model)
        for name, value in values.items():
            jid = model.getJointId(name)
            i, nq = model.joints[jid].idx_q, model.joints[jid].nq
            qp[i:i + nq] = [np.cos(value), np.sin(value)] if nq == 2 else [value]
        pin.updateGeometryPlacements(model, data, collision, gdata, qp)
        a, b = arm_capsules(robot, geometry, q)
        for k, obj in enumerate(collision.geometryObjects):
            kind = type(obj.geometry).__name__
            if obj.name not in chain_link or kind not in ("Box", "Cylinder", "Sphere"):
                assert kind not in ("Box", "Cylinder", "Sphere") or any(
                    obj.name.startswith(f"{d}_") for d in table.detached), obj.name
                continue
            T = gdata.oMg[k].homogeneous
            p = inside_points(obj.geometry, rng) @ T[:3, :3].T + T[:3, 3]
            mine = np.flatnonzero(geometry.link == chain_link[obj.name])
            gap = np.min([segment_gap(p, a[c], b[c], geometry.radius[c]) for c in mine], axis=0)
            assert gap.max() <= 1e-9, (obj.name, q, gap.max())
            checked += 1
    return checked


def test_hand_written_primitives_are_contained(arm_file):
    robot = armkit.load_robot(arm_file, tip=TIP)
    assert assert_contained(str(arm_file), robot) == 8 * 5


@pytest.mark.parametrize("suffix, tip, primitives", [
    ("panda_description/urdf/panda_collision.urdf", "panda_hand", 33),
    ("z1_description/urdf/z1.urdf", "gripperMover", 8),
    # Through the right finger's mimic joint (its leader, the left finger's, off the chain).
    ("panda_description/urdf/panda_collision.urdf", "panda_rightfinger", 36),
])
@pytest.mark.slow
def test_real_urdf_primitives_are_contained(suffix, tip, primitives):
    path = robot_file(suffix)
    robot = armkit.load_robot(path, tip=tip)
    geometry = arm_geometry(robot)
    assert geometry.source.startswith("URDF collision primitives")
    assert sum(label.startswith("URDF ") and "mesh" not in label
               for label in geometry.labels) == primitives
    assert assert_contained(path, robot) == 8 * primitives


def test_real_urdf_geometry_plans():
    """The Panda's URDF capsules in the checker: its home pose is free, the geometry is usable."""
    robot = armkit.load_robot(robot_file("panda_description/urdf/panda_collision.urdf"),
                              tip="panda_hand")
    checker = CollisionChecker(robot, Scene(), resolution=0.005)
    assert checker.geometry.source == "URDF collision primitives"
    home = np.array([0, -0.785, 0, -2.356, 0, 1.571, 0.785])
    assert checker.valid(home)


# --- fuzz: mutated collision elements ----------------------------------------------------------

JUNK = ["", "nan", "inf", "-0.1", "0", "1e400", "2e3", "0.1 0.2", "abc", "0x10", "١", "1_0",
        " 0.3 ", "1e-3", "0.05", "0.1 0.2 0.3", "-0 0 0", "1e-300", "+.5", "5.", "0.1,0.2,0.3"]
ATTRIBUTES = ["radius", "length", "size", "xyz", "rpy", "filename"]
TAGS = ["box", "cylinder", "sphere", "mesh", "cone", "capsule", "Box", ""]


def mutate(rng) -> tuple[str, str]:
    """The hand-written URDF with one collision element changed, and the changed link's name."""
    root = ET.fromstring(ARM)
    elements = [(link.get("name"), c) for link in root.findall("link")
                for c in link.findall("collision")]
    name, c = elements[rng.integers(len(elements))]
    geometry = c.find("geometry")
    action = rng.integers(6)
    if action == 0:                                   # a value of the shape or the origin
        origin = c.find("origin")
        target = [geometry[0], origin if origin is not None else
                  ET.SubElement(c, "origin")][rng.integers(2)]
        target.set(str(rng.choice(ATTRIBUTES)), str(rng.choice(JUNK)))
    elif action == 1:                                 # an attribute removed
        shape = geometry[0]
        if shape.attrib:
            shape.attrib.pop(str(rng.choice(list(shape.attrib))))
    elif action == 2:                                 # the shape renamed
        tag = str(rng.choice(TAGS))
        geometry[0].tag = tag or "x"
    elif action == 3:                                 # no geometry, or an empty one
        c.remove(geometry)
        if rng.integers(2):
            ET.SubElement(c, "geometry")
    elif action == 4:                                 # two shapes
        ET.SubElement(geometry, str(rng.choice(TAGS[:4])), radius="0.1")
    else:                                             # several values at once
        for shape in list(geometry):
            for key in list(shape.attrib):
                shape.set(key, str(rng.choice(JUNK)))
    return ET.tostring(root, encoding="unicode"), name


def assert_holds_what_was_read(robot, geometry, rng):
    """Points inside each primitive the reader kept lie in its link's capsules (link frames)."""
    to_tool = np.linalg.inv(robot.chain.T_tool)
    for c in robot.table.collisions:
        if c.kind == "mesh":
            continue
        T = (to_tool if c.chain_link == robot.chain.n_joints else np.eye(4)) @ c.T
        r = c.size[0]
        half = {"box": c.size / 2, "cylinder": [r, r, c.size[-1] / 2], "sphere": [r, r, r]}[c.kind]
        local = rng.uniform(-1, 1, (200, 3)) * half
        if c.kind == "sphere":
            local = local[np.linalg.norm(local, axis=1) <= r]
        elif c.kind == "cylinder":
            local = local[np.hypot(local[:, 0], local[:, 1]) <= r]
        p = local @ T[:3, :3].T + T[:3, 3]
        mine = np.flatnonzero(geometry.link == c.chain_link)
        gap = np.min([segment_gap(p, geometry.a[k], geometry.b[k], geometry.radius[k])
                      for k in mine], axis=0)
        assert gap.max() <= 1e-9, (c.link, c.kind, gap.max())


def test_fuzz_of_collision_elements(tmp_path):
    """Every mutation is refused with one line naming the file, the link's <collision> element
    and what was expected, or loads a geometry that is finite and holds every primitive read."""
    rng = np.random.default_rng(0)
    path = tmp_path / "fuzz.urdf"
    refused = loaded = 0
    for _ in range(300):
        text, name = mutate(rng)
        path.write_text(text)
        try:
            robot = armkit.load_robot(path, tip=TIP)
        except ModelFileError as err:
            message = str(err)
            assert "\n" not in message and message.startswith(f"{path}: "), message
            assert f"link '{name}' <collision>[0]" in err.field, message
            assert "expected " in message and ", found " in message, message
            refused += 1
            continue
        except ArmkitError as err:                    # pragma: no cover - a defect
            raise AssertionError(f"{type(err).__name__} instead of ModelFileError: {err}")
        geometry = arm_geometry(robot)
        assert np.isfinite(geometry.a).all() and np.isfinite(geometry.b).all()
        assert (geometry.radius > 0).all() and geometry.radius.max() <= 1e3
        assert len(geometry.labels) == len(geometry)
        if geometry.source == "URDF collision primitives":
            assert_holds_what_was_read(robot, geometry, rng)
        loaded += 1
    assert refused > 100 and loaded > 20, (refused, loaded)
