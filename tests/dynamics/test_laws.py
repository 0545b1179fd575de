"""The laws of rigid-body dynamics, for all inputs (hypothesis): M symmetric positive definite,
forward and inverse dynamics each other's inverse, dM/dt - 2 C skew-symmetric, energy kept in
free motion, a payload the same as mass added to the last link; friction and armature as
stated; batch shapes as single calls."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armkit
from armkit.dynamics import (Inertia, coriolis, coriolis_matrix, forward_dynamics,
                             gravity_torques, inverse_dynamics, mass_matrix, with_payload)
from armkit.errors import InputError
from armkit.model.inertia import link_frames_to_kernel
from tests.dynamics.reference import robot_file

DYNAMIC = [name for name in armkit.robots() if armkit.robot(name).inertia is not None]
ROBOTS = {name: armkit.robot(name) for name in DYNAMIC}


def mimic_robot() -> armkit.Robot:
    """The Panda to its right finger, which mimics the left finger (a leader off the chain)."""
    return armkit.load_robot(robot_file("panda_description/urdf/panda.urdf"),
                             tip="panda_rightfinger")


@st.composite
def states(draw, names=tuple(DYNAMIC)):
    """(robot, q, qd, x): a built-in robot with inertias, a configuration within its limits,
    joint rates, and a third joint vector (accelerations or torques)."""
    robot = ROBOTS[draw(st.sampled_from(names))]
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper)
    return robot, q, rng.uniform(-3, 3, robot.n), rng.uniform(-10, 10, robot.n)


@given(states())
def test_mass_matrix_is_symmetric_positive_definite(state):
    robot, q, _, _ = state
    M = mass_matrix(robot, q)
    np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-12 * np.abs(M).max())
    assert np.linalg.eigvalsh(M)[0] > 0


@given(states())
def test_forward_dynamics_inverts_inverse_dynamics(state):
    robot, q, qd, tau = state
    qdd = forward_dynamics(robot, q, qd, tau)
    back = inverse_dynamics(robot, q, qd, qdd)
    np.testing.assert_allclose(back, tau, rtol=0, atol=1e-9 * max(np.abs(tau).max(), 1.0))


@given(states())
def test_mass_matrix_derivative_minus_twice_coriolis_is_skew(state):
    """dM/dt along qd (central differences of M(q + h qd)) minus 2 C is skew-symmetric: x^T
    (dM/dt - 2 C) x = 0 for every x, qd itself included (the power balance)."""
    robot, q, qd, x = state
    h = 1e-6
    M_dot = (mass_matrix(robot, q + h * qd) - mass_matrix(robot, q - h * qd)) / (2 * h)
    N = M_dot - 2 * coriolis_matrix(robot, q, qd)
    scale = np.abs(M_dot).max() + np.abs(mass_matrix(robot, q)).max() * np.abs(qd).max()
    np.testing.assert_allclose(N + N.T, 0, atol=1e-6 * scale)
    assert abs(qd @ N @ qd) <= 1e-6 * scale * (qd @ qd)
    assert abs(x @ N @ x) <= 1e-6 * scale * (x @ x)


@given(states())
def test_coriolis_matrix_times_rates_is_the_velocity_torque(state):
    robot, q, qd, _ = state
    C = coriolis_matrix(robot, q, qd)
    np.testing.assert_allclose(C @ qd, coriolis(robot, q, qd), rtol=0,
                               atol=1e-11 * (1 + np.abs(C).max() * np.abs(qd).max()))
    still = inverse_dynamics(robot, q, qd, np.zeros(robot.n), gravity=[0, 0, 0])
    np.testing.assert_allclose(coriolis(robot, q, qd), still - frictions(robot, qd),
                               rtol=0, atol=1e-11 * (1 + np.abs(still).max()))


def frictions(robot: armkit.Robot, qd):
    model = robot.inertia
    viscous = 0 if model.viscous is None else model.viscous
    coulomb = 0 if model.coulomb is None else model.coulomb
    return viscous * qd + coulomb * np.sign(qd)


@given(states())
def test_torques_split_into_their_terms(state):
    """tau = M qdd + C qd + g (+ friction), each term from its own function."""
    robot, q, qd, qdd = state
    tau = inverse_dynamics(robot, q, qd, qdd)
    parts = (mass_matrix(robot, q) @ qdd + coriolis(robot, q, qd) + gravity_torques(robot, q)
             + frictions(robot, qd))
    np.testing.assert_allclose(tau, parts, rtol=0, atol=1e-10 * (1 + np.abs(tau).max()))


def potential_energy(robot: armkit.Robot, q) -> float:
    """-sum m_i g . c_i, each centre of mass from the link frames of forward kinematics."""
    from armkit.kinematics.forward import joint_frames

    frames, _ = joint_frames(robot, q)
    links = frames @ link_frames_to_kernel(robot.chain)
    total = 0.0
    for body, T in zip(robot.inertia.links, links):
        total -= body.mass * robot.inertia.gravity @ (T[:3, :3] @ body.com + T[:3, 3])
    return total


def free_fall(robot: armkit.Robot, q, qd, duration: float, dt: float):
    """RK4 of the unactuated arm (tau = 0); the energies at every step."""
    def rates(state):
        a, b = state[:robot.n], state[robot.n:]
        return np.r_[b, forward_dynamics(robot, a, b, np.zeros(robot.n))]

    state = np.r_[q, qd]
    energy = []
    for _ in range(int(round(duration / dt))):
        a, b = state[:robot.n], state[robot.n:]
        energy.append(0.5 * b @ mass_matrix(robot, a) @ b + potential_energy(robot, a))
        k1 = rates(state)
        k2 = rates(state + dt / 2 * k1)
        k3 = rates(state + dt / 2 * k2)
        k4 = rates(state + dt * k3)
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.array(energy)


def without_friction_and_armature(robot: armkit.Robot) -> armkit.Robot:
    return dataclasses.replace(robot, inertia=dataclasses.replace(
        robot.inertia, viscous=None, coulomb=None, armature=None))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "inspection_6dof", "water_supply"])
def test_energy_is_kept_in_free_fall(name):
    """No friction, no torques: kinetic plus potential energy stays constant over 2 s of
    RK4 (1e-6 relative to the energy that moved)."""
    robot = without_friction_and_armature(ROBOTS[name])
    q = np.random.default_rng(1).uniform(robot.lower, robot.upper) * 0.5
    energy = free_fall(robot, q, np.zeros(robot.n), 2.0, 5e-4)
    swing = np.abs(energy - energy[0]).max()
    moved = np.abs(potential_energy(robot, q) - potential_energy(robot, q + 0.5)) + 1.0
    assert swing <= 1e-6 * moved


@pytest.mark.slow
@settings(max_examples=20)
@given(states(names=("ur5", "inspection_6dof", "water_supply", "tool_changer_6dof")))
def test_energy_is_kept_from_any_start(state):
    """Free fall from random configurations and rates, 1 s of RK4."""
    robot, q, qd, _ = state
    robot = without_friction_and_armature(robot)
    energy = free_fall(robot, q, qd * 0.3, 1.0, 5e-4)
    moved = np.abs(energy).max() + np.abs(potential_energy(robot, q)
                                          - potential_energy(robot, q + 0.5)) + 1.0
    assert np.abs(energy - energy[0]).max() <= 1e-6 * moved


@given(states(), st.floats(0.1, 20.0), st.lists(st.floats(-0.2, 0.2), min_size=3,
                                                  max_size=3))
def test_payload_is_mass_added_to_the_last_link(state, mass, com):
    """A payload in the tool frame gives the torques of the same body added to the last
    link's inertia in its link frame."""
    robot, q, qd, qdd = state
    payload = Inertia(mass, com, np.diag([0.01, 0.02, 0.03]) * mass)
    loaded = with_payload(robot, payload)
    last = robot.inertia.links[-1] + payload.moved(robot.chain.T_tool)
    heavier = dataclasses.replace(robot, inertia=dataclasses.replace(
        robot.inertia, links=robot.inertia.links[:-1] + (last,)))
    a, b = inverse_dynamics(loaded, q, qd, qdd), inverse_dynamics(heavier, q, qd, qdd)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * (1 + np.abs(b).max()))
    assert with_payload(loaded, None).inertia.payload is None


