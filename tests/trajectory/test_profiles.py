"""Trapezoidal and jerk-limited profiles: goal reached, limits kept, joints synchronised, and
durations (and positions) equal to ruckig's for the same limits."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import ruckig
from hypothesis import given
from hypothesis import strategies as st

import armkit
from armkit.errors import InputError
from armkit.trajectory import (jerk_limited, jerk_limited_profile, trapezoidal,
                               trapezoidal_profile)

RTOL = 1e-9          # limits and goal, relative


def ruckig_trajectory(q0, qf, vmax, amax, jmax):
    n = len(q0)
    inp = ruckig.InputParameter(n)
    inp.current_position, inp.target_position = list(q0), list(qf)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = (list(np.broadcast_to(x, n))
                                                            for x in (vmax, amax, jmax))
    out = ruckig.Trajectory(n)
    assert ruckig.Ruckig(n).calculate(inp, out) == ruckig.Result.Working
    return out


def check_motion(tr, q0, qf, vmax, amax, jmax=np.inf):
    """Starts and ends at rest at q0 and qf, within every limit, on a dense sample."""
    s = tr.sample(np.r_[np.linspace(tr.start, tr.end, 20001), tr.breaks])
    ends = tr.sample([tr.start, tr.end])
    scale = 1.0 + np.abs(qf - q0).max()
    np.testing.assert_allclose(ends.q, [q0, qf], atol=1e-12 * scale)
    np.testing.assert_allclose(ends.qd, 0.0, atol=1e-12 * scale)
    assert (np.abs(s.qd) <= np.broadcast_to(vmax, q0.shape) * (1 + RTOL)).all()
    assert (np.abs(s.qdd) <= np.broadcast_to(amax, q0.shape) * (1 + RTOL)).all()
    if np.isfinite(jmax).all():
        np.testing.assert_allclose(ends.qdd, 0.0, atol=1e-12 * scale)
        assert (np.abs(s.qddd) <= np.broadcast_to(jmax, q0.shape) * (1 + RTOL)).all()


def random_case(seed: int, n: int = 6):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(0.2, 2.0, n),
            rng.uniform(0.5, 5.0, n), rng.uniform(1.0, 50.0, n))


def test_jerk_limited_durations_equal_ruckigs():
    rng = np.random.default_rng(0)
    q0, qf = rng.uniform(-3, 3, (300, 6)), rng.uniform(-3, 3, (300, 6))
    for k in range(3):                                 # the limits vary, and with them the cases
        _, _, vmax, amax, jmax = random_case(k)
        ours = jerk_limited_profile(q0, qf, vmax, amax, jmax).duration
        theirs = [ruckig_trajectory(a, b, vmax, amax, jmax).duration for a, b in zip(q0, qf)]
        np.testing.assert_allclose(ours, theirs, rtol=1e-9)       # target: 0.1 %


@pytest.mark.parametrize("seed", range(4))
def test_jerk_limited_motion_matches_ruckig_and_keeps_limits(seed):
    q0, qf, vmax, amax, jmax = random_case(seed)
    tr = jerk_limited(q0, qf, vmax, amax, jmax)
    reference = ruckig_trajectory(q0, qf, vmax, amax, jmax)
    assert tr.duration == pytest.approx(reference.duration, rel=1e-9)
    t = np.linspace(0, tr.duration, 37)
    theirs = np.array([reference.at_time(x)[0] for x in t])
    np.testing.assert_allclose(tr.evaluate(t), theirs, atol=1e-9)
    check_motion(tr, q0, qf, vmax, amax, jmax)


@pytest.mark.parametrize("D, phases", [
    (10.0, 7),          # every limit reached: jerk, constant acceleration, cruise
    (0.4, 6),           # vmax not reached: no cruise
    (0.01, 4),          # neither vmax nor amax: jerk phases only
])
def test_double_s_drops_the_segments_it_does_not_need(D, phases):
    tr = jerk_limited([0.0], [D], 1.0, 2.0, 10.0)
    assert len(tr.breaks) - 1 == phases
    reference = ruckig_trajectory([0.0], [D], 1.0, 2.0, 10.0)
    assert tr.duration == pytest.approx(reference.duration, rel=1e-12)


def test_trapezoid_closed_form_and_triangle_when_short():
    tr = trapezoidal([0.0], [5.0], 1.0, 2.0)
    assert tr.duration == pytest.approx(5.0 / 1.0 + 1.0 / 2.0, rel=1e-14)
    tri = trapezoidal([0.0], [0.3], 1.0, 2.0)
    assert tri.duration == pytest.approx(2 * np.sqrt(0.3 / 2.0), rel=1e-14)
    assert len(tri.breaks) == 3                              # accelerate, decelerate
    assert np.abs(tri.sample_uniform(1001).qd).max() < 1.0   # never reaches vmax


@pytest.mark.parametrize("seed", range(4))
def test_trapezoid_time_sync_keeps_limits_and_ends_together(seed):
    q0, qf, vmax, amax, _ = random_case(seed)
    tr = trapezoidal(q0, qf, vmax, amax)
    D = np.abs(qf - q0)
    own = np.where(D * amax >= vmax**2, D / vmax + vmax / amax, 2 * np.sqrt(D / amax))
    assert tr.duration == pytest.approx(own.max(), rel=1e-12)       # the slowest joint's
    check_motion(tr, q0, qf, vmax, amax)


@pytest.mark.parametrize("build", [lambda *a: trapezoidal(*a[:4], sync="phase"),
                                   lambda *a: jerk_limited(*a, sync="phase")])
def test_phase_sync_is_a_straight_line_in_joint_space(build):
    q0, qf, vmax, amax, jmax = random_case(7)
    tr = build(q0, qf, vmax, amax, jmax)
    s = tr.sample_uniform(501)
    progress = (s.q - q0) / (qf - q0)                      # the same fraction for every joint
    np.testing.assert_allclose(progress, np.broadcast_to(progress[:, :1], progress.shape),
                               atol=1e-12)
    check_motion(tr, q0, qf, vmax, amax, jmax if tr.label == "jerk-limited" else np.inf)
    time_sync = (jerk_limited(q0, qf, vmax, amax, jmax) if tr.label == "jerk-limited"
                 else trapezoidal(q0, qf, vmax, amax))
    assert tr.duration >= time_sync.duration * (1 - 1e-12)


def test_profiles_are_batch_first():
    rng = np.random.default_rng(4)
    q0, qf = rng.uniform(-1, 1, (2, 3, 4)), rng.uniform(-1, 1, (2, 3, 4))
    p = jerk_limited_profile(q0, qf, 1.0, 2.0, [5, 6, 7, 8])
    assert p.duration.shape == (2, 3) and p.times.shape == (2, 3, 4, 8)
    for index in np.ndindex(2, 3):
        one = jerk_limited_profile(q0[index], qf[index], 1.0, 2.0, [5, 6, 7, 8])
        np.testing.assert_array_equal(p.times[index], one.times)
    v, a, j = p.peaks()
    assert (v <= 1 + 1e-12).all() and (a <= 2 + 1e-12).all()
    assert (j <= np.r_[5, 6, 7, 8] * (1 + 1e-12)).all()
    assert trapezoidal_profile(q0, qf, 1.0, 2.0).times.shape == (2, 3, 4, 4)


def test_a_joint_that_does_not_move_stays_put():
    tr = jerk_limited([0.0, 1.0], [2.0, 1.0], 1.0, 1.0, 1.0)
    np.testing.assert_array_equal(tr.sample_uniform(100).q[:, 1], 1.0)


@pytest.mark.parametrize("build", [
    lambda q: trapezoidal(q, q, 1.0, 2.0), lambda q: jerk_limited(q, q, 1.0, 2.0, 5.0),
    lambda q: armkit.cubic(q, q), lambda q: armkit.quintic(q, q, vmax=1.0),
    lambda q: trapezoidal(q, q, 1.0, 2.0, sync="phase"),
])
def test_a_goal_equal_to_the_start_is_a_motion_of_zero_duration(build):
    q = np.array([0.5, -1.0, 2.0])
    tr = build(q)
    assert tr.duration == 0.0 and tr.start == tr.end == 0.0
    s = tr.sample([0.0])
    np.testing.assert_array_equal(s.q, [q])
    np.testing.assert_array_equal(np.r_[s.qd, s.qdd, s.qddd], 0.0)


@pytest.mark.parametrize("profile", ["trapezoidal", "jerk"])
def test_a_row_without_motion_does_not_spoil_its_batch(profile):
    q0 = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 3.0]])
    qf = np.array([[0.0, 0.0], [2.0, 0.0], [3.0, 3.0]])
    if profile == "trapezoidal":
        batch, one = trapezoidal_profile(q0, qf, 1.0, 2.0), trapezoidal_profile(q0[1], qf[1],
                                                                                1.0, 2.0)
    else:
        batch = jerk_limited_profile(q0, qf, 1.0, 2.0, 5.0)
        one = jerk_limited_profile(q0[1], qf[1], 1.0, 2.0, 5.0)
    np.testing.assert_array_equal(batch.duration, [0.0, one.duration, 0.0])
    np.testing.assert_array_equal(batch.times[1], one.times)
    np.testing.assert_array_equal(batch.values[[0, 2]], 0.0)


@pytest.mark.parametrize("call, words", [
    (lambda: jerk_limited([0.0], [1.0], 1.0, 1.0, np.inf), "jmax: expected positive finite"),
    (lambda: trapezoidal([0.0], [1.0], 1.0, -1.0), "amax: expected positive finite"),
    (lambda: trapezoidal([0.0, 1.0], [1.0, 1.0], [1.0, 2.0, 3.0], 1.0), "broadcast"),
    (lambda: trapezoidal(np.zeros((2, 2)), np.ones((2, 2)), 1.0, 1.0), "_profile functions"),
    (lambda: trapezoidal([0.0], [1.0], 1.0, 1.0, sync="space"), "sync: expected"),
])
def test_bad_input(call, words):
    with pytest.raises(InputError, match=words):
        call()


limits = st.floats(0.05, 20.0)


@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), limits, limits, limits),
                min_size=1, max_size=4),
       st.sampled_from(["time", "phase"]))
def test_limits_and_goal_hold_for_random_cases(joints, sync):
    q0, qf, vmax, amax, jmax = (np.array(x) for x in zip(*joints))
    if np.abs(qf - q0).max() < 1e-6:
        return
    check_motion(jerk_limited(q0, qf, vmax, amax, jmax, sync=sync), q0, qf, vmax, amax, jmax)
    check_motion(trapezoidal(q0, qf, vmax, amax, sync=sync), q0, qf, vmax, amax)


@pytest.mark.parametrize("limits", [
    (1.0, 2.0, 10.0),                                               # numbers: no arrays made
    (1, 2, 10),                                                     # ints
    (np.float64(1.0), np.array(2.0), [10.0]),                       # NumPy scalar, 0-d, (1,)
    ([0.5, 1, 2, 0.7], np.r_[1.0, 2, 3, 4], np.arange(10, 50, 10)),  # list, floats, ints
    (np.linspace(0.5, 2, 8)[::2], 2.0, np.array([5.0, 6, 7, 8], dtype=np.float32)),  # strided
])
@pytest.mark.parametrize("sync", ["time", "phase"])
def test_one_problem_equals_the_same_problem_as_a_batch(limits, sync):
    rng = np.random.default_rng(5)
    q0, qf = rng.uniform(-2, 2, 4), rng.uniform(-2, 2, 4)
    qf[2] = q0[2]                                   # a joint that does not move
    for single, batch in ((jerk_limited_profile, jerk_limited_profile),
                          (trapezoidal_profile, trapezoidal_profile)):
        args = limits if single is jerk_limited_profile else limits[:2]
        one = single(list(q0), qf, *args, sync=sync)
        many = batch(q0[None], qf, *(np.broadcast_to(np.asarray(x, float), (1, 4))
                                      for x in args), sync=sync)
        assert type(one.duration) is np.float64 and one.times.shape == many.times.shape[1:]
        assert one.duration == many.duration[0]
        for name in ("times", "values", "q0", "qf"):
            np.testing.assert_array_equal(getattr(one, name), getattr(many, name)[0])


def test_a_single_profile_owns_its_arrays_and_is_frozen():
    q0, qf = np.zeros(3), np.array([1.0, -2.0, 0.5])
    p = jerk_limited_profile(q0, qf, 1.0, 2.0, 10.0)
    q0[:], qf[:] = 7.0, 7.0                         # the caller reuses its buffers
    np.testing.assert_array_equal(p.q0, 0.0)
    np.testing.assert_array_equal(p.qf, [1.0, -2.0, 0.5])
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.duration = 1.0
    same = dataclasses.replace(p)
    assert same.duration == p.duration and same.times is p.times and same.order == 3
    assert [f.name for f in dataclasses.fields(p)] == ["duration", "times", "values", "order",
                                                       "q0", "qf"]


def test_shapes_of_no_single_problem_take_the_general_way():
    q0, qf = np.zeros(3), np.ones(3)
    p = jerk_limited_profile(q0, qf, np.array([[1.0], [2.0]]), 2.0, 10.0)    # two problems
    assert p.duration.shape == (2,) and p.duration[0] > p.duration[1]
    p = jerk_limited_profile(q0, np.ones((2, 3)), 1.0, 2.0, 10.0)
    assert p.times.shape == (2, 3, 8)
    with pytest.raises(InputError, match="broadcast"):
        jerk_limited_profile(q0, qf, [1.0, 2.0], 2.0, 10.0)
    with pytest.raises(InputError, match="n >= 1 joints"):
        jerk_limited_profile([], [], 1.0, 2.0, 10.0)
    with pytest.raises(InputError, match="one problem"):
        jerk_limited(q0, qf, np.ones((2, 3)), 2.0, 10.0)


def test_bad_limits_of_one_problem_are_named_with_their_values():
    with pytest.raises(InputError, match=r"amax: expected positive limits, found \[-2.0, 1.0\]"):
        jerk_limited_profile([0.0, 0.0], [1.0, 1.0], 1.0, np.array([1.0, -2.0]), 10.0)
    with pytest.raises(InputError, match=r"vmax: expected positive limits, found \[0.0\]"):
        trapezoidal([0.0], [1.0], 0, 1.0)
    with pytest.raises(InputError, match="finite joint values"):
        jerk_limited([0.0, np.nan], [1.0, 1.0], 1.0, 1.0, 1.0)


@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), limits,
                          st.one_of(limits, st.just(np.inf)), limits), min_size=1, max_size=4),
       st.sampled_from(["time", "phase"]), st.booleans())
def test_kernel_pieces_pass_the_trajectory_checks_they_skip(joints, sync, vmax_inf):
    """jerk_limited builds its Trajectory with check=False: its breaks and coefficients must
    pass the checks all the same, also with infinite vmax or amax."""
    q0, qf, vmax, amax, jmax = (np.array(x) for x in zip(*joints))
    tr = jerk_limited(q0, qf, np.inf if vmax_inf else vmax, amax, jmax, sync=sync)
    armkit.Trajectory(tr.breaks, tr.coefficients)          # checked: does not raise
    assert np.isfinite(tr.coefficients).all() and tr.duration >= 0.0
    tr = trapezoidal(q0, qf, vmax, np.where(np.isinf(amax), 3.0, amax), sync=sync)
    armkit.Trajectory(tr.breaks, tr.coefficients)


def test_trajectory_check_false_skips_the_value_checks_not_the_shapes():
    breaks, c = np.array([0.0, 2.0, 1.0]), np.zeros((2, 2, 1))
    with pytest.raises(InputError, match="strictly increasing"):
        armkit.Trajectory(breaks, c)
    with pytest.raises(InputError, match="finite"):
        armkit.Trajectory([0.0, 1.0], np.full((1, 2, 1), np.nan))
    assert armkit.Trajectory(breaks, c, check=False).breaks.tolist() == [0.0, 2.0, 1.0]
    with pytest.raises(InputError, match="coefficients: expected shape"):
        armkit.Trajectory(breaks, np.zeros((3, 2, 1)), check=False)


def test_every_kind_of_limit_takes_the_same_compiled_kernel(monkeypatch):
    """A Robot's limits are read-only arrays, which numba types apart from writable ones: they
    must not make it compile the timing kernel again (seconds on a first call)."""
    from armkit import jit
    from armkit.trajectory import _kernels
    monkeypatch.setattr(jit, "mode", "compiled")           # every call compiled, as in a batch
    robot = armkit.robot("inspection_6dof")            # finite velocity and acceleration limits
    q0, qf = np.zeros(6), np.full(6, 0.5)
    jerk_limited_profile(q0, qf, 1.0, 2.0, 10.0)
    compiled = set(_kernels.profile_timing.dispatcher.signatures)
    frozen = np.full(6, 10.0)
    frozen.setflags(write=False)
    for limits in [(robot.velocity_limits, robot.acceleration_limits, 10.0),
                   (robot.velocity_limits, 2, frozen), ([1.0] * 6, np.float32(2.0), frozen[:1]),
                   (np.full(12, 1.0)[::2], robot.acceleration_limits, np.int64(10))]:
        jerk_limited(q0, qf, *limits)
        trapezoidal(q0, qf, *limits[:2], sync="phase")
        jerk_limited_profile(np.zeros((3, 6)), qf, *limits)
    assert set(_kernels.profile_timing.dispatcher.signatures) == compiled
