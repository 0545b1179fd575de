"""Inverse kinematics: FK(IK(x)) = x for every built-in robot, complete closed-form solution sets
against roboticstoolbox and against multi-start enumeration, honest failures, masks, choice."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
import roboticstoolbox as rtb
from hypothesis import given
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.kinematics.ik import analytic, default_mask, ik, ik_solutions
from armkit.kinematics.ik.seeds import SeedBank, feature_columns, features
from armkit.kinematics.ik.masks import as_mask, task_errors
from armkit.model import DHRow, DHTable, Limits, Robot, ScrewRow, ScrewTable, chain_from_dh
from armkit.model import chain_from_poe
from armkit.spatial import rotx, transform
from tests.helpers import random_q

ROBOTS = {name: armkit.robot(name) for name in armkit.robots()}
CLOSED_FORM = ["water_supply", "modular_4dof", "inspection_6dof", "ur5", "puma560", "stanford"]
seeds = st.integers(0, 2**32 - 1)


def same_angles(robot, a, b, tol=1e-7):
    d = np.where(robot.chain.revolute, (a - b + np.pi) % (2 * np.pi) - np.pi, a - b)
    return np.abs(d).max(axis=-1) < tol


def assert_solved(robot, result, T, mask=None):
    mask = default_mask(robot) if mask is None else as_mask(mask)
    assert np.all(result.success), np.unique(result.reason)
    pe, re = task_errors(armkit.fk(robot, result.q), T, mask)
    assert pe.max() < 1e-9 and re.max() < 1e-9
    assert np.all((result.q >= robot.lower - 1e-12) & (result.q <= robot.upper + 1e-12))


@pytest.mark.parametrize("name", sorted(ROBOTS))
@given(seed=seeds)
def test_fk_of_ik_is_the_target(name, seed):
    robot = ROBOTS[name]
    T = armkit.fk(robot, random_q(robot, 20, seed))
    result = ik(robot, T)
    missed = ~result.success    # about one Panda target in 20,000 is an honest "did not converge"
    assert missed.sum() <= 1    # of its random starts (see BENCHMARKS.md); other starts reach it
    if missed.any():
        assert result.reason[missed][0].startswith("did not converge")
        assert_solved(robot, ik(robot, T[missed], seed=seed + 1), T[missed])
    kept = ~missed
    assert_solved(robot, ik(robot, T[kept]) if missed.any() else result, T[kept])


@pytest.mark.parametrize("name", sorted(ROBOTS))
@pytest.mark.parametrize("method", ["lm", "newton"])
def test_numeric_solvers_alone(name, method):
    robot = ROBOTS[name]
    T = armkit.fk(robot, random_q(robot, 100, seed=11))
    result = ik(robot, T, method=method)
    assert_solved(robot, result, T)
    assert set(result.method) == {method} and result.iterations.min() >= 0


def test_newton_from_a_nearby_start_converges_in_a_few_steps():
    """The inspection-robot paper: Newton's method from a nearby start, about 5 iterations."""
    robot = ROBOTS["inspection_6dof"]
    q = random_q(robot, 80, seed=12)
    # Away from singularities (a folded elbow, say), where the nearby basin is tiny.
    q = q[armkit.min_singular_value(robot, q) > 0.05][:50]
    q0 = q + np.random.default_rng(12).normal(scale=0.05, size=q.shape)
    result = ik(robot, armkit.fk(robot, q), q0, method="newton")
    assert result.success.all()
    assert np.median(result.iterations) <= 6
    assert same_angles(robot, result.q, q).all()          # the nearby solution, not another


@pytest.mark.parametrize("name", CLOSED_FORM)
def test_each_closed_form_solution_reaches_the_target(name):
    robot = ROBOTS[name]
    for q in random_q(robot, 30, seed=13):
        T = armkit.fk(robot, q)
        sols = ik_solutions(robot, T)
        assert len(sols.q) >= 1 and np.any(same_angles(robot, sols.q, q))
        pe, re = task_errors(armkit.fk(robot, sols.q), T, as_mask(sols.mask))
        assert pe.max() < 1e-10 and re.max() < 1e-10