@given(states())
def test_friction_and_armature_add_their_terms(state):
    robot, q, qd, qdd = state
    rng = np.random.default_rng(int(abs(q[0]) * 1e6))
    viscous, coulomb, armature = rng.uniform(0, 5, (3, robot.n))
    bare = without_friction_and_armature(robot)
    rough = dataclasses.replace(bare, inertia=dataclasses.replace(
        bare.inertia, viscous=viscous, coulomb=coulomb, armature=armature))
    extra = inverse_dynamics(rough, q, qd, qdd) - inverse_dynamics(bare, q, qd, qdd)
    np.testing.assert_allclose(extra, viscous * qd + coulomb * np.sign(qd) + armature * qdd,
                               rtol=0, atol=1e-10 * (1 + np.abs(extra).max()))
    np.testing.assert_allclose(mass_matrix(rough, q) - mass_matrix(bare, q), np.diag(armature),
                               rtol=0, atol=1e-12)


@given(states(), st.floats(-20, 20), st.floats(-20, 20), st.floats(-20, 20))
def test_gravity_is_settable(state, gx, gy, gz):
    """Torques are linear in gravity: g(q) under any vector is the sum of its components'."""
    robot, q, _, _ = state
    parts = sum(c * gravity_torques(robot, q, gravity=e)
                for c, e in zip((gx, gy, gz), np.eye(3)))
    both = gravity_torques(robot, q, gravity=[gx, gy, gz])
    np.testing.assert_allclose(both, parts, rtol=0, atol=1e-10 * (1 + np.abs(both).max()))


