"""The end-to-end job (armkit.job): every outcome, checked independently of the job's own
checks: the motion densely re-verified, the drive's record read directly, drives that fail or
lie met through a proxy on loopback."""

from __future__ import annotations

import re
import socket
from dataclasses import replace

import numpy as np
import pytest

import armkit
from armkit.drives import SimDrive
from armkit.io.clouds import Cloud
from armkit.io.tasks import demo_task, load_task
from armkit.job import run_job
from armkit.job.steps import Motion, check_motion, motion_limits
from armkit.planning import Box, CollisionChecker, Scene
from armkit.trajectory import retime
from tests.drives.proxy import FaultProxy, get_register, registers, set_register
from tests.job import EXAMPLES

RATE = 10_000          # Hz: the motion's limits checked on samples this dense


@pytest.fixture(scope="module")
def demo_result():
    return run_job(demo_task())


def _port_free(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


def test_the_demo_reaches_its_target_around_the_post(demo_result):
    r = demo_result
    task = r.task
    assert r.success, r.reason
    assert r.final.position_error <= r.final.resolution
    # The post is in the way of the straight joint motion ...
    checker = CollisionChecker(task.robot, task.scene, resolution=1e-9)
    line = np.linspace(r.q_current, r.ik.q_goal, 400)
    assert (checker.clearance(line) <= 0).any()
    # ... and the motion is clear, by a check every 0.002 rad of joint motion.
    tr = r.motion.trajectory
    steps = int(np.ceil(np.abs(np.diff(tr.evaluate(np.linspace(
        0, tr.duration, 20001)), axis=0)).sum(axis=0).max() / 0.002)) + 2
    dense = tr.evaluate(np.linspace(0, tr.duration, max(steps, 20001)))
    assert np.abs(np.diff(dense, axis=0)).max() <= 0.002
    assert checker.clearance(dense).min() > 0


def test_the_demo_motion_is_jerk_limited_and_near_the_acceleration_optimum(demo_result):
    """At 10 kHz: |jerk| within the jerk limits, no acceleration step (a change between two
    samples of at most the jerk limit times the step), rest at both ends; the duration within
    1.2 times the acceleration-limited optimum along the same path (armkit.retime)."""
    r = demo_result
    V, A, J = motion_limits(r.task)
    tr = r.motion.trajectory
    s = tr.sample(np.r_[np.arange(0.0, tr.end, 1.0 / RATE), tr.end])
    assert (np.abs(s.qd) <= V * (1 + 1e-7)).all()
    assert (np.abs(s.qdd) <= A * (1 + 1e-7)).all()
    assert (np.abs(s.qddd) <= J * (1 + 1e-7)).all()
    assert (np.abs(np.diff(s.qdd, axis=0)) <= J / RATE * (1 + 1e-6) + 1e-12).all()
    np.testing.assert_allclose(s.qdd[[0, -1]], 0.0, atol=1e-6)
    optimum = retime(r.motion.path, V, A)
    assert optimum.success and tr.duration <= 1.2 * optimum.duration


def test_the_waypoints_lie_on_the_motion_and_were_all_taken(demo_result):
    r = demo_result
    motion = r.motion
    assert motion.q.shape == (r.task.motion.waypoints, r.task.robot.n)
    np.testing.assert_allclose(motion.trajectory.evaluate(motion.t), motion.q, atol=1e-9)
    assert r.sent.last_accepted == r.task.motion.waypoints - 1
    np.testing.assert_allclose(motion.q[0], r.q_current, atol=1e-6)
    assert r.drive.startswith("simulated drive on 127.0.0.1:")
    assert _port_free(int(r.drive.rsplit(":", 1)[1]))          # stopped afterwards
    assert [item[1] for item in r.checks.items] == ["ok"] * len(r.checks.items)


def test_the_chosen_solution_is_the_nearest_collision_free_one(demo_result):
    choice = demo_result.ik
    free = np.flatnonzero(choice.collision_free)
    d = np.linalg.norm(choice.solutions - demo_result.q_current, axis=1)
    assert choice.chosen == free[np.argmin(d[free])]
    T = armkit.fk(demo_result.task.robot, choice.q_goal)
    np.testing.assert_allclose(T[:3, 3], demo_result.target.T_base_target[:3, 3], atol=1e-9)


def test_the_job_record_is_frozen(demo_result):
    with pytest.raises(AttributeError):
        demo_result.success = False
    with pytest.raises(AttributeError):
        demo_result.motion.t = None


def test_an_unreachable_target_sends_nothing():
    task = demo_task()
    far = task.target.T_camera_target.copy()
    far[:3, 3] += [5.0, 0, 0]
    result = run_job(replace(task, target=replace(task.target, T_camera_target=far)))
    assert not result.success and result.stopped_at == "ik"
    assert "out of reach" in result.reason
    assert result.sent is None and result.motion is None


def test_no_path_within_the_budget_sends_nothing():
    task = demo_task()
    result = run_job(replace(task, planner=replace(task.planner, name="rrt",
                                                   max_iterations=2, seed=3)))
    assert not result.success and result.stopped_at == "plan"
    assert "no collision-free path" in result.reason and "budget" in result.reason
    assert result.sent is None


def test_every_solution_in_collision_is_a_reason():
    task = demo_task()
    T = task.T_base_camera @ task.target.T_camera_target
    cage = Box([0.3, 0.3, 0.3], _at(T[:3, 3]), "cage")
    result = run_job(replace(task, scene=Scene((cage,))))
    assert not result.success and result.stopped_at == "ik"
    assert "no collision-free IK solution" in result.reason
    assert not result.ik.collision_free.any()


def _at(p):
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _on(task, port: int, **settings):
    """The task with its drive at 127.0.0.1:port."""
    return replace(task, drive=replace(task.drive, host="127.0.0.1", port=port, **settings))


def test_a_drive_fault_reports_the_last_accepted_waypoint():
    task = demo_task()
    with SimDrive(task.drive.register_map, position=task.start) as sim:
        sim.inject("fault", at=4)
        result = run_job(_on(task, sim.port))
        taken = len(sim.taken)
    assert not result.success and result.stopped_at in ("send", "arrival")
    assert result.sent.last_accepted == taken - 1 == 3


def test_a_status_read_failing_mid_job_names_the_true_last_accepted_waypoint():
    """The job reads the drive's actual positions between waypoints; when such a read gets no
    answer after waypoint 4 was taken, the reason names waypoint 4, as the record does."""
    task = demo_task()
    m = task.drive.register_map
    actual = min(j.actual for j in m.joints)
    writes = []

    def on_request(frame):
        found = registers(frame)
        if found and found[0] == 16 and found[1] == m.block_start:
            writes.append(found)
        return frame

    def on_response(request, response):
        found = registers(request)
        if len(writes) >= 5 and found and found[0] == 3 and found[1] == actual:
            return None                       # the positions' read goes unanswered
        return response

    with SimDrive(m, position=task.start) as sim, \
            FaultProxy(sim.port, on_request, on_response) as proxy:
        result = run_job(_on(task, proxy.port, timeout=0.3))
        taken = len(sim.taken)
    assert not result.success and result.stopped_at == "send"
    assert "status read failed" in result.reason
    assert result.sent.last_accepted == taken - 1 == 4
    assert "(last accepted waypoint: 4" in result.reason


def test_a_drive_reporting_positions_off_by_a_constant_records_where_it_said_it_stopped():
    task = demo_task()
    m = task.drive.register_map
    swing1 = m.joints[1]                      # int16, 10 counts per deg
    assert swing1.type == "int16" and swing1.scale == 10
    first = min(j.actual for j in m.joints)

    def on_response(request, response):       # swing1 reported 2 deg (20 counts) high
        found = registers(request)
        if found and found[0] == 3 and found[1] <= swing1.actual < found[1] + found[2]:
            at = swing1.actual - found[1]
            return set_register(response, 9, at, get_register(response, 9, at) + 20)
        return response

    with SimDrive(m, position=task.start) as sim, \
            FaultProxy(sim.port, on_response=on_response) as proxy:
        result = run_job(_on(task, proxy.port, arrival_timeout=1.0))
    assert first == swing1.actual - 2
    assert not result.success and result.stopped_at == "arrival"
    assert "did not arrive within 1 s: it reports swing1 +" in result.reason
    off = float(re.search(r"swing1 \+([0-9.]+) deg from the last waypoint", result.reason)[1])
    assert off == pytest.approx(2.0, abs=0.051)          # half a count of 0.1 deg each way
    reported = task.robot.q_from_si(result.arrival.q_reported)
    expected = task.robot.q_from_si(result.motion.q[-1])
    np.testing.assert_allclose(reported - expected, [0, 2, 0, 0], atol=0.051)
    assert result.arrival.q_final is None and result.final is None


def test_an_unreachable_drive_is_a_result():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]          # closed again: nothing listens there
    result = run_job(_on(demo_task(), port, timeout=0.5))
    assert not result.success and result.stopped_at == "drive"
    assert "cannot connect" in result.reason


