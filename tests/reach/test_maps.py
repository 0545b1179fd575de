"""Reachability maps against independent references: brute-force IK per voxel, the numeric
solver against the closed forms, the water-supply arm's map derived by hand, sampled forward
kinematics, and the Monte Carlo workspace."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.reach import Orientations, reach_map
from armkit.reach.maps import dilated, manipulability_of, voxel_keys, voxel_targets
from tests.helpers import random_q

UR5 = armkit.robot("ur5")


@pytest.fixture(scope="module")
def ur5_map():
    return reach_map(UR5, 0.1, 50, samples=400_000)


def test_a_voxels_index_is_brute_force_ik_over_its_orientations(ur5_map):
    # Every closed-form solution of every (voxel, orientation), from the public IKSolver, one
    # voxel at a time; reached: some solution within the limits.
    m = ur5_map
    solver = armkit.IKSolver(UR5)
    rows = np.random.default_rng(1).choice(len(m.voxels), 40, replace=False)
    rows = np.union1d(rows, np.flatnonzero((m.count > 0) & (m.count < 50))[:20])
    R = m.orientations.rotations
    for v in rows:
        T = np.tile(np.eye(4), (len(R), 1, 1))
        T[:, :3, :3] = R
        T[:, :3, 3] = m.centers[v]
        sols = solver.solutions(T)
        usable = sols.valid & sols.within_limits
        reached = usable.any(axis=1)
        np.testing.assert_array_equal(m.reached_at(v), reached)
        assert m.count[v] == reached.sum() and m.index[v] == reached.mean()
        best = armkit.manipulability(UR5, sols.q[usable]).max() if usable.any() else 0.0
        assert m.manipulability[v] == pytest.approx(best, rel=1e-9, abs=1e-15)
    assert (m.count[rows] > 0).any() and (m.count[rows] == 0).any()


@pytest.mark.parametrize("name, orientations", [
    ("ur5", Orientations.sphere(24)),
    ("puma560", Orientations.sphere(24)),
    ("modular_4dof", 12),
    ("water_supply", 8)])
@pytest.mark.slow
def test_closed_form_and_numeric_maps_agree(name, orientations):
    robot = armkit.robot(name)
    closed = reach_map(robot, 0.25, orientations, samples=200_000)
    numeric = reach_map(robot, 0.25, orientations, samples=200_000, method="lm", restarts=40)
    assert closed.settings["method"] == "analytic" and numeric.settings["method"] == "lm"
    np.testing.assert_array_equal(closed.voxels, numeric.voxels)
    assert closed.count.sum() > 0
    # The numeric solver finds one solution where the closed form finds all: what it reaches
    # the closed form reaches, and its manipulability is at most the best (to the 1e-9
    # tolerance of the solutions).
    bits = lambda m: np.array([m.reached_at(v) for v in range(len(m.voxels))])  # noqa: E731
    numeric_bits, closed_bits = bits(numeric), bits(closed)
    assert not (numeric_bits & ~closed_bits).any()
    assert np.all(numeric.manipulability <= closed.manipulability * (1 + 1e-6) + 1e-12)
    # A map's numeric solves have few restarts (a lower bound): the few problems they miss,
    # IK with its full budget of restarts solves.
    missed = np.argwhere(closed_bits & ~numeric_bits)
    assert len(missed) <= 0.002 * closed_bits.sum()
    if len(missed):
        R = closed.orientations.in_base(closed.centers[missed[:, 0]], robot)
        T = np.tile(np.eye(4), (len(missed), 1, 1))
        T[:, :3, :3] = R[np.arange(len(missed)), missed[:, 1]]
        T[:, :3, 3] = closed.centers[missed[:, 0]]
        assert armkit.IKSolver(robot).solve(T, method="lm", restarts=1000).success.all()


def water_supply_reaches(p: np.ndarray) -> np.ndarray:
    """By hand, for the water-supply arm (mm of SPEC.md, limits of the built-in file): the
    lift keeps the tool 525.5 .. 1125.5 mm high; swing 1's axis stands 214 mm along x; links of
    760 and 352.5 mm with the elbow within 150 deg put the tool between rho_min and 1112.5 mm
    from that axis, at an azimuth swing 1 (within 120 deg) turns to, give or take the angle
    the elbow adds; swing 3 turns a full turn, so every yaw is reached wherever the position
    is. Points p (..., 3) in m."""
    a, b = 0.760, 0.3525
    x, y, z = p[..., 0] - 0.214, p[..., 1], p[..., 2]
    rho = np.hypot(x, y)
    cos_elbow = (rho**2 - a**2 - b**2) / (2 * a * b)
    elbow = np.arccos(np.clip(cos_elbow, -1, 1))
    turn = np.arctan2(b * np.sin(elbow), a + b * np.cos(elbow))    # the elbow's share
    phi = np.arctan2(y, x)
    wrap = lambda t: (t + np.pi) % (2 * np.pi) - np.pi            # noqa: E731
    swing = np.radians(120)
    azimuth = (np.abs(wrap(phi - turn)) <= swing) | (np.abs(wrap(phi + turn)) <= swing)
    return ((z >= 0.5255) & (z <= 1.1255) & (cos_elbow >= math.cos(np.radians(150)))
            & (cos_elbow <= 1.0) & azimuth)


def test_the_water_supply_map_is_exact_by_hand():
    arm = armkit.robot("water_supply")
    m = reach_map(arm, 0.1, 12)
    assert m.orientations.task == "position+yaw" and len(m.orientations) == 12
    inside = water_supply_reaches(m.centers)
    # Every yaw at every position inside, none outside.
    np.testing.assert_array_equal(m.index, np.where(inside, 1.0, 0.0))
    assert m.count.sum() == 12 * inside.sum() and inside.sum() > 500
    # And the map covers every voxel whose centre the arm reaches: its grid's cells, over the
    # box of the reachable region, reachable by hand, are all in it.
    h = 0.1
    grid = np.stack(np.meshgrid(np.arange(-14, 14), np.arange(-14, 14), np.arange(4, 12),
                                indexing="ij"), -1).reshape(-1, 3)
    wanted = grid[water_supply_reaches((grid + 0.5) * h)]
    assert np.isin(voxel_keys(wanted), voxel_keys(m.voxels)).all()


def test_sampled_fk_finds_no_pose_the_map_calls_unreachable(ur5_map):
    # Random configurations inside the limits: each tool pose's voxel is in the map; from the
    # configuration, the numeric solver (no closed form, no restarts) moves the tool to the
    # voxel's centre in the orientation of the set nearest the pose; wherever it gets there
    # inside the limits, the map must say that orientation is reached.
    m = ur5_map
    q = random_q(UR5, 2000, seed=5)
    T = armkit.fk(UR5, q)
    row = m.find(T[:, :3, 3])
    assert (row >= 0).all()
    k = m.orientations.nearest(T[:, :3, :3], m.centers[row], UR5)
    target = np.tile(np.eye(4), (len(q), 1, 1))
    target[:, :3, :3] = m.orientations.rotations[k]
    target[:, :3, 3] = m.centers[row]
    moved = armkit.IKSolver(UR5).solve(target, q, method="lm", restarts=0, seeds=False,
                                       max_iter=50)
    index, reached = m.lookup(target)
    assert moved.success.sum() > 500
    assert reached[moved.success].all()
    assert (index[moved.success] > 0).all()


def test_the_map_holds_the_monte_carlo_workspace(ur5_map):
    # Positions sampled with another seed: every one falls in a voxel of the map, and every
    # voxel deep inside the sampled workspace (all 26 neighbours sampled too) reaches some
    # orientation.
    m = ur5_map
    ws = armkit.workspace(UR5, 400_000, resolution=m.resolution, seed=11, cloud=20_000)
    assert (m.find(ws.cloud) >= 0).all()
    assert np.isin(voxel_keys(ws.voxels), voxel_keys(m.voxels)).all()
    keys = voxel_keys(ws.voxels)
    steps = dilated(np.zeros((1, 3), np.int64))
    deep = np.isin(voxel_keys(ws.voxels[:, None] + steps), keys).all(axis=1)
    assert deep.sum() > 300
    assert (m.index_at((ws.voxels[deep] + 0.5) * m.resolution) > 0).all()


@pytest.mark.parametrize("name", ["ur5", "water_supply", "modular_4dof", "panda",
                                  "tool_changer_6dof"])
def test_compiled_manipulability_is_armkits(name):
    robot = armkit.robot(name)
    q = random_q(robot, 500, seed=2)
    q[0] = 0.0                              # singular for most arms
    np.testing.assert_allclose(manipulability_of(robot, q), armkit.manipulability(robot, q),
                               rtol=1e-9, atol=1e-13)


def test_targets_are_voxel_centres_in_every_orientation(ur5_map):
    m = ur5_map
    T = voxel_targets(UR5, m.centers[14:21], m.orientations).reshape(7, 50, 4, 4)
    np.testing.assert_array_equal(T[:, :, :3, 3], np.repeat(m.centers[14:21, None], 50, 1))
    np.testing.assert_array_equal(T[3, :, :3, :3], m.orientations.rotations)
    np.testing.assert_array_equal(T[..., 3, :], np.broadcast_to([0, 0, 0, 1], (7, 50, 4)))


def test_sections_show_the_index():
    m = reach_map(armkit.robot("water_supply"), 0.1, 4)
    level = m.horizontal_section(0.8)
    i0, _, j0, _ = np.round(level.extent / 0.1).astype(int)
    rows, cols = np.nonzero(np.isfinite(level.index))
    centers = np.column_stack([(cols + i0 + 0.5) * 0.1, (rows + j0 + 0.5) * 0.1,
                               np.full(len(rows), 0.85)])
    np.testing.assert_array_equal(level.index[rows, cols], water_supply_reaches(centers))
    upright = m.vertical_section(0.0)
    assert np.nanmax(upright.index) == 1.0 and upright.extent[2] < 0.55 < upright.extent[3]
    assert np.isnan(m.horizontal_section(5.0).index).all()


@pytest.mark.parametrize("kwargs, message", [
    (dict(resolution=-1), "resolution: expected a positive voxel edge (m), found -1"),
    (dict(resolution=1e-4), "resolution: expected at least"),
    (dict(resolution=float("nan")), "resolution: expected a finite number"),
    (dict(orientations=0), "orientations: expected 1 .. 100000, found 0"),
    (dict(orientations=2.5), "orientations: expected a whole number"),
    (dict(method="ikfast"), "method: expected one of auto, analytic, lm, newton"),
    (dict(restarts=-1), "restarts: expected 0 .. 10000, found -1"),
    (dict(chunk=0), "chunk: expected 1 .. 10000000, found 0"),
    (dict(scene="shelf"), "scene: expected an armkit.planning.Scene, found str"),
    (dict(scheduler="tcp://"), "scheduler: expected an address"),
])
def test_bad_arguments_say_what_was_expected(kwargs, message):
    args = dict(resolution=0.3, orientations=4, samples=1000) | kwargs
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        reach_map(UR5, **args)


def test_analytic_needs_a_closed_form():
    with pytest.raises(InputError, match="method: expected 'auto', 'lm' or 'newton' for panda"):
        reach_map(armkit.robot("panda"), 0.3, 4, method="analytic", samples=1000)
    with pytest.raises(InputError, match="robot: expected a Robot"):
        reach_map("ur5", 0.3, 4)


def test_with_a_scene_only_collision_free_solutions_count():
    from armkit.planning import Box, CollisionChecker, Scene

    table = Scene([Box.from_bounds([0.25, -0.4, -0.2], [0.7, 0.4, 0.05], "table")])
    orientations = Orientations.sphere(16)
    free = reach_map(UR5, 0.15, orientations, samples=200_000)
    blocked = reach_map(UR5, 0.15, orientations, samples=200_000, scene=table)
    assert blocked.settings["obstacles"] == 1 and free.settings["obstacles"] is None
    assert np.all(blocked.count <= free.count) and blocked.count.sum() < free.count.sum()
    # Voxel by voxel, brute force: every closed-form solution within the limits, then the
    # checker; a voxel inside the table reaches nothing.
    checker = CollisionChecker(UR5, table)
    solver = armkit.IKSolver(UR5)
    changed = np.flatnonzero(blocked.count < free.count)
    rows = np.union1d(changed[::max(1, len(changed) // 25)], np.arange(0, len(free.voxels), 97))
    for v in rows:
        T = np.tile(np.eye(4), (len(orientations), 1, 1))
        T[:, :3, :3] = orientations.rotations
        T[:, :3, 3] = blocked.centers[v]
        sols = solver.solutions(T)
        usable = sols.valid & sols.within_limits
        ok = np.zeros_like(usable)
        ok[usable] = checker.valid(sols.q[usable])
        np.testing.assert_array_equal(blocked.reached_at(v), ok.any(axis=1))
    inside = np.all((blocked.centers > [0.25, -0.4, -0.2]) & (blocked.centers < [0.7, 0.4, 0.05]),
                    axis=1)
    assert inside.any() and (blocked.count[inside] == 0).all()