@pytest.mark.parametrize("lead", [(), (5,), (2, 3)])
def test_batches_match_single_calls(lead):
    robot = ROBOTS["ur5"]
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.uniform(-2, 2, (3,) + lead + (6,))
    tau = inverse_dynamics(robot, q, qd, qdd)
    M = mass_matrix(robot, q)
    C = coriolis_matrix(robot, q, qd)
    qdd2 = forward_dynamics(robot, q, qd, tau)
    assert tau.shape == lead + (6,) and M.shape == C.shape == lead + (6, 6)
    for index in np.ndindex(*lead):
        np.testing.assert_array_equal(tau[index], inverse_dynamics(robot, q[index], qd[index],
                                                                   qdd[index]))
        np.testing.assert_array_equal(M[index], mass_matrix(robot, q[index]))
        np.testing.assert_array_equal(C[index], coriolis_matrix(robot, q[index], qd[index]))
    np.testing.assert_allclose(qdd2, qdd, rtol=0, atol=1e-9)
    # Leading shapes broadcast: one configuration against many accelerations.
    many = inverse_dynamics(robot, q.reshape(-1, 6)[0], np.zeros(6), qdd.reshape(-1, 6))
    assert many.shape == qdd.reshape(-1, 6).shape


@pytest.mark.slow
def test_large_batch_runs_in_parallel_with_the_same_results():
    robot = ROBOTS["ur5"]
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-2, 2, (3, 20_000, 6))
    armkit.set_num_threads(2)
    try:
        tau = inverse_dynamics(robot, q, qd, qdd)
        M = mass_matrix(robot, q)
    finally:
        armkit.set_num_threads(None)
    for k in (0, 12_345, 19_999):
        np.testing.assert_array_equal(tau[k], inverse_dynamics(robot, q[k], qd[k], qdd[k]))
        np.testing.assert_array_equal(M[k], mass_matrix(robot, q[k]))