def test_puma_solutions_include_every_roboticstoolbox_configuration():
    robot, puma = ROBOTS["puma560"], rtb.models.DH.Puma560()
    for q in random_q(robot, 20, seed=14):
        T = armkit.fk(robot, q)
        ours = ik_solutions(robot, T).q
        assert len(ours) == 8
        for config in ("".join(c) for c in itertools.product("lr", "ud", "nf")):
            theirs = puma.ikine_a(T, config=config)
            assert theirs.success
            assert np.any(same_angles(robot, ours, theirs.q, tol=1e-6)), config


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "inspection_6dof", "stanford"])
def test_solution_count_matches_multistart_enumeration(name):
    """Every distinct solution that 300 random numeric starts find is a closed-form one, and
    the other way round (an independent count of the solutions)."""
    robot = ROBOTS[name]
    for q in random_q(robot, 3, seed=15):
        T = armkit.fk(robot, q)
        sols = ik_solutions(robot, T)
        ours = sols.q[sols.within_limits]                 # numeric solves stay inside limits
        starts = random_q(robot, 300, seed=16)
        found = ik(robot, np.broadcast_to(T, (300, 4, 4)), starts, method="lm", restarts=0)
        numeric = found.q[found.success]
        assert all(np.any(same_angles(robot, ours, s, 1e-6)) for s in numeric)
        assert all(np.any(same_angles(robot, numeric, s, 1e-6)) for s in ours)


def test_yaw_pitch_arm_has_four_solutions_with_the_twin_base_angle():
    robot = ROBOTS["modular_4dof"]
    wide = dataclasses.replace(robot, chain=dataclasses.replace(robot.chain, joints=tuple(
        dataclasses.replace(j, limits=Limits(-np.pi, np.pi)) for j in robot.chain.joints)))
    q = np.deg2rad([20, 30, 40, -30])
    sols = ik_solutions(wide, armkit.fk(wide, q))
    assert len(sols.q) == 4
    base = np.sort(np.rad2deg(sols.q[:, 0]))
    np.testing.assert_allclose(base, [-160, -160, 20, 20], atol=1e-9)   # 20 deg and its twin
    assert sols.within_limits.all()
    # Under the real limits the twins fall outside.
    sols = ik_solutions(robot, armkit.fk(robot, q))
    assert sols.within_limits.sum() < len(sols.q)


def test_closed_forms_are_found_by_geometry_not_by_name():
    ur5 = ROBOTS["ur5"]
    # The UR5 as screws (no DH table at all), under another name.
    rows = tuple(ScrewRow("revolute", S[3:], j.limits, point)
                 for S, j, point in zip(ur5.chain.screws, ur5.chain.joints, ur5.chain.points))
    other = Robot("my_arm", chain_from_poe(ScrewTable(rows, ur5.chain.T_home)))
    assert analytic.family_of(other.chain).name == "parallel_wrist"
    # A SCARA with its lift third and one swing axis pointing down.
    rows = (DHRow("revolute", 0, 0.4, 0.3, 0, limits=Limits(-2, 2)),
            DHRow("revolute", np.pi, 0.3, 0, 0, limits=Limits(-2, 2)),
            DHRow("prismatic", 0, 0, 0, 0, limits=Limits(0, 0.2)),
            DHRow("revolute", 0, 0, 0.05, 0, limits=Limits(-3, 3)))
    scara = Robot("scara", chain_from_dh(DHTable(rows, T_tool=transform(p=[0.02, 0, 0.1]))))
    assert analytic.family_of(scara.chain).name == "lift_swing"
    q = np.array([0.3, -0.8, 0.1, 1.0])
    T = armkit.fk(scara, q)
    assert_solved(scara, ik(scara, T), T)
    assert any(same_angles(scara, ik_solutions(scara, T).q, q))


def test_target_beyond_reach_is_a_failed_result_with_reason():
    for name in sorted(ROBOTS):
        robot = ROBOTS[name]
        T = armkit.fk(robot, random_q(robot, 1, seed=17)[0])
        T[:3, 3] = robot.chain.points[0] + 10.0 * (T[:3, 3] - robot.chain.points[0]) / np.linalg.norm(
            T[:3, 3] - robot.chain.points[0])
        result = ik(robot, T)
        assert not result.success and result.q.shape == (robot.n,)
        # Past the reach bound, even where a closed form sees that a longer stroke of a
        # prismatic joint would reach (the Stanford arm), the reason is the reach.
        assert result.reason == "out of reach" and result.position_error > 1.0, name


def test_just_outside_reach_and_at_the_reach_boundary():
    robot = ROBOTS["water_supply"]
    T = armkit.fk(robot, [0.3, 0.0, 0.0, 0.0])          # arm stretched: 1326.5 mm out
    assert ik(robot, T).success                          # at the boundary: reachable
    T[0, 3] += 1e-6                                      # 1 um beyond
    result = ik(robot, T)
    assert not result.success and result.reason == "out of reach"
    # UR5: bisect along a ray for the edge of the reachable poses; the arm is singular there.
    ur5 = ROBOTS["ur5"]
    T0 = armkit.fk(ur5, np.array([0.2, -0.9, 0.8, 0.3, 0.7, 0.1]))
    ray = T0[:3, 3] - ur5.chain.points[1]
    ray /= np.linalg.norm(ray)
    moved = lambda s: transform(T0[:3, :3], T0[:3, 3] + s * ray)     # noqa: E731
    inside, outside = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (inside + outside)
        inside, outside = (mid, outside) if ik(ur5, moved(mid)).success else (inside, mid)
    assert ik(ur5, moved(inside - 1e-6)).success
    assert armkit.min_singular_value(ur5, ik(ur5, moved(inside)).q) < 1e-3
    for method in ("auto", "lm"):
        result = ik(ur5, moved(outside + 1e-6), method=method)
        assert not result.success, method
        assert str(result.reason) in ("out of reach", "singular") or str(result.reason).startswith("did not")
    # The tool changer (numeric only) stretched along x, 1 mm beyond its 2.8 m reach.
    changer = ROBOTS["tool_changer_6dof"]
    T = armkit.fk(changer, [0, 0, 0, 0.8, 0, 0])
    T[0, 3] += 1e-3
    result = ik(changer, T)
    assert not result.success and result.position_error > 0.9e-3
    assert str(result.reason) in ("out of reach", "singular") or str(result.reason).startswith("did not")


