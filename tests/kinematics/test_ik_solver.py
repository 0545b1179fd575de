"""IKSolver: task masks on 6- and 7-joint arms, batch solutions, reuse, no growing state,
serialisable results, the reach bound and the vocabulary of reasons, following a target."""

from __future__ import annotations

import dataclasses
import gc
import json
import weakref

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.kinematics.ik import (OUT_OF_REACH, IKSolver, ik, ik_solutions, reach_bound,
                                  reasons)
from armkit.kinematics.ik.numeric import TARGETS_PER_THREAD, thread_count
from armkit.kinematics.ik.masks import as_mask, task_errors
from armkit.spatial import rotx, roty, rotz, transform
from tests.helpers import random_q

ARMS = ["ur5", "puma560", "inspection_6dof", "stanford", "panda", "tool_changer_6dof"]
PARTIAL = ["position", "position+yaw", "position+pitch", "position+axis"]
SOLVERS = {name: IKSolver(armkit.robot(name)) for name in ARMS}


def assert_task_met(solver, result, T, mask):
    robot = solver.robot
    assert np.all(result.success), np.unique(result.reason)
    pe, re = task_errors(armkit.fk(robot, result.q), T, as_mask(mask))
    assert pe.max() < 1e-9 and re.max() < 1e-9
    assert np.all((result.q >= robot.lower - 1e-12) & (result.q <= robot.upper + 1e-12))


@pytest.mark.parametrize("name", ARMS)
@pytest.mark.parametrize("mask", PARTIAL)
def test_partial_tasks_on_six_and_seven_joint_arms(name, mask):
    """A task with fewer constraints than joints leaves the null space free: it converges at
    least as easily as the full pose (issue: 0 of 30 position+yaw targets did)."""
    solver = SOLVERS[name]
    T = armkit.fk(solver.robot, random_q(solver.robot, 150, seed=31))
    result = solver.solve(T, mask=mask)
    assert result.mask == mask
    assert_task_met(solver, result, T, mask)


@pytest.mark.parametrize("name", ["ur5", "panda"])
@pytest.mark.parametrize("mask", ["position+yaw", "position+pitch"])
def test_partial_task_from_a_start_two_degrees_off(name, mask):
    solver = SOLVERS[name]
    q = random_q(solver.robot, 30, seed=32)
    T = armkit.fk(solver.robot, q)
    result = solver.solve(T, q + np.deg2rad(2), mask=mask, restarts=0)
    assert_task_met(solver, result, T, mask)
    assert np.all(result.iterations <= 10)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), mask=st.sampled_from(PARTIAL),
       name=st.sampled_from(["ur5", "panda", "stanford"]))
def test_fk_of_ik_meets_the_partial_task(seed, mask, name):
    solver = SOLVERS[name]
    T = armkit.fk(solver.robot, random_q(solver.robot, 5, seed))
    # A different orientation about the free axes must not matter.
    result = solver.solve(T, mask=mask)
    assert_task_met(solver, result, T, mask)


def test_yaw_task_ignores_tilt_but_keeps_heading():
    solver = SOLVERS["ur5"]
    T = armkit.fk(solver.robot, [0.3, -1.2, 1.1, -0.4, 1.2, 0.5])
    result = solver.solve(T, mask="position+yaw")
    reached = armkit.fk(solver.robot, result.q)
    np.testing.assert_allclose(reached[:3, 3], T[:3, 3], atol=1e-9)
    # The heading: the tool's x axis and the target's, seen along the tool's z axis.
    z = reached[:3, 2]
    a = T[:3, 0] - z * (z @ T[:3, 0])
    b = reached[:3, 0]
    assert np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b) < 1e-9


# --- every closed-form solution, batched ------------------------------------------------------