def test_mimic_chain_is_the_coupled_system():
    """A chain through a mimic joint: torques are the leader's share of both joints, and the
    mass matrix the uncoupled one reduced through the coupling."""
    robot = mimic_robot()
    assert robot.chain.coupled
    q = np.random.default_rng(0).uniform(*robot.chain.sampling_limits)
    M = mass_matrix(robot, q)
    assert np.linalg.eigvalsh(M)[0] > 0
    qd = np.linspace(-1, 1, robot.n)
    tau = inverse_dynamics(robot, q, qd, qd)
    np.testing.assert_allclose(forward_dynamics(robot, q, qd, tau), qd, atol=1e-8)


def test_robot_without_inertias_is_a_clear_error():
    robot = armkit.robot("stanford")
    assert robot.inertia is None
    for call in (lambda: inverse_dynamics(robot, np.zeros(6), np.zeros(6), np.zeros(6)),
                 lambda: mass_matrix(robot, np.zeros(6)),
                 lambda: gravity_torques(robot, np.zeros(6)),
                 lambda: forward_dynamics(robot, np.zeros(6), np.zeros(6), np.zeros(6)),
                 lambda: coriolis_matrix(robot, np.zeros(6), np.zeros(6)),
                 lambda: with_payload(robot, 1.0)):
        with pytest.raises(InputError, match="robot stanford: expected inertial parameters"):
            call()


@pytest.mark.parametrize("bad, message", [
    (dict(q=np.zeros(5)), "q: expected last axis 6"),
    (dict(qd=[0, 0, 0, 0, 0, np.nan]), "qd: expected finite"),
    (dict(qdd=np.full(6, np.inf)), "qdd: expected finite"),
    (dict(q=np.zeros((2, 6)), qd=np.zeros((3, 6))), "expected shapes that broadcast"),
    (dict(qdd="abc"), "qdd: expected real joint values"),
])
def test_bad_arrays_are_named(bad, message):
    args = dict(q=np.zeros(6), qd=np.zeros(6), qdd=np.zeros(6)) | bad
    with pytest.raises(InputError, match=message):
        inverse_dynamics(ROBOTS["ur5"], **args)


def test_a_joint_moving_no_mass_is_refused_by_forward_dynamics():
    robot = ROBOTS["ur5"]
    links = list(robot.inertia.links)
    links[-1] = Inertia(0.0)
    hollow = dataclasses.replace(robot, inertia=dataclasses.replace(robot.inertia,
                                                                    links=links))
    with pytest.raises(InputError, match="mass matrix is positive definite"):
        forward_dynamics(hollow, np.zeros(6), np.zeros(6), np.zeros(6))


@pytest.mark.parametrize("tensor, message", [
    (np.diag([1.0, -1.0, 1.0]), "principal moments >= 0"),
    ([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "symmetric"),
    (np.full((3, 3), np.nan), "finite"),
])
def test_unphysical_inertias_are_refused(tensor, message):
    with pytest.raises(InputError, match=message):
        Inertia(1.0, [0, 0, 0], tensor)
    with pytest.raises(InputError, match="mass"):
        Inertia(-1.0)


@settings(max_examples=30)
@given(st.floats(0.1, 10), st.floats(0.01, 2), st.floats(0, 0.2))
def test_tube_and_rod_are_the_textbook_bodies(mass, length, radius):
    rod = Inertia.rod(mass, length, radius, axis=[0, 0, 1])
    assert np.allclose(rod.com, [0, 0, length / 2])
    np.testing.assert_allclose(np.diag(rod.tensor), [mass * (3 * radius**2 + length**2) / 12] * 2
                               + [mass * radius**2 / 2], rtol=1e-12, atol=1e-15 * mass * length**2)
    tube = Inertia.tube(mass, [0, 0, 0], [0, 0, length], radius + 0.01, radius)
    assert tube.tensor[2, 2] == pytest.approx(mass * ((radius + 0.01)**2 + radius**2) / 2)