def test_a_motion_beyond_the_limits_fails_its_checks_before_anything_is_sent(demo_result):
    """The checks between the motion and the send judge the motion itself: the demo's motion
    played 1.5 times faster exceeds the velocity, acceleration and jerk limits."""
    motion = demo_result.motion
    fast = replace(motion, trajectory=motion.trajectory.scaled(1 / 1.5), t=motion.t / 1.5)
    checks = check_motion(demo_result.task, fast, demo_result.task.drive.register_map)
    assert not checks.success
    verdicts = dict(checks.items)
    assert verdicts["joint positions within the limits"] == "ok"
    for name in ("velocity", "acceleration", "jerk"):
        assert "times its limit" in verdicts[f"joint {name} within the limits"]
    assert checks.reason.startswith("joint velocity within the limits: ")
    assert isinstance(fast, Motion)


def test_the_torques_are_checked_before_anything_is_sent(demo_result):
    """For a robot with inertias the checks hold the joint torques along the motion within the
    torque limits: the demo's motion holds them, the same motion with a 5 kg payload on the
    water-supply arm's lift does not (its 180 N limit: the arm alone needs about 177 N)."""
    task, motion = demo_result.task, demo_result.motion
    torques = demo_result.checks.torques
    assert demo_result.checks.success and torques.within
    t = np.linspace(motion.trajectory.start, motion.trajectory.end, 500)
    s = motion.trajectory.sample(t)
    independent = armkit.inverse_dynamics(task.robot, s.q, s.qd, s.qdd)
    assert np.abs(independent).max(axis=0) == pytest.approx(torques.peak, rel=0.02)
    loaded = replace(task, robot=armkit.with_payload(task.robot, 5.0))
    checks = check_motion(loaded, motion, task.drive.register_map)
    verdict = dict(checks.items)["joint torques within the limits"]
    assert not checks.success and verdict.startswith("lift at 1.")
    assert checks.reason == f"joint torques within the limits: {verdict}"


