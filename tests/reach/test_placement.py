"""Base placement: every base called feasible reaches every task pose, re-checked by forward
kinematics and by the numeric solver; the water-supply arm along its rail, by hand; the
margins; no feasible base is a result with its reason."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.reach import base_placement, floor_grid, rail_grid, reach_map
from armkit.spatial import invert, pose_from_xyz_rpy, rotz
from tests.reach.test_maps import water_supply_reaches

UR5 = armkit.robot("ur5")
WATER = armkit.robot("water_supply")


@pytest.fixture(scope="module")
def ur5_map():
    return reach_map(UR5, 0.1, 50, samples=400_000)


def grasps(count: int, seed: int) -> np.ndarray:
    """Grasp poses over a table in front of the world origin, gripper pointing down."""
    rng = np.random.default_rng(seed)
    return np.array([pose_from_xyz_rpy([0.6 + 0.1 * rng.standard_normal(),
                                        0.15 * rng.standard_normal(), 0.15],
                                       [math.pi, 0.0, rng.uniform(-1, 1)])
                     for _ in range(count)])


def test_a_found_base_reaches_every_pose_rechecked(ur5_map):
    task = grasps(10, seed=0)
    grid = floor_grid((-0.3, 0.3), (-0.3, 0.3), 0.1, yaw_step=math.radians(45))
    placement = base_placement(UR5, task, grid, reach_map=ur5_map)
    assert placement.success and placement.reason == "ok"
    assert 0 < placement.feasible.sum() < len(grid)
    # The best base: its joint values put the tool on every pose (in the base frame), inside
    # the limits.
    local = invert(placement.T_world_base) @ task
    np.testing.assert_allclose(armkit.fk(UR5, placement.q), local, atol=1e-9)
    assert np.all((placement.q >= UR5.lower) & (placement.q <= UR5.upper))
    # Every feasible base, again with the numeric solver (no closed form), from random starts.
    solver = armkit.IKSolver(UR5)
    rows = np.flatnonzero(placement.feasible)
    T = (invert(grid.poses[rows])[:, None] @ task[None]).reshape(-1, 4, 4)
    assert solver.solve(T, method="lm").success.all()
    # A base ruled out: some pose has no closed-form solution within the limits from it.
    out = np.flatnonzero(~placement.feasible)
    T = invert(grid.poses[out])[:, None] @ task[None]
    sols = solver.solutions(T)
    assert not (sols.valid & sols.within_limits).any(axis=-1).all(axis=1).any()
    # The score is the worst pose's index; the best has the highest score.
    np.testing.assert_array_equal(placement.score[rows], placement.reachability[rows].min(1))
    assert placement.score[placement.best] == np.nanmax(placement.score)


def test_without_a_map_ik_decides_and_manipulability_scores():
    task = grasps(6, seed=1)
    grid = floor_grid((-0.2, 0.2), (-0.2, 0.2), 0.1, yaw_step=math.radians(90))
    placement = base_placement(UR5, task, grid)
    assert placement.criterion == "manipulability" and np.isnan(placement.reachability).all()
    rows = np.flatnonzero(placement.feasible)
    solver = armkit.IKSolver(UR5)
    for b in rows[:5]:
        sols = solver.solutions(invert(grid.poses[b]) @ task)
        usable = sols.valid & sols.within_limits
        best = [armkit.manipulability(UR5, q[u]).max() for q, u in zip(sols.q, usable)]
        assert placement.score[b] == pytest.approx(min(best), rel=1e-9)


def test_the_water_supply_arm_along_its_rail_is_exact_by_hand():
    # The arm stands beside the track; the train's inlet, 1.2 m along the track from the
    # rail's start and 0.9 m beside it, 0.8 m high, filler pointing along -y. Moving the base
    # along the rail moves the inlet in the base frame: reachable where it is inside the
    # annular sector and height band of test_maps.water_supply_reaches.
    task = pose_from_xyz_rpy([1.2, 0.9, 0.8], [0, 0, -math.pi / 2])[None]
    grid = rail_grid([0, 0, 0], [3, 0, 0], 0.01, yaw=math.pi / 2)
    placement = base_placement(WATER, task, grid)
    local = invert(grid.poses) @ task
    np.testing.assert_array_equal(placement.feasible, water_supply_reaches(local[:, :3, 3]))
    s = grid.axes["s"]
    assert 0.3 < s[placement.feasible].min() and s[placement.feasible].max() < 2.5
    # The margin: distance to the nearest base that fails, or to the rail's end.
    rows = np.flatnonzero(placement.feasible)
    bad = s[~placement.feasible]
    for b in rows[::7]:
        assert placement.margin[b] == pytest.approx(min(np.abs(bad - s[b]).min(),
                                                        min(s[b], 3 - s[b]) + 0.01))
    assert placement.score[placement.best] == np.nanmax(placement.score)
    assert placement.yaw_margin == 0.0          # one yaw on this rail


def test_a_wider_yaw_range_gives_a_yaw_margin():
    task = pose_from_xyz_rpy([1.2, 0.9, 0.8], [0, 0, -math.pi / 2])[None]
    grid = rail_grid([0, 0, 0], [3, 0, 0], 0.05, yaw=(0.0, math.pi), yaw_step=math.radians(5))
    placement = base_placement(WATER, task, grid)
    best = placement.best
    assert placement.success and 0 < placement.yaw_margin < math.pi
    yaws = grid.axes["yaw"]
    ok = placement.feasible.reshape(grid.shape)[best // len(yaws)]
    k = best % len(yaws)
    assert ok[k] and placement.yaw_margin == pytest.approx(
        np.abs(yaws[~ok] - yaws[k]).min())


def test_no_base_reaches_everything_is_a_result_with_its_reason(ur5_map):
    far = pose_from_xyz_rpy([5.0, 0.0, 0.3], [math.pi, 0, 0])
    task = np.concatenate([grasps(2, seed=2), far[None]])
    grid = floor_grid((-0.2, 0.2), (-0.2, 0.2), 0.2)
    placement = base_placement(UR5, task, grid, reach_map=ur5_map, names=("a", "b", "far"))
    assert not placement.success and placement.best is None and placement.q is None
    assert placement.reason == ("no base of the grid reaches every pose: pose 2 (far) is in no "
                                "voxel the map reaches, from any base")
    assert placement.to_dict()["feasible"] == 0
    apart = np.stack([pose_from_xyz_rpy([x, 0, 0.3], [math.pi, 0, 0]) for x in (-1.2, 1.2)])
    split = base_placement(UR5, apart, floor_grid((-0.6, 0.6), (0, 0), 0.2))
    assert "at most 1 of 2 from one" in split.reason


def test_grids_hold_the_poses_they_say():
    grid = floor_grid((0, 1), (-0.5, 0.5), 0.05, z=0.3)
    assert grid.shape == (21, 21, 36) and len(grid) == 21 * 21 * 36
    rows = grid.poses.reshape(grid.shape + (4, 4))
    np.testing.assert_allclose(rows[3, 5, 7, :3, 3], [0.25, -0.35, 0.3], atol=1e-12)
    np.testing.assert_allclose(rows[3, 5, 7, :3, :3], rotz(-math.pi + 7 * math.radians(10)))
    np.testing.assert_allclose(grid.yaws[:36], -math.pi + np.radians(10) * np.arange(36))
    rail = rail_grid([1, 1, 0], [1, 3, 0], 0.5, yaw=0.3)
    np.testing.assert_allclose(rail.positions, [[1, y, 0] for y in (1, 1.5, 2, 2.5, 3)])


@pytest.mark.parametrize("call, message", [
    (lambda: floor_grid((1, 0), (0, 1), 0.1), "x: expected a range low .. high, found 1 .. 0"),
    (lambda: floor_grid((0, 1), (0, 1), 0), "step: expected a positive length"),
    (lambda: floor_grid((0, 1), (0, 1), 1e-6), "expected at most 1,000,000"),
    (lambda: floor_grid((0, 1), (0, 1), 0.1, yaw_step=0), "yaw_step: expected above 0"),
    (lambda: rail_grid([0, 0], [1, 0, 0], 0.1), "start, end: expected 3 coordinates each"),
    (lambda: base_placement(UR5, np.eye(3), floor_grid((0, 0), (0, 0), 1)), "task: expected"),
    (lambda: base_placement(UR5, np.eye(4), "floor"), "grid: expected a BaseGrid"),
    (lambda: base_placement(UR5, np.eye(4), floor_grid((0, 0), (0, 0), 1),
                            criterion="reachability"), "criterion: expected 'manipulability'"),
    (lambda: base_placement(UR5, np.eye(4), floor_grid((0, 0), (0, 0), 1), criterion="x"),
     "criterion: expected one of reachability, manipulability"),
])
def test_bad_arguments_say_what_was_expected(call, message):
    with pytest.raises(InputError, match=message):
        call()


def test_a_map_of_another_robot_is_refused(ur5_map):
    with pytest.raises(InputError, match="reach_map: expected a map of puma560"):
        base_placement(armkit.robot("puma560"), np.eye(4), floor_grid((0, 0), (0, 0), 1),
                       reach_map=ur5_map)


ANY = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from(
    [0.0, -0.0, 1e-320, 5e-324, 1e308, -1e308, 0.05, 1.0])


@settings(max_examples=60)
@given(x=st.tuples(ANY, ANY), y=st.tuples(ANY, ANY), step=ANY, yaw_step=ANY, z=ANY)
def test_any_floor_numbers_give_a_grid_or_say_why(x, y, step, yaw_step, z):
    try:
        grid = floor_grid(x, y, step, z=z, yaw_step=yaw_step)
    except InputError as err:
        assert ": expected " in str(err)
        return
    assert 1 <= len(grid) <= 1_000_000 and np.isfinite(grid.poses).all()


@settings(max_examples=60)
@given(start=st.tuples(ANY, ANY, ANY), end=st.tuples(ANY, ANY, ANY), step=ANY, yaw=ANY)
def test_any_rail_numbers_give_a_grid_or_say_why(start, end, step, yaw):
    try:
        grid = rail_grid(start, end, step, yaw=yaw)
    except InputError as err:
        assert ": expected " in str(err)
        return
    assert 1 <= len(grid) <= 1_000_000 and np.isfinite(grid.poses).all()
