"""The tool's motion along a joint trajectory against finite differences of forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.trajectory import Samples, spline, tool_motion


def table1_motion():
    robot = armkit.robot("tool_changer_6dof")
    q = np.zeros((4, 6))
    q[:, [1, 2, 4]] = [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    q[:, 3] = [0, 200, 400, 300]                        # the telescope moves too (mm)
    return robot, spline([0, 2, 4, 5], robot.q_to_si(q), "5-5-5")


def test_velocity_and_acceleration_are_derivatives_of_the_tool_path():
    robot, tr = table1_motion()
    h = 1e-5
    t = np.linspace(0.1, 4.9, 25)
    m = tool_motion(robot, tr, t)
    p = lambda s: armkit.fk(robot, tr.evaluate(s))[..., :3, 3]        # noqa: E731
    np.testing.assert_allclose(m.velocity[:, :3], (p(t + h) - p(t - h)) / (2 * h), atol=1e-8)
    v = lambda s: tool_motion(robot, tr, s).velocity                   # noqa: E731
    np.testing.assert_allclose(m.acceleration, (v(t + h) - v(t - h)) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(m.position, p(t), atol=1e-15)
    assert m.speed.shape == (25,) and m.path_length > 0


def test_samples_and_rest_at_the_ends():
    robot, tr = table1_motion()
    m = tool_motion(robot, tr.sample([0.0, 5.0]))
    np.testing.assert_allclose(m.velocity, 0.0, atol=1e-15)
    np.testing.assert_allclose(m.acceleration, 0.0, atol=1e-14)
    assert tool_motion(robot, tr, count=7).t.shape == (7,)


def test_the_motion_must_cover_every_joint():
    robot, tr = table1_motion()
    s = tr.sample([0.0, 1.0])
    with pytest.raises(InputError, match="motion: expected 6 joints"):
        tool_motion(robot, Samples(s.t, s.q[:, :3], s.qd[:, :3], s.qdd[:, :3], s.qddd[:, :3]))
