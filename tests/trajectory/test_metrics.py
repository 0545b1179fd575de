"""Peaks, jumps at knots, integrated squared jerk, and the comparison of patterns."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from armkit.trajectory import (compare, jerk_limited, knot_jumps, patterns, peaks, quintic,
                               spline, squared_jerk, stats, trapezoidal)

T1 = np.array([0.0, 2.0, 4.0, 5.0])
Q1 = np.deg2rad([[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]])


def test_squared_jerk_against_quadrature():
    for pattern in ("3-3-3", "4-5-5", "5-5-5"):
        tr = spline(T1, Q1, pattern)
        for j in range(3):
            pieces = [quad(lambda t: tr.evaluate(t, 3)[j] ** 2, a, b, epsabs=1e-13)[0]
                      for a, b in zip(T1[:-1], T1[1:])]
            assert squared_jerk(tr)[j] == pytest.approx(sum(pieces), rel=1e-9)


def test_quintic_closed_form_effort_and_peaks():
    D, T = 2.0, 3.0
    tr = quintic([0.0], [D], T)
    # int_0^T (D/T^3 (60 - 360 s + 360 s^2))^2 dt = 720 D^2 / T^5
    assert squared_jerk(tr)[0] == pytest.approx(720 * D**2 / T**5, rel=1e-12)
    s = stats(tr)
    assert s.peak_velocity[0] == pytest.approx(1.875 * D / T, rel=1e-12)
    assert s.peak_acceleration[0] == pytest.approx(10 / np.sqrt(3) * D / T**2, rel=1e-12)
    assert s.peak_jerk[0] == pytest.approx(60 * D / T**3, rel=1e-12)
    assert s.duration == T and s.label == "quintic"


def test_peaks_of_profiles_are_their_limits():
    s = stats(jerk_limited([0.0], [10.0], 1.0, 2.0, 10.0))
    np.testing.assert_allclose([s.peak_velocity[0], s.peak_acceleration[0], s.peak_jerk[0]],
                               [1.0, 2.0, 10.0], rtol=1e-12)
    trap = stats(trapezoidal([0.0, 0.0], [3.0, -1.0], 1.0, 2.0))
    assert trap.peak_acceleration[0] == pytest.approx(2.0, rel=1e-12)
    np.testing.assert_allclose(trap.peak_jerk, 0.0)     # steps are not in the piecewise jerk


def test_sampled_peaks_agree_with_stats():
    tr = spline(T1, Q1, "4-5-5")
    dense = peaks(tr.sample(np.linspace(0, 5, 200_001)))
    exact = stats(tr)
    for sampled, found in zip(dense, (exact.peak_velocity, exact.peak_acceleration,
                                      exact.peak_jerk)):
        assert (sampled <= found * (1 + 1e-12)).all()
        np.testing.assert_allclose(sampled, found, rtol=1e-6)


def test_knot_jumps_take_the_arm_at_rest_outside():
    tr = spline(T1, Q1, "3-3-3")
    jumps = knot_jumps(tr)
    np.testing.assert_array_equal(jumps.t, T1)
    start, end = tr.sample([0.0, 5.0]).qdd
    np.testing.assert_allclose(jumps.jump[0, 2], start, atol=1e-15)
    np.testing.assert_allclose(jumps.jump[-1, 2], -end, atol=1e-15)
    np.testing.assert_allclose(jumps.jump[:, 0], 0.0, atol=1e-15)


def test_compare_the_papers_patterns():
    table = compare(patterns(T1, Q1))
    assert list(table) == ["3-3-3", "4-5-5", "5-5-5"]
    # Among the two that start and stop without an acceleration step, 5-5-5 (least jerk with
    # the most freedom) has the least integrated squared jerk.
    assert (table["5-5-5"].squared_jerk <= table["4-5-5"].squared_jerk).all()
    assert (table["3-3-3"].peak_acceleration > table["5-5-5"].peak_acceleration).all()