def test_a_branch_near_the_target_is_polished_by_the_numeric_solver():
    """Branches within 1e-6 of the target but not within tolerance go to Levenberg-Marquardt.
    Below double precision (1e-17) nothing can succeed: every target takes that path and
    fails honestly, its q still as close as arithmetic allows."""
    robot = ROBOTS["ur5"]
    T = armkit.fk(robot, random_q(robot, 5, seed=23))
    result = ik(robot, T, tol_position=1e-17, tol_rotation=1e-17, restarts=2)
    assert set(result.method) == {"analytic:parallel_wrist+lm"}
    assert not result.success.any() and all(r != "ok" for r in result.reason)
    assert np.all(result.position_error < 1e-12) and np.all(result.rotation_error < 1e-12)


@pytest.mark.parametrize("name, wrist", [("ur5", 4), ("inspection_6dof", 4), ("puma560", 4),
                                         ("stanford", 4)])
def test_poses_at_a_wrist_singularity_are_solved(name, wrist):
    """With the wrist's middle joint at zero the solutions form a continuum; the closed form's
    one branch may not close there, and the numeric solver takes over from it."""
    robot = ROBOTS[name]
    Q = random_q(robot, 300, seed=24)
    Q[:, wrist] = 0.0
    result = ik(robot, armkit.fk(robot, Q))
    assert_solved(robot, result, armkit.fk(robot, Q))


def test_outside_joint_limits_is_its_own_reason():
    robot = ROBOTS["water_supply"]
    T = armkit.fk(robot, [0.0, 0.3, 0.2, 0.1])
    T[2, 3] += 1.0                                       # needs 1.0 m of lift, the stroke is 0.6
    result = ik(robot, T)
    assert not result.success and result.reason == "outside joint limits"


def test_position_mask_leaves_orientation_free():
    robot = ROBOTS["ur5"]
    T = armkit.fk(robot, random_q(robot, 10, seed=18))
    wanted = T.copy()
    wanted[:, :3, :3] = rotx(2.5)                        # an orientation it will not keep
    result = ik(robot, wanted, mask="position")
    assert result.success.all() and result.mask == "position"
    reached = armkit.fk(robot, result.q)
    np.testing.assert_allclose(reached[:, :3, 3], T[:, :3, 3], atol=1e-9)
    _, full_rotation_error = task_errors(reached, wanted, as_mask("pose"))
    assert full_rotation_error.max() > 1e-3              # orientation was left free


def test_position_and_yaw_for_the_lift_and_swing_arm():
    robot = ROBOTS["water_supply"]
    T = armkit.fk(robot, [0.2, 0.4, -0.6, 0.9])
    tilted = T @ transform(rotx(0.3))                    # a tilt the arm cannot make
    result = ik(robot, tilted)
    assert result.success and result.mask == "position+yaw"
    np.testing.assert_allclose(armkit.fk(robot, result.q), T, atol=1e-12)


@pytest.mark.parametrize("lead", [(), (3,), (2, 3)])
def test_leading_shapes(lead):
    robot = ROBOTS["puma560"]
    q = random_q(robot, lead or 1, seed=19)
    q = q[0] if not lead else q
    result = ik(robot, armkit.fk(robot, q))
    kinds = {"success": bool, "position_error": float, "rotation_error": float,
             "iterations": int, "reason": str, "method": str}
    for field, kind in kinds.items():
        value = getattr(result, field)
        if lead:
            assert value.shape == lead
        else:           # one target: plain Python values
            assert type(value) is kind, (field, type(value))
    assert result.q.shape == lead + (6,)


def test_the_nearest_solution_to_q0_is_chosen():
    robot = ROBOTS["ur5"]
    q = random_q(robot, 1, seed=20)[0]
    T = armkit.fk(robot, q)
    sols = ik_solutions(robot, T).q
    for target_q in sols:
        q0 = target_q + 0.01
        chosen = ik(robot, T, q0).q
        assert same_angles(robot, chosen, target_q)