@pytest.mark.parametrize("name", ["ur5", "puma560", "stanford", "water_supply", "modular_4dof"])
def test_batch_solutions_equal_the_single_calls(name):
    robot = armkit.robot(name)
    solver = IKSolver(robot)
    q = random_q(robot, (2, 3), seed=33)
    T = armkit.fk(robot, q)
    T[1, 2, :3, 3] += 10.0                              # one target out of reach
    batch = solver.solutions(T)
    K = solver.family.branches
    assert batch.q.shape == (2, 3, K, robot.n) and batch.valid.shape == (2, 3, K)
    assert batch.count.shape == (2, 3)
    # Out of reach: no solution, or (a telescopic joint) none inside the limits.
    assert batch.count[1, 2] == 0 or not batch.within_limits[1, 2].any()
    for i in np.ndindex(2, 3):
        single = ik_solutions(robot, T[i])
        k = single.count
        assert k == batch.count[i] == len(single.q)
        assert np.all(batch.valid[i][:k]) and not np.any(batch.valid[i][k:])
        np.testing.assert_array_equal(batch.q[i][:k], single.q)
        np.testing.assert_array_equal(batch.within_limits[i][:k], single.within_limits)
        assert np.isnan(batch.q[i][k:]).all() and np.isnan(batch.position_error[i][k:]).all()
        if k:
            pe, re = task_errors(armkit.fk(robot, single.q), T[i], as_mask(single.mask))
            assert pe.max() < 1e-9 and re.max() < 1e-9


# --- reuse, immutability, nothing that grows ---------------------------------------------------

def test_a_solver_is_reused_and_gives_what_ik_gives():
    robot = armkit.robot("panda")
    solver = IKSolver(robot)
    T = armkit.fk(robot, random_q(robot, 20, seed=34))
    first = solver.solve(T, seed=2)
    bank = solver.bank
    again = solver.solve(T, seed=2)
    assert solver.bank is bank                           # derived once
    np.testing.assert_array_equal(first.q, again.q)
    # ik() on fewer than BANK_FROM targets is a solver without a bank.
    np.testing.assert_array_equal(IKSolver(robot, samples=0).solve(T, seed=2).q,
                                  ik(robot, T, seed=2).q)
    for k in range(0, 20, 7):                           # one target at a time, same answers
        np.testing.assert_array_equal(solver.solve(T[k], seed=2).q, first.q[k])
    with pytest.raises(AttributeError, match="immutable"):
        solver.reach = 1.0


def test_ik_keeps_nothing_per_robot():
    """A calibration loop makes a new robot per iteration: none may be kept alive by IK."""
    base = armkit.robot("ur5")
    T = armkit.fk(base, random_q(base, 3, seed=35))
    refs = []
    for k in range(30):
        robot = dataclasses.replace(base, name=f"ur5_{k}")
        ik(robot, T)
        ik(robot, T[0], method="lm")
        ik_solutions(robot, T[0])
        refs.append(weakref.ref(robot))
        del robot
    gc.collect()
    assert all(r() is None for r in refs)


def test_thread_count_follows_the_batch_size():
    assert thread_count(1) == 1
    assert thread_count(TARGETS_PER_THREAD - 1, threads=8) == 1
    assert thread_count(10 * TARGETS_PER_THREAD, threads=2) == 2
    assert thread_count(10 * TARGETS_PER_THREAD, threads=1) == 1
    armkit.set_num_threads(1)           # the process-wide bound applies when none is given
    try:
        assert thread_count(10 * TARGETS_PER_THREAD) == 1
    finally:
        armkit.set_num_threads(None)
    robot = armkit.robot("ur5")
    T = armkit.fk(robot, random_q(robot, 3 * TARGETS_PER_THREAD, seed=36))
    one = IKSolver(robot, threads=1).solve(T, method="lm")
    two = IKSolver(robot, threads=2).solve(T, method="lm")
    np.testing.assert_array_equal(one.q, two.q)         # threads never change a result


# --- results -----------------------------------------------------------------------------------

