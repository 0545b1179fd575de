"""Point-to-point cubic and quintic: the closed forms, end conditions, durations from limits."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.errors import InputError
from armkit.trajectory import cubic, quintic

Q0 = np.deg2rad([0.0, 10.0, -20.0, 0.0, 45.0, 5.0])
QF = np.deg2rad([30.0, -45.0, 60.0, 0.0, 90.0, -5.0])


def test_quintic_is_the_10_15_6_law_of_paper_3():
    T = 10.0                                           # the inspection-robot paper's T
    tr = quintic(Q0, QF, T)
    t = np.linspace(0, T, 1001)
    s, D = (t / T)[:, None], QF - Q0
    sample = tr.sample(t)
    np.testing.assert_allclose(sample.q, Q0 + D * (10 * s**3 - 15 * s**4 + 6 * s**5), atol=1e-14)
    np.testing.assert_allclose(sample.qd, D * (30 * s**2 - 60 * s**3 + 30 * s**4) / T,
                               atol=1e-14)
    np.testing.assert_allclose(sample.qdd, D * (60 * s - 180 * s**2 + 120 * s**3) / T**2,
                               atol=1e-14)
    np.testing.assert_allclose(sample.qddd, D * (60 - 360 * s + 360 * s**2) / T**3, atol=1e-14)
    assert tr.label == "quintic" and tr.duration == T


def test_cubic_closed_form_and_end_velocities():
    tr = cubic(Q0, QF, 4.0)
    t = np.linspace(0, 4, 101)
    s = (t / 4)[:, None]
    np.testing.assert_allclose(tr.evaluate(t), Q0 + (QF - Q0) * (3 * s**2 - 2 * s**3),
                               atol=1e-14)
    moving = cubic(Q0, QF, 4.0, start_velocity=0.1, end_velocity=-0.2)
    end = moving.sample([0.0, 4.0])
    np.testing.assert_allclose(end.q, [Q0, QF], atol=1e-14)
    np.testing.assert_allclose(end.qd, [np.full(6, 0.1), np.full(6, -0.2)], atol=1e-14)


def test_quintic_meets_given_end_velocities_and_accelerations():
    tr = quintic(Q0, QF, 3.0, start_velocity=0.3, end_velocity=-0.1, start_acceleration=1.0,
                 end_acceleration=[0, 1, 2, 3, 4, 5])
    end = tr.sample([0.0, 3.0])
    np.testing.assert_allclose(end.q, [Q0, QF], atol=1e-14)
    np.testing.assert_allclose(end.qd, [np.full(6, 0.3), np.full(6, -0.1)], atol=1e-13)
    np.testing.assert_allclose(end.qdd, [np.ones(6), np.arange(6.0)], atol=1e-12)


@pytest.mark.parametrize("law, peak_v, peak_a", [(cubic, 1.5, 6.0),
                                                 (quintic, 1.875, 10 / np.sqrt(3))])
def test_shortest_duration_meets_the_tightest_limit(law, peak_v, peak_a):
    vmax, amax = np.full(6, 0.5), np.full(6, 20.0)          # velocity binds
    tr = law(Q0, QF, vmax=vmax, amax=amax)
    D = np.abs(QF - Q0)
    assert tr.duration == pytest.approx(np.max(peak_v * D / vmax), rel=1e-12)
    s = tr.sample_uniform(20001)
    assert (np.abs(s.qd).max(0) <= vmax * (1 + 1e-9)).all()
    assert np.max(np.abs(s.qd).max(0) / vmax) == pytest.approx(1.0, rel=1e-6)
    tight = law(Q0, QF, vmax=100.0, amax=0.5)                # acceleration binds
    assert tight.duration == pytest.approx(np.sqrt(peak_a * D.max() / 0.5), rel=1e-12)


def test_quintic_duration_from_a_jerk_limit():
    tr = quintic(Q0, QF, jmax=2.0)
    assert tr.duration == pytest.approx(np.cbrt(60 * np.abs(QF - Q0).max() / 2.0), rel=1e-12)


@pytest.mark.parametrize("call, words", [
    (lambda: quintic(Q0, QF), "duration: expected a duration, or limits"),
    (lambda: quintic(Q0, Q0, vmax=-1.0), "vmax: expected positive limits"),
    (lambda: quintic(Q0, QF, -1.0), "duration: expected a positive number"),
    (lambda: quintic(Q0, QF, start_velocity=1.0, vmax=1.0), "end velocity or acceleration"),
    (lambda: cubic(Q0, QF[:3], 1.0), "q0, qf: expected two arrays of shape"),
    (lambda: cubic(Q0, QF, vmax=-1.0), "vmax: expected positive limits"),
])
def test_bad_input(call, words):
    with pytest.raises(InputError, match=words):
        call()
