"""The end-to-end job (armkit.task): every outcome, checked independently of the job's own
checks: the motion densely re-verified, the drive's record read directly."""

from __future__ import annotations

import socket
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import armkit
from armkit.io.tasks import load_task
from armkit.planning import Box, CollisionChecker, Scene
from armkit.task import demo_task, run_task

EXAMPLES = Path(__file__).parents[1] / "examples" / "tasks"


@pytest.fixture(scope="module")
def demo_result():
    return run_task(demo_task())


def _port_free(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


def test_the_demo_reaches_its_target_around_the_post(demo_result):
    r = demo_result
    task = r.task
    assert r.success, r.reason
    assert r.position_error <= r.resolution
    # The post is in the way of the straight joint motion ...
    checker = CollisionChecker(task.robot, task.scene, resolution=1e-9)
    line = np.linspace(r.q_current, r.solutions[r.chosen], 400)
    assert (checker.clearance(line) <= 0).any()
    # ... and the planned motion is clear, by a check every 0.002 rad of joint motion.
    q = r.trajectory.sample_uniform(2).q
    steps = int(np.ceil(np.abs(np.diff(r.trajectory.evaluate(np.linspace(
        0, r.trajectory.duration, 20001)), axis=0)).sum(axis=0).max() / 0.002)) + 2
    dense = r.trajectory.evaluate(np.linspace(0, r.trajectory.duration, max(steps, 20001)))
    assert np.abs(np.diff(dense, axis=0)).max() <= 0.002
    assert checker.clearance(dense).min() > 0
    assert q.shape == (2, task.robot.n)


def test_the_waypoints_lie_on_the_motion_and_were_all_taken(demo_result):
    r = demo_result
    assert r.q.shape == (r.task.waypoints, r.task.robot.n)
    np.testing.assert_allclose(r.trajectory.evaluate(r.t), r.q, atol=1e-9)
    assert r.sent["last_accepted"] == r.task.waypoints - 1
    np.testing.assert_allclose(r.q[0], r.q_current, atol=1e-6)
    assert r.drive.startswith("simulated drive on 127.0.0.1:")
    assert _port_free(int(r.drive.rsplit(":", 1)[1]))          # stopped afterwards


def test_the_chosen_solution_is_the_nearest_collision_free_one(demo_result):
    r = demo_result
    free = np.flatnonzero(r.collision_free)
    d = np.linalg.norm(r.solutions - r.q_current, axis=1)
    assert r.chosen == free[np.argmin(d[free])]
    T = armkit.fk(r.task.robot, r.solutions[r.chosen])
    np.testing.assert_allclose(T[:3, 3], r.T_base_target[:3, 3], atol=1e-9)


def test_an_unreachable_target_sends_nothing():
    task = demo_task()
    far = task.T_camera_target.copy()
    far[:3, 3] += [5.0, 0, 0]
    result = run_task(replace(task, T_camera_target=far))
    assert not result.success and result.stopped_at == "ik"
    assert "out of reach" in result.reason
    assert result.sent is None and result.q is None


def test_no_path_within_the_budget_sends_nothing():
    result = run_task(replace(demo_task(), planner="rrt", max_iterations=2, seed=3))
    assert not result.success and result.stopped_at == "plan"
    assert "no collision-free path" in result.reason and "budget" in result.reason
    assert result.sent is None


def test_every_solution_in_collision_is_a_reason():
    task = demo_task()
    T = task.T_base_camera @ task.T_camera_target
    cage = Box([0.3, 0.3, 0.3], _at(T[:3, 3]), "cage")
    result = run_task(replace(task, scene=Scene((cage,))))
    assert not result.success and result.stopped_at == "ik"
    assert "no collision-free IK solution" in result.reason
    assert not result.collision_free.any()


def _at(p):
    T = np.eye(4)
    T[:3, 3] = p
    return T


def test_a_drive_fault_reports_the_last_accepted_waypoint():
    from armkit.drives import SimDrive
    from armkit.task import builtin_register_map

    task = demo_task()
    drive_map = builtin_register_map(task.robot)
    with SimDrive(drive_map, position=task.start) as sim:
        sim.inject("fault", at=4)
        result = run_task(replace(task, drive_host="127.0.0.1", drive_port=sim.port,
                                  drive_map=drive_map))
        taken = len(sim.taken)
    assert not result.success and result.stopped_at in ("send", "arrival")
    assert result.sent["last_accepted"] == taken - 1 == 3


def test_an_unreachable_drive_is_a_result():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]          # closed again: nothing listens there
    task = demo_task()
    from armkit.task import builtin_register_map
    result = run_task(replace(task, drive_host="127.0.0.1", drive_port=port,
                              drive_map=builtin_register_map(task.robot), drive_timeout=0.5))
    assert not result.success and result.stopped_at == "drive"
    assert "cannot connect" in result.reason


@pytest.mark.parametrize("name", ["modular_4dof", "inspection_6dof", "tool_changer_6dof"])
def test_each_example_obstacle_blocks_the_straight_motion(name):
    task = load_task(EXAMPLES / f"{name}.task.yaml")
    result = run_task(task)
    assert result.success, result.reason
    checker = CollisionChecker(task.robot, task.scene, resolution=1e-9)
    line = np.linspace(result.q_current, result.solutions[result.chosen], 400)
    assert (checker.clearance(line) <= 0).any()
    dense = result.trajectory.evaluate(np.linspace(0, result.trajectory.duration, 40001))
    assert checker.clearance(dense).min() > 0


def test_a_target_found_in_a_point_cloud():
    task = load_task(EXAMPLES / "water_supply_lidar.task.yaml")
    result = run_task(task)
    assert result.success, result.reason
    assert result.detection.success
    np.testing.assert_allclose(result.T_base_target, result.detection.T_base_target)
    # The tool reaches the inlet's centre (position task) within the drive's resolution.
    p = armkit.fk(task.robot, result.q_final)[:3, 3]
    assert np.linalg.norm(p - result.T_base_target[:3, 3]) <= result.resolution


def test_a_cloud_without_an_inlet_is_a_reason(tmp_path):
    flat = tmp_path / "wall.npy"
    rng = np.random.default_rng(0)
    xy = rng.uniform(-0.5, 0.5, (20_000, 2))
    np.save(flat, np.c_[xy[:, 0], np.full(len(xy), 1.2), xy[:, 1]])
    task = replace(load_task(EXAMPLES / "water_supply_lidar.task.yaml"),
                   target_cloud={"path": flat, "kind": "pipe", "radius": None, "units": "m"})
    result = run_task(task)
    assert not result.success and result.stopped_at == "target"
    assert result.reason.startswith("no target in the cloud: ") and result.sent is None
