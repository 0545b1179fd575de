"""Spheres from meshes: every vertex of the real collision meshes of example-robot-data lies in a
sphere; on shapes with known surfaces (trimesh's primitives), no sphere reaches far past the
surface; a URDF whose links are meshes plans out of the box, and the spheres found can be kept
in a robot file; bad meshes are one error."""

from __future__ import annotations

import dataclasses
import glob
import os

import numpy as np
import pytest
import trimesh

import armkit
from armkit.errors import InputError, ModelFileError
from armkit.model.collision import CollisionShape, CollisionSpec
from armkit.planning import CollisionChecker, Scene, arm_geometry, plan
from armkit.planning.spheres import spheres_from_mesh
from tests.model.test_real_urdfs import robot_file
from tests.model.urdf_collision_files import ARM, TIP

MESHES = sorted(
    glob.glob(os.path.join(os.path.dirname(robot_file("panda_description/srdf/panda.srdf")),
                           "..", "meshes", "collision", "*.stl"))
    + glob.glob(os.path.join(os.path.dirname(robot_file("ur_description/srdf/ur5.srdf")),
                             "..", "meshes", "ur5", "collision", "*.stl")))


def outside(vertices, centres, radii):
    """How far each vertex lies outside every sphere (<= 0: inside one)."""
    return (np.linalg.norm(vertices[:, None] - centres[None], axis=2) - radii).min(axis=1)


@pytest.mark.parametrize("path", MESHES, ids=os.path.basename)
def test_spheres_contain_every_vertex_of_the_real_meshes(path):
    mesh = trimesh.load(path, force="mesh")
    centres, radii = spheres_from_mesh(mesh.vertices, mesh.faces, 0.02)
    assert outside(mesh.vertices, centres, radii).max() <= 0
    assert 1 <= len(radii) <= 40 and np.all(radii > 0)


@pytest.mark.parametrize("tolerance", [0.01, 0.02])
@pytest.mark.parametrize("shape", ["box", "cylinder", "icosphere"])
def test_spheres_hug_a_known_surface(shape, tolerance):
    """Points sampled on every sphere's surface lie within the tolerance and half a voxel of
    the solid (its signed distance from the exact shape), and the surface is covered."""
    mesh = {"box": lambda: trimesh.creation.box([0.3, 0.1, 0.05]),
            "cylinder": lambda: trimesh.creation.cylinder(0.04, 0.3),
            "icosphere": lambda: trimesh.creation.icosphere(3, 0.08)}[shape]()
    centres, radii = spheres_from_mesh(mesh.vertices, mesh.faces, tolerance)
    assert outside(mesh.vertices, centres, radii).max() <= 0
    surface = trimesh.sample.sample_surface_even(mesh, 2000, seed=0)[0]
    assert outside(surface, centres, radii).max() <= 0.25 * tolerance
    d = np.random.default_rng(0).normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    P = (centres[:, None] + radii[:, None, None] * d[None]).reshape(-1, 3)
    if shape == "box":
        excess = np.linalg.norm(np.maximum(np.abs(P) - [0.15, 0.05, 0.025], 0), axis=1)
    elif shape == "cylinder":
        excess = np.hypot(np.maximum(np.hypot(P[:, 0], P[:, 1]) - 0.04, 0),
                          np.maximum(np.abs(P[:, 2]) - 0.15, 0))
    else:
        excess = np.maximum(np.linalg.norm(P, axis=1) - 0.08, 0)
    assert excess.max() <= 1.5 * tolerance


def test_small_meshes_and_bad_input():
    tiny = trimesh.creation.box([0.001, 0.001, 0.001])
    centres, radii = spheres_from_mesh(tiny.vertices, tiny.faces, 0.02)
    assert len(radii) == 1 and outside(tiny.vertices, centres, radii).max() <= 0
    for vertices, faces, tolerance, match in (
            (np.empty((0, 3)), np.empty((0, 3), int), 0.01, "mesh: expected finite vertices"),
            ([[0, 0, np.nan]], [[0, 0, 0]], 0.01, "mesh: expected finite vertices"),
            (tiny.vertices, [[0, 1, 99]], 0.01, "mesh faces: expected vertex indices 0 .. 7"),
            (tiny.vertices, tiny.faces, 0.0, "tolerance: expected a positive length"),
            (tiny.vertices, tiny.faces, float("inf"), "tolerance")):
        with pytest.raises(InputError, match=match):
            spheres_from_mesh(vertices, faces, tolerance)


