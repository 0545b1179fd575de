"""spatial.py: group laws (hypothesis), conventions against scipy and by hand, batch shapes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from armkit import jit
from armkit import spatial as sp
from armkit.errors import InputError

finite = st.floats(-10, 10, allow_nan=False)
vec3 = arrays(float, 3, elements=finite)
angles = st.floats(-np.pi, np.pi)


@st.composite
def transforms(draw):
    quat = draw(arrays(float, 4, elements=st.floats(-1, 1)).filter(
        lambda q: np.linalg.norm(q) > 0.1))
    return sp.transform(sp.quat_to_matrix(quat / np.linalg.norm(quat)), draw(vec3))


def test_axis_rotations_match_scipy():
    a = np.linspace(-3, 3, 7)
    for f, axis in ((sp.rotx, "x"), (sp.roty, "y"), (sp.rotz, "z")):
        np.testing.assert_allclose(f(a), Rotation.from_euler(axis, a[:, None]).as_matrix(), atol=1e-15)


def test_rpy_is_z_then_y_then_x_fixed_axes():
    r, p, y = 0.3, -0.7, 1.9
    expected = sp.rotz(y) @ sp.roty(p) @ sp.rotx(r)
    np.testing.assert_allclose(sp.rpy_to_matrix([r, p, y]), expected, atol=1e-15)
    np.testing.assert_allclose(sp.matrix_to_rpy(expected), [r, p, y], atol=1e-14)
    np.testing.assert_allclose(sp.rpy_to_matrix([30, 0, 0], degrees=True), sp.rotx(np.pi / 6),
                               atol=1e-15)


def test_rpy_matches_scipy_and_rebuilds_the_rotation_better():
    R = Rotation.random(20_000, random_state=3).as_matrix()
    ours = sp.matrix_to_rpy(R)
    theirs = Rotation.from_matrix(R).as_euler("xyz")
    wrapped = (ours - theirs + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(wrapped).max() < 1e-13
    assert np.abs(sp.rpy_to_matrix(ours) - R).max() <= np.abs(sp.rpy_to_matrix(theirs) - R).max()
    assert np.abs(sp.rpy_to_matrix(ours) - R).max() < 1e-15


@pytest.mark.parametrize("sign", [1, -1])
def test_rpy_at_gimbal_lock_sets_yaw_to_zero_as_scipy_does(sign):
    rng = np.random.default_rng(5)
    rpy = np.column_stack([rng.uniform(-3, 3, 500), np.full(500, sign * np.pi / 2),
                           rng.uniform(-3, 3, 500)])
    R = sp.rpy_to_matrix(rpy)
    ours = sp.matrix_to_rpy(R)
    # numba's compiler records warnings through the process-wide warnings module (not
    # thread-safe): while armkit's background thread compiles, another thread's warnings
    # can go to numba's record instead. Nothing compiles during the check below.
    jit.wait_for_background()
    with pytest.warns(UserWarning, match="Gimbal lock"):
        theirs = Rotation.from_matrix(R).as_euler("xyz")
    assert np.all(ours[:, 2] == 0.0)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sp.rpy_to_matrix(ours), R, rtol=0, atol=1e-15)


@given(st.floats(-np.pi, np.pi), st.floats(-np.pi / 2, np.pi / 2), st.floats(-np.pi, np.pi))
@example(0.3, np.pi / 2 - 2e-7, -1.2)          # just outside the lock: ill-conditioned angles
def test_rpy_rebuilds_any_rotation_outside_the_lock(r, p, y):
    R = sp.rpy_to_matrix([r, p, y])
    rebuilt = sp.rpy_to_matrix(sp.matrix_to_rpy(R))
    # Inside the lock yaw is dropped, which moves R by about twice the pitch's distance to it.
    allowed = 2e-15 if np.cos(p) > sp.GIMBAL_LOCK else 2e-15 + 2.5 * np.cos(p)
    assert np.abs(rebuilt - R).max() <= allowed


@given(transforms())
def test_inverse_is_inverse(T):
    np.testing.assert_allclose(T @ sp.invert(T), np.eye(4), atol=1e-12)


@given(transforms())
def test_exp_of_log_is_identity(T):
    np.testing.assert_allclose(sp.exp_se3(sp.log_se3(T)), T, atol=1e-10)


@given(vec3, arrays(float, 3, elements=st.floats(-1, 1)), st.floats(0, np.pi - 1e-6))
@example(np.array([0.0, 3.0, 3.0]), np.ones(3), 1e-4)     # 1 - cos t once lost 8 digits here
def test_log_of_exp_is_identity(v, axis, angle):
    w = axis / np.linalg.norm(axis) * angle if np.linalg.norm(axis) > 1e-3 else np.zeros(3)
    xi = np.r_[v, w]
    np.testing.assert_allclose(sp.log_se3(sp.exp_se3(xi)), xi, atol=1e-8)


def test_exp_near_zero_and_near_pi():
    tiny = np.array([0.1, 0.2, 0.3, 1e-9, -2e-9, 0.5e-9])
    T = sp.exp_se3(tiny)
    np.testing.assert_allclose(T[:3, 3], tiny[:3], atol=1e-12)
    half_turn = np.array([0.0, 0.0, 0.0, np.pi, 0.0, 0.0])
    np.testing.assert_allclose(sp.exp_se3(half_turn)[:3, :3], np.diag([1, -1, -1]), atol=1e-15)
    np.testing.assert_allclose(np.abs(sp.log_se3(sp.exp_se3(half_turn))), np.abs(half_turn),
                               atol=1e-12)


def test_screw_motion_by_hand():
    # A quarter turn about z through p = (1, 0, 0): the screw (v, w) = (-w x p, w) = (0, -1, 0, 0, 0, 1);
    # the origin, at -1 along x from p, swings to -1 along y from p.
    T = sp.exp_se3(np.array([0.0, -1.0, 0.0, 0.0, 0.0, 1.0]) * np.pi / 2)
    np.testing.assert_allclose(T[:3, 3], [1.0, -1.0, 0.0], atol=1e-15)


@given(transforms(), vec3, vec3)
def test_adjoint_conjugates_twists(T, v, w):
    xi = np.r_[v, w] * 0.1
    np.testing.assert_allclose(T @ sp.exp_se3(xi) @ sp.invert(T),
                               sp.exp_se3(sp.adjoint(T) @ xi), atol=1e-10)


@given(arrays(float, 4, elements=st.floats(-1, 1)).filter(lambda q: np.linalg.norm(q) > 0.1))
def test_quaternion_round_trip_up_to_sign(q):
    q = q / np.linalg.norm(q)
    back = sp.matrix_to_quat(sp.quat_to_matrix(q))
    assert min(np.abs(back - q).max(), np.abs(back + q).max()) < 1e-12
    assert back[3] >= 0


def test_rotation_angle_keeps_small_angles():
    for angle in (1e-12, 1e-9, 1e-5, 1.0, np.pi - 1e-9, np.pi):
        assert sp.rotation_angle(sp.rotx(angle)) == pytest.approx(angle, rel=1e-6, abs=1e-15)


def test_pose_error_by_hand():
    A = sp.transform(sp.rotz(0.2), [1.0, 2.0, 3.0])
    B = sp.transform(sp.rotz(0.5), [1.0, 2.0, 3.003])
    dp, dr = sp.pose_error(A, B)
    assert dp == pytest.approx(0.003) and dr == pytest.approx(0.3)


@pytest.mark.parametrize("lead", [(), (5,), (2, 3)])
def test_batch_shapes_match_single_calls(lead):
    rng = np.random.default_rng(0)
    xi = rng.normal(size=lead + (6,)) * 0.5
    T = sp.exp_se3(xi)
    assert T.shape == lead + (4, 4)
    flat_xi, flat_T = xi.reshape(-1, 6), T.reshape(-1, 4, 4)
    for k in range(flat_xi.shape[0]):
        np.testing.assert_allclose(sp.exp_se3(flat_xi[k]), flat_T[k], atol=1e-15)
    assert sp.log_se3(T).shape == lead + (6,)
    assert sp.matrix_to_rpy(T[..., :3, :3]).shape == lead + (3,)
    assert sp.adjoint(T).shape == lead + (6, 6)
    assert sp.pose_error(T, T)[0].shape == lead


def test_checks_say_what_was_expected_and_found():
    with pytest.raises(InputError, match=r"T: expected shape \(\.\.\., 4, 4\), found \(3, 3\)"):
        sp.as_transform(np.eye(3))
    with pytest.raises(InputError, match="orthonormal"):
        sp.as_transform(np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(InputError, match="finite"):
        sp.as_transform(np.full((4, 4), np.nan))