@pytest.mark.parametrize("name", ["modular_4dof", "inspection_6dof", "tool_changer_6dof"])
def test_each_example_obstacle_blocks_the_straight_motion(name):
    task = load_task(EXAMPLES / f"{name}.task.yaml")
    result = run_job(task)
    assert result.success, result.reason
    checker = CollisionChecker(task.robot, task.scene, resolution=1e-9)
    line = np.linspace(result.q_current, result.ik.q_goal, 400)
    assert (checker.clearance(line) <= 0).any()
    tr = result.motion.trajectory
    dense = tr.evaluate(np.linspace(0, tr.duration, 40001))
    assert checker.clearance(dense).min() > 0


def test_a_target_found_in_a_point_cloud():
    task = load_task(EXAMPLES / "water_supply_lidar.task.yaml")
    result = run_job(task)
    assert result.success, result.reason
    assert result.target.detection.success
    np.testing.assert_allclose(result.target.T_base_target,
                               result.target.detection.T_base_target)
    # The tool reaches the inlet's centre (position task) within the drive's resolution.
    p = armkit.fk(task.robot, result.arrival.q_final)[:3, 3]
    assert np.linalg.norm(p - result.target.T_base_target[:3, 3]) <= result.final.resolution


def test_a_cloud_without_an_inlet_is_a_reason():
    rng = np.random.default_rng(0)
    xy = rng.uniform(-0.5, 0.5, (20_000, 2))
    wall = Cloud(np.c_[xy[:, 0], np.full(len(xy), 1.2), xy[:, 1]], "m", 0, "wall.npy")
    task = load_task(EXAMPLES / "water_supply_lidar.task.yaml")
    result = run_job(replace(task, target=replace(task.target, cloud=wall, radius=None)))
    assert not result.success and result.stopped_at == "target"
    assert result.reason.startswith("no target in the cloud: ") and result.sent is None