@pytest.mark.parametrize("criterion", ["least_travel", "manipulability", "limits"])
def test_each_criterion_picks_its_best(criterion):
    robot = ROBOTS["puma560"]
    q = random_q(robot, 1, seed=21)[0]
    T = armkit.fk(robot, q)
    result = ik(robot, T, np.zeros(6), criterion=criterion)
    assert result.criterion == criterion
    sols = ik_solutions(robot, T)
    valid = sols.q[sols.within_limits]              # folded into the limits nearest 0
    from armkit.kinematics.ik.choose import scores
    best = valid[np.argmin(scores(robot, valid[None], np.zeros((1, 6)), criterion, None)[0])]
    assert same_angles(robot, result.q, best)


def test_same_seed_same_result_and_batch_equals_singles():
    robot = ROBOTS["panda"]
    T = armkit.fk(robot, random_q(robot, 8, seed=22))
    a, b = ik(robot, T, seed=3), ik(robot, T, seed=3)
    np.testing.assert_array_equal(a.q, b.q)
    for k in range(len(T)):
        np.testing.assert_array_equal(ik(robot, T[k], seed=3).success, a.success[k])


@pytest.mark.parametrize("kwargs, words", [
    ({"mask": "orientation"}, "mask: expected one of pose, position"),
    ({"mask": [1, 1, 1]}, "mask: expected 6 flags"),
    ({"method": "magic"}, "method: expected one of auto, analytic, lm, newton"),
    ({"criterion": "best"}, "criterion: expected one of nearest"),
    ({"tol_position": 0}, "tol_position: expected a positive tolerance"),
    ({"q0": [0, 0]}, "q0: expected last axis 6"),
    ({"seed": -1}, "seed: expected a non-negative whole number, found -1"),
    ({"seed": 1.5}, "seed: expected a non-negative whole number, found 1.5"),
    ({"weights": [1, 1, 1, 1, 1, -1]}, "weights: expected 6 non-negative numbers"),
])
def test_bad_arguments_are_refused(kwargs, words):
    robot = ROBOTS["ur5"]
    with pytest.raises(InputError, match=words.replace("(", r"\(")):
        ik(robot, np.eye(4), **kwargs)


def test_bad_targets_and_robots_without_closed_form():
    with pytest.raises(InputError, match=r"target: expected shape \(\.\.\., 4, 4\)"):
        ik(ROBOTS["ur5"], np.eye(3))
    with pytest.raises(InputError, match="target: expected a rotation part that is orthonormal"):
        ik(ROBOTS["ur5"], np.diag([2.0, 1, 1, 1]))
    with pytest.raises(InputError, match="found panda, which only the numeric solvers serve"):
        ik_solutions(ROBOTS["panda"], np.eye(4))
    with pytest.raises(InputError, match="its geometry has no closed form"):
        ik(ROBOTS["tool_changer_6dof"], np.eye(4), method="analytic")


@pytest.mark.parametrize("count", [1, 8, 4096])
def test_seed_starts_are_the_samples_nearest_the_target_around_it(count):
    """The grid search ranks by features: with every sample wanted it is an exact sort, and
    the first start is at least as near as every sample in the 27 cells around the target."""
    robot, mask = ROBOTS["ur5"], as_mask("pose")
    T = armkit.fk(robot, random_q(robot, 50, seed=3))
    bank = SeedBank.build(robot, 4096, length=0.1)
    starts = bank.starts(T, mask, count)
    cols = feature_columns(mask)
    F = bank.features[:, cols]
    wanted = features(T, bank.length)[:, cols]
    d = np.sum((wanted[:, None, :] - F[None]) ** 2, axis=-1)                  # (50, 4096)
    reached = features(armkit.fk(robot, starts), bank.length)[..., cols]
    picked = np.sum((wanted[:, None, :] - reached) ** 2, axis=-1)
    assert starts.shape == (50, count, robot.n)
    assert np.all(np.diff(picked, axis=1) >= 0)                                # ranked
    assert np.all([len(np.unique(s, axis=0)) == count for s in starts])        # distinct
    if count == 4096:
        np.testing.assert_allclose(picked, np.sort(d, axis=1), atol=1e-12)
    G, lo, inv = bank.cells, bank.lo, bank.inv
    cell = lambda p: np.clip(((p - lo) * inv).astype(int), 0, G - 1)          # noqa: E731
    around = np.abs(cell(T[:, None, :3, 3]) - cell(F[None, :, :3])).max(axis=-1) <= 1
    assert np.all(picked[:, 0] <= np.where(around, d, np.inf).min(axis=1) + 1e-12)
    assert np.all(picked[:, 0] >= d.min(axis=1) - 1e-12)