def arm_with_meshes(tmp_path):
    """The hand-written arm whose l1 cylinder and l2 sphere are STL meshes of the same
    shapes."""
    (tmp_path / "meshes" / "urdf").mkdir(parents=True)
    trimesh.creation.cylinder(0.05, 0.4).export(tmp_path / "meshes" / "urdf" / "l1.stl")
    trimesh.creation.icosphere(2, 0.03).export(tmp_path / "meshes" / "l2.stl")
    text = ARM.replace('<cylinder radius="0.05" length="0.4"/>', '<mesh filename="l1.stl"/>')
    text = text.replace('<sphere radius="0.03"/>',
                        '<mesh filename="package://meshes/l2.stl" scale="1 1 1"/>')
    (tmp_path / "meshes" / "urdf" / "arm.urdf").write_text(text)
    return tmp_path / "meshes" / "urdf" / "arm.urdf"


def test_a_urdf_of_meshes_plans_and_keeps_its_spheres(tmp_path):
    path = arm_with_meshes(tmp_path)
    robot = armkit.load_robot(path, tip=TIP)
    mesh = [c for c in robot.table.collisions if c.kind == "mesh"]
    assert len(mesh) == 2 and all(c.vertices is not None for c in mesh)
    geometry = arm_geometry(robot)
    assert geometry.source == "URDF collision primitives and meshes as spheres"
    on_l1 = geometry.link[[label.startswith("URDF l1[0] mesh sphere") for label in
                           geometry.labels]]
    assert len(on_l1) >= 2 and set(on_l1) == {1}
    assert set(geometry.names) == {"base", "l1", "sensor", "l2", "tool"}
    # Every vertex of l1's cylinder, placed by its collision origin, lies in its spheres.
    c = next(c for c in mesh if c.link == "l1")
    V = c.vertices @ c.T[:3, :3].T + c.T[:3, 3]
    k = np.array([label.startswith("URDF l1[0]") for label in geometry.labels])
    assert outside(V, geometry.a[k], geometry.radius[k]).max() <= 0
    checker = CollisionChecker(robot, Scene())
    result = plan(checker, [0.2, 0.3], [2.0, -1.0], time_limit=30)
    assert result.success, result.reason
    # The spheres found kept in a robot file: read back, the same parts, no mesh read.
    kept = dataclasses.replace(robot, collision=CollisionSpec(shapes=tuple(
        CollisionShape(int(k), a, b, float(r), name) for k, a, b, r, name in
        zip(geometry.link, geometry.a, geometry.b, geometry.radius, geometry.names))))
    saved = tmp_path / "kept.yaml"
    armkit.save_robot(kept, saved)
    again = arm_geometry(armkit.robot(str(saved)))
    assert again.source == "robot file" and again.names == geometry.names
    np.testing.assert_allclose(again.a, geometry.a, atol=1e-12)
    np.testing.assert_allclose(again.radius, geometry.radius, atol=1e-12)


def test_bad_mesh_files(tmp_path):
    path = arm_with_meshes(tmp_path)
    for scale, found in (('"0 1 1"', "'0 1 1'"), ('"1 1"', "'1 1'"), ('"x y z"', "'x y z'")):
        text = path.read_text().replace('scale="1 1 1"', f"scale={scale}")
        bad = path.parent / "bad.urdf"
        bad.write_text(text)
        with pytest.raises(ModelFileError, match=rf"link 'l2' <collision>\[0\] <mesh> scale: "
                                                 rf"expected .*, found {found}"):
            armkit.load_robot(bad, tip=TIP)
    (path.parent / "l1.stl").write_bytes(b"solid x\nfacet normal nan\n")
    with pytest.raises(ModelFileError, match=r"link 'l1' <collision>\[0\] <mesh> filename"):
        armkit.load_robot(path, tip=TIP)