def test_one_target_gives_plain_values_and_results_serialise():
    robot = armkit.robot("ur5")
    T = armkit.fk(robot, random_q(robot, 4, seed=37))
    one = ik(robot, T[0])
    assert one.success is True and one.reason == "ok" and isinstance(one.position_error, float)
    json.dumps(one.to_dict())
    assert json.loads(json.dumps(one.to_dict()))["q"] == one.q.tolist()
    many = ik(robot, T.reshape(2, 2, 4, 4))
    doc = json.loads(json.dumps(many.to_dict()))
    assert np.shape(doc["success"]) == (2, 2) and np.shape(doc["q"]) == (2, 2, 6)
    sols = ik_solutions(robot, T)
    doc = json.loads(json.dumps(sols.to_dict()))
    assert None in np.ravel(doc["q"]).tolist() or all(np.ravel(doc["valid"]))
    failed = ik(robot, transform(p=[5.0, 0, 0]))
    assert failed.to_dict()["reason"] == OUT_OF_REACH


def test_reach_bound_is_public_and_decides_out_of_reach():
    """The Stanford arm's telescope: a target twice beyond reach is out of reach, not outside
    the joint limits (a closed form sees that a longer stroke would get there)."""
    for name in ARMS + ["water_supply", "modular_4dof"]:
        robot = armkit.robot(name)
        bound = reach_bound(robot)
        assert bound == IKSolver(robot).reach
        q = random_q(robot, 200, seed=38)
        d = np.linalg.norm(armkit.fk(robot, q)[:, :3, 3] - robot.chain.points[0], axis=1)
        assert d.max() <= bound
    stanford = armkit.robot("stanford")
    T = armkit.fk(stanford, random_q(stanford, 1, seed=39)[0])
    p = T[:3, 3] - stanford.chain.points[0]
    T[:3, 3] = stanford.chain.points[0] + 2 * reach_bound(stanford) * p / np.linalg.norm(p)
    assert ik(stanford, T).reason == OUT_OF_REACH


def test_one_vocabulary_of_reasons():
    assert reasons.REASONS == ("ok", "out of reach", "outside joint limits", "singular",
                               "did not converge")
    assert reasons.not_converged(20, 251) == "did not converge in 20 iterations x 251 starts"


# --- following a moving target -----------------------------------------------------------------

def test_track_follows_small_moves_from_the_previous_solution():
    solver = SOLVERS["ur5"]
    q0 = np.deg2rad([30, -60, 80, -100, -70, 20])
    T0 = armkit.fk(solver.robot, q0)
    targets = np.stack([transform(T0[:3, :3] @ rotz(0.01 * k), T0[:3, 3] + [0.002 * k, 0, 0])
                        for k in range(40)])
    track = solver.track(targets, q0)
    assert track.success and track.followed == 40 and track.reason == "ok"
    np.testing.assert_allclose(armkit.fk(solver.robot, track.q), targets, atol=1e-9)
    assert np.abs(np.diff(track.q, axis=0)).max() < 0.05
    # A jump bigger than the bound stops it, with the vocabulary's reason.
    jumpy = targets.copy()
    jumpy[20:] = transform(rotx(2.0) @ roty(0.5), T0[:3, 3])
    stopped = solver.track(jumpy, q0, max_joint_step=0.2)
    assert not stopped.success and stopped.followed <= 20
    assert stopped.reason in ("singular",) or stopped.reason.startswith("did not converge")
    with pytest.raises(InputError, match="q_start: expected one configuration"):
        solver.track(targets, np.zeros((2, 6)))


def test_bad_solver_arguments():
    with pytest.raises(InputError, match="robot: expected a Robot, found str"):
        IKSolver("ur5")
    with pytest.raises(InputError, match="threads: expected a whole number >= 1, found 0"):
        IKSolver(armkit.robot("ur5"), threads=0)
    with pytest.raises(InputError, match="samples: expected a whole number >= 0"):
        IKSolver(armkit.robot("ur5"), samples=-5)


# --- one target: the single-call path gives what the batch gives ----------------------------

