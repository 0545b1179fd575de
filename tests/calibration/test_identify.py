"""Kinematic calibration: analytic identification Jacobian, identifiability, recovery of the
perturbed identifiable parameters, the identified robot file, pose selection."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.calibration.identify import (
    calibrate,
    evaluate,
    identifiability,
    identified_robot,
    parametric_model,
    select_poses,
)
from armkit.errors import InputError
from armkit.model import Robot
from tests.helpers import random_q

PAPER_ROBOTS = ["water_supply", "modular_4dof", "inspection_6dof"]


def _perturbed(robot, seed, size=0.002, only=None, n=40):
    """Nominal parameters with the identifiable ones (from nominal data at n configurations q,
    returned) moved by ~size."""
    model = parametric_model(robot)
    rng = np.random.default_rng(seed)
    q = random_q(robot, n, seed=seed)
    _, J = evaluate(model, model.nominal, q)
    found = identifiability(J[:, :3].reshape(-1, len(model.names)), model.names)
    truth = model.nominal.copy()
    idx = found.identifiable if only is None else only
    truth[idx] += rng.normal(size=len(idx)) * size
    return model, found, truth, q


@pytest.mark.parametrize("name", [*PAPER_ROBOTS, "tool_changer_6dof", "ur5"])
def test_model_reproduces_the_robots_forward_kinematics(name):
    robot = armkit.robot(name)
    model = parametric_model(robot)
    q = random_q(robot, 50, seed=1)
    T, _ = evaluate(model, model.nominal, q)
    assert np.abs(T - armkit.fk(robot, q)).max() < 1e-12


@settings(max_examples=15)
@given(st.sampled_from([*PAPER_ROBOTS, "tool_changer_6dof", "panda"]), st.integers(0, 1000))
def test_identification_jacobian_matches_central_differences(name, seed):
    robot = armkit.robot(name)
    model = parametric_model(robot)
    rng = np.random.default_rng(seed)
    params = model.nominal + rng.normal(size=len(model.nominal)) * 0.01
    q = random_q(robot, 5, seed=seed)
    T, J = evaluate(model, params, q)
    h = 1e-6
    for k in range(len(params)):
        up, down = params.copy(), params.copy()
        up[k] += h
        down[k] -= h
        Tu, Td = evaluate(model, up, q, False)[0], evaluate(model, down, q, False)[0]
        dp = (Tu[:, :3, 3] - Td[:, :3, 3]) / (2 * h)
        dR = (Tu[:, :3, :3] - Td[:, :3, :3]) / (2 * h) @ np.swapaxes(T[:, :3, :3], -1, -2)
        w = np.stack([dR[:, 2, 1], dR[:, 0, 2], dR[:, 1, 0]], axis=-1)
        assert np.abs(J[:, :3, k] - dp).max() < 1e-7, model.names[k]
        assert np.abs(J[:, 3:, k] - w).max() < 1e-7, model.names[k]


@pytest.mark.parametrize("name", PAPER_ROBOTS)
def test_noise_free_identifiable_parameters_recovered(name, tmp_path):
    robot = armkit.robot(name)
    model, found, truth, q = _perturbed(robot, seed=3)
    actual = identified_robot(model, truth)
    measured = armkit.fk(actual, q)[:, :3, 3]
    result = calibrate(robot, q, measured)
    assert result.success and result.added == {}
    assert np.array_equal(np.flatnonzero(result.identifiable), found.identifiable)
    assert np.abs(result.identified - truth).max() < 1e-9
    assert result.residuals_after.max() < 1e-9 < result.residuals_before.max()
    # Unidentifiable parameters stay at nominal, and are named with what they act as.
    held = ~result.identifiable
    assert np.array_equal(result.identified[held], model.nominal[held])
    assert set(result.dependencies) == {model.names[k] for k in np.flatnonzero(held)}
    # The identified table saved as a robot file loads and reproduces the measurements.
    path = tmp_path / f"{name}_calibrated.yaml"
    armkit.save_robot(result.robot, path)
    loaded = armkit.load_robot(path)
    assert loaded.units == robot.units and type(loaded.table) is type(robot.table)
    assert np.abs(armkit.fk(loaded, q)[:, :3, 3] - measured).max() < 1e-9


def _every_parameter_moved(robot, seed, n=200):
    """A true arm with every parameter off nominal by realistic amounts (0.5 mm, 0.2 deg),
    its measured positions at n configurations and at 100 hold-out ones."""
    model = parametric_model(robot)
    rng = np.random.default_rng(seed)
    truth = model.nominal + np.where(model.angular,
                                     rng.normal(size=len(model.names)) * np.deg2rad(0.2),
                                     rng.normal(size=len(model.names)) * 5e-4)
    actual = identified_robot(model, truth)
    q, qh = random_q(robot, n, seed=seed), random_q(robot, 100, seed=seed + 1)
    return model, armkit.fk(actual, q)[:, :3, 3], q, (qh, armkit.fk(actual, qh)[:, :3, 3])


def test_second_pass_adds_what_the_nominal_geometry_hides():
    """UR5, every parameter moved: at nominal the tool point is on the last axis, so two of
    wrist2's alpha, a, theta, d look dependent; at the fitted values (the tool point off the
    axis) they are not. The second pass names the two it adds, and the model then meets
    noise-free measurements; held at nominal, they leave micrometres."""
    robot = armkit.robot("ur5")
    model, measured, q, holdout = _every_parameter_moved(robot, seed=2)
    result = calibrate(robot, q, measured, holdout=holdout)
    nominal_only = calibrate(robot, q, measured, holdout=holdout, significance=np.inf)
    assert nominal_only.added == {} and nominal_only.holdout_after.max() > 2e-6
    assert len(result.added) == 2
    assert set(result.added) <= {"wrist2.alpha", "wrist2.a", "wrist2.theta", "wrist2.d"}
    assert min(result.added.values()) > 10               # far past the default 2 sigma
    assert result.holdout_after.max() < 1e-7 and result.residuals_after.max() < 1e-7
    added = [model.names.index(n) for n in result.added]
    assert result.identifiable[added].all() and (result.std[added] > 0).all()
    assert not set(result.added) & set(result.dependencies)
    assert result.identifiable.sum() == nominal_only.identifiable.sum() + 2


def test_second_pass_leaves_what_noise_hides():
    """With 0.05 mm of noise on 200 points the same micrometre effects are not significant:
    nothing is added. The lengths along UR5's three parallel axes (elbow.d, wrist1.d), whose
    effect at any values is second order, stay held: their estimates would swing by metres."""
    robot = armkit.robot("ur5")
    _, measured, q, holdout = _every_parameter_moved(robot, seed=2)
    noisy = measured + np.random.default_rng(2).normal(0, 5e-5, measured.shape)
    result = calibrate(robot, q, noisy, holdout=holdout)
    assert result.added == {}
    assert {"elbow.d", "wrist1.d"} <= set(result.dependencies)
    assert result.holdout_after.mean() < 3e-5


def test_water_supply_unidentifiable_from_positions():
    """All the d's merge into one, and joint 4's offset is invisible (the tool is on its axis)."""
    robot = armkit.robot("water_supply")
    model, found, _, _ = _perturbed(robot, seed=0)
    names = [model.names[k] for k in found.identifiable]
    ds = ["base.d", "lift.d", "swing1.d", "swing2.d", "swing3.d"]
    kept = [d for d in ds if d in names]
    assert len(kept) == 1
    for d in ds:
        if d != kept[0]:
            assert found.dependencies[d] == pytest.approx({kept[0]: 1.0})
    assert found.dependencies["swing3.theta"] == {}
    assert found.dependencies["T_tool.rz"] == {}
    assert "swing1.theta" in names and "swing2.theta" in names


def test_modular_4dof_unidentifiable_from_positions():
    robot = armkit.robot("modular_4dof")
    model, found, _, _ = _perturbed(robot, seed=0)
    names = [model.names[k] for k in found.identifiable]
    assert found.dependencies["wrist.alpha"] == {}
    assert sum(d in names for d in ("shoulder.d", "elbow.d", "wrist.d")) == 1
    assert "T_base.rz" in found.dependencies or "yaw.theta" in found.dependencies


def test_inspection_6dof_unidentifiable_from_positions():
    robot = armkit.robot("inspection_6dof")
    model, found, _, _ = _perturbed(robot, seed=0)
    names = [model.names[k] for k in found.identifiable]
    assert found.dependencies["q6.theta"] == {} and found.dependencies["q6.alpha"] == {}
    assert sum(d in names for d in ("q2.d", "q3.d", "q4.d")) == 1
    assert len(names) == 23


def test_screw_table_recovered_and_saved(tmp_path):
    robot = armkit.robot("tool_changer_6dof")
    model, found, truth, q = _perturbed(robot, seed=5, size=0.001)
    measured = armkit.fk(identified_robot(model, truth), q)[:, :3, 3]
    result = calibrate(robot, q, measured)
    assert np.abs(result.identified - truth).max() < 1e-9
    armkit.save_robot(result.robot, tmp_path / "tc.yaml")
    loaded = armkit.load_robot(tmp_path / "tc.yaml")
    assert np.abs(armkit.fk(loaded, q)[:, :3, 3] - measured).max() < 1e-9


def test_pose_measurements_identify_more():
    robot = armkit.robot("inspection_6dof")
    model = parametric_model(robot)
    q = random_q(robot, 30, seed=8)
    _, J = evaluate(model, model.nominal, q)
    J[:, 3:] *= 0.1                 # calibrate's rotation_weight: rotations count 0.1 m per rad
    found = identifiability(J.reshape(-1, len(model.names)), model.names)
    truth = model.nominal.copy()
    truth[found.identifiable] += np.random.default_rng(8).normal(
        size=len(found.identifiable)) * 0.002
    measured = armkit.fk(identified_robot(model, truth), q)
    result = calibrate(robot, q, measured)
    assert result.identifiable.sum() > 23
    assert "T_tool.ry" not in result.dependencies and "q6.theta" not in result.dependencies
    assert result.dependencies["T_tool.rx"] == pytest.approx({"q6.alpha": 1.0})
    assert result.dependencies["T_tool.rz"] == pytest.approx({"q6.theta": 1.0})
    assert np.abs(result.identified - truth).max() < 1e-9


def test_noisy_measurements_with_a_holdout():
    """0.05 mm of noise: hold-out error falls from millimetres to well under 0.1 mm, and the
    standard deviations are the size of the actual errors."""
    robot = armkit.robot("inspection_6dof")
    model, found, truth, q = _perturbed(robot, seed=9, n=100)
    actual = identified_robot(model, truth)
    rng = np.random.default_rng(9)
    qh = random_q(robot, 50, seed=11)
    measured = armkit.fk(actual, q)[:, :3, 3] + rng.normal(0, 5e-5, (100, 3))
    result = calibrate(robot, q, measured, holdout=(qh, armkit.fk(actual, qh)[:, :3, 3]))
    assert result.holdout_before.mean() > 1e-3 and result.holdout_after.mean() < 5e-5
    assert 3e-5 < np.sqrt(np.mean(result.residuals_after ** 2)) < 1.2e-4
    free = result.identifiable
    z = (result.identified - truth)[free] / result.std[free]
    assert np.sqrt(np.mean(z ** 2)) < 2.5
    assert result.condition_number > 1 and 0 < result.o1


def test_select_poses_beats_random_choices():
    robot = armkit.robot("water_supply")
    model = parametric_model(robot)
    pool = random_q(robot, 300, seed=4)
    chosen = select_poses(robot, pool, 10)
    assert len(set(chosen.tolist())) == 10 and chosen.min() >= 0 and chosen.max() < 300
    _, J = evaluate(model, model.nominal, pool)
    J = J[:, :3]
    found = identifiability(J.reshape(-1, len(model.names)), model.names)
    J = J[:, :, found.identifiable]
    J = J / np.linalg.norm(J, axis=(0, 1))

    def logdet(idx):
        M = J[idx].reshape(-1, J.shape[-1])
        return np.linalg.slogdet(M.T @ M)[1]

    rng = np.random.default_rng(0)
    random_sets = [logdet(rng.choice(300, 10, replace=False)) for _ in range(50)]
    assert logdet(chosen) > max(random_sets)


def test_bad_input():
    robot = armkit.robot("water_supply")
    q = random_q(robot, 5, seed=1)
    with pytest.raises(InputError, match=r"measurements q: expected last axis 4"):
        calibrate(robot, q[:, :3], np.zeros((5, 3)))
    with pytest.raises(InputError, match=r"measurements: expected shape \(5, 3\) positions or "
                                         r"\(5, 4, 4\) poses, found \(4, 3\)"):
        calibrate(robot, q, np.zeros((4, 3)))
    with pytest.raises(InputError, match="positions: expected finite numbers"):
        calibrate(robot, q, np.full((5, 3), np.nan))
    bare = Robot("bare", robot.chain)
    with pytest.raises(InputError, match="expected one built from a DH, modified DH or screw "
                                         "table"):
        calibrate(bare, q, np.zeros((5, 3)))
    with pytest.raises(InputError, match="parts: expected some of table, base, tool, found "
                                         "wrist"):
        parametric_model(robot, ("table", "wrist"))
    with pytest.raises(InputError, match=r"n: expected 1 \.\. 5 \(the pool's size\), found 6"):
        select_poses(robot, q, 6)