@pytest.mark.parametrize("name", ["tool_changer_6dof", "panda", "ur5"])
def test_one_numeric_target_equals_its_row_of_the_batch(name):
    """One target takes the single-call path (the pose read in plain Python, q0 checked once,
    the mask's arrays looked up); a batch takes the batch path: the same results, from q0 or
    without, for any mask and however q0 is given."""
    solver = SOLVERS[name]
    robot = solver.robot
    Q = random_q(robot, 6, seed=40)
    T = armkit.fk(robot, Q)
    near = Q + 0.03
    for mask in (None, "position", "position+yaw"):
        batch = solver.solve(T, method="lm", mask=mask)
        from_q0 = solver.solve(T, near, method="lm", mask=mask)
        for k in range(len(T)):
            one = solver.solve(T[k], method="lm", mask=mask)
            assert (one.success, one.reason, one.iterations, one.mask) == (
                batch.success[k], batch.reason[k], batch.iterations[k], batch.mask)
            np.testing.assert_array_equal(one.q, batch.q[k])
            frozen = near[k].copy()
            frozen.setflags(write=False)
            for q0 in (near[k], near[k].tolist(), frozen):
                one = solver.solve(T[k].tolist(), q0, method="lm", mask=mask)
                np.testing.assert_array_equal(one.q, from_q0.q[k])
                assert one.position_error == from_q0.position_error[k]
                assert one.iterations == from_q0.iterations[k]
    far = T[0].copy()
    far[:3, 3] = robot.chain.points[0] + 3 * solver.reach * (far[:3, 3] - robot.chain.points[0]) \
        / np.linalg.norm(far[:3, 3] - robot.chain.points[0])
    assert solver.solve(far, Q[0], method="lm").reason == OUT_OF_REACH
    with pytest.raises(InputError, match="q0: expected finite joint values"):
        solver.solve(T[0], np.full(robot.n, np.nan), method="lm")


def test_seed_starts_of_one_target_equal_its_row_of_a_batch():
    solver = SOLVERS["panda"]
    T = armkit.fk(solver.robot, random_q(solver.robot, 20, seed=41))
    for mask in ("pose", "position", "position+axis", "position+yaw"):
        many = solver.bank.starts(T, as_mask(mask), 8)
        for k in range(len(T)):
            np.testing.assert_array_equal(solver.bank.starts(T[k:k + 1], as_mask(mask), 8)[0],
                                          many[k])


def test_every_mask_has_its_forms_and_name():
    from armkit.kinematics.ik.masks import MASK_FORMS, NAMED_MASKS, mask_forms, mask_name
    assert len(MASK_FORMS) == 63
    for flags, forms in MASK_FORMS.items():
        mask = np.array(flags, dtype=bool)
        assert mask_forms(mask) is forms and mask_name(mask) == forms.name
        np.testing.assert_array_equal(forms.flags, mask)
        np.testing.assert_array_equal(forms.ints, flags)
        np.testing.assert_array_equal(forms.rows, np.flatnonzero(flags))
        assert not (forms.flags.flags.writeable or forms.rows.flags.writeable)
    for name, flags in NAMED_MASKS.items():
        assert mask_name(as_mask(name)) == name
    assert mask_name(np.array([1, 1, 0, 0, 0, 1])) == "110001"


def test_the_chain_holds_its_reach_and_kernel_limits():
    for name in ARMS + ["water_supply", "modular_4dof"]:
        chain = armkit.robot(name).chain
        assert chain.reach == reach_bound(armkit.robot(name)) and chain.reach is chain.reach
        L = chain.kernel_limits
        assert L.shape == (5, chain.n) and not L.flags.writeable
        np.testing.assert_array_equal(L[1], chain.upper)
        np.testing.assert_array_equal(L[2], chain.wraps)
        np.testing.assert_array_equal(L[3:], chain.sampling_limits)
        np.testing.assert_array_equal(L[0], np.where(chain.wraps & ~np.isfinite(chain.lower),
                                                     -np.pi, chain.lower))
