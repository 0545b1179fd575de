"""The 3-D views: `armkit.show` figures, and the page of `armkit view` in a real headless
Chromium, its joint sliders moved as a user moves them and the tool pose the page computes
compared with armkit's forward kinematics."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import plotly.graph_objects as go
import pytest

import armkit
from armkit.planning import Box, Scene, arm_geometry
from armkit.report.view import capsule_bodies, show, view_page
from tests.report.browser import Browser

SET_JOINTS = """(() => {{
  const values = {values};
  for (const s of document.querySelectorAll("input[data-joint]")) {{
    s.value = values[Number(s.dataset.joint)];
    s.dispatchEvent(new Event("input"));
  }}
  const out = document.getElementById("tool-pose");
  const arm = document.getElementById("view").data[0];
  const seen = [0, 1, 2, 3, 4].map((k) => Math.floor(k * (arm.x.length - 1) / 4));
  return [out.dataset.matrix, Array.from(document.querySelectorAll("input[data-joint]"),
                                         (s) => Number(s.value)),
          seen.map((v) => [arm.x[v], arm.y[v], arm.z[v]]), seen];
}})()"""


def _moved(page: Path, profile: Path, robot, count: int, seed: int):
    """Open the page, set every slider to `count` random configurations (file units) one after
    another; per configuration the values the sliders took and the page's tool pose; and
    checks five of the drawn arm's vertices against armkit's link frames."""
    bodies = capsule_bodies(arm_geometry(robot))
    scale = 1000.0 if robot.units.length == "mm" else 1.0
    rng = np.random.default_rng(seed)
    lo, hi = robot.chain.sampling_limits
    found = []
    with Browser(page.as_uri(), profile) as browser:
        browser.wait_for('document.getElementById("tool-pose")?.dataset.matrix')
        for q in rng.uniform(lo, hi, (count, robot.n)):
            wanted = robot.q_from_si(q)
            matrix, taken, drawn, which = browser.evaluate(SET_JOINTS.format(
                values=json.dumps(wanted.tolist())))
            frames = armkit.fk_frames(robot, robot.q_to_si(taken))[bodies.link[which]]
            local = bodies.vertices[which]
            expected = np.einsum("vij,vj->vi", frames[:, :3, :3], local) + frames[:, :3, 3]
            # float32 vertices in the page: a micrometre's precision is plenty for a picture
            np.testing.assert_allclose(np.array(drawn) / scale, expected, atol=2e-6)
            found.append((np.array(taken), np.array(json.loads(matrix)).reshape(4, 4)))
    return found


SLOW = ["panda", "tool_changer_6dof", "stanford", "puma560", "inspection_6dof", "modular_4dof"]


@pytest.mark.parametrize("name", ["ur5", "water_supply", *[
    pytest.param(name, marks=pytest.mark.slow) for name in SLOW]])
@pytest.mark.slow
def test_sliders_move_the_arm_as_armkit_fk(name, tmp_path):
    robot = armkit.robot(name)
    page = tmp_path / f"{name}.html"
    page.write_text(view_page(robot, np.clip(0.0, robot.lower, robot.upper)))
    for taken, T in _moved(page, tmp_path / "profile", robot, 5, seed=1):
        expected = armkit.fk(robot, robot.q_to_si(taken))
        assert np.abs(T[:3, 3] - expected[:3, 3]).max() <= 1e-9           # m
        assert np.abs(T[:3, :3] - expected[:3, :3]).max() <= 1e-9


def test_show_returns_a_figure_of_the_arm_and_of_a_motion():
    robot = armkit.robot("water_supply")
    q = robot.q_to_si([100, 30, -45, 10])
    fig = armkit.show(robot, q)
    assert isinstance(fig, go.Figure)
    names = [trace.name for trace in fig.data]
    assert "arm (collision capsules)" in names and "floor" in names
    # The figure's joint origins are armkit's link frames (mm, the robot's unit).
    skeleton = next(t for t in fig.data if t.name == "joint origins, base to tool")
    np.testing.assert_allclose(np.c_[skeleton.x, skeleton.y, skeleton.z],
                               armkit.fk_frames(robot, q)[:, :3, 3] * 1000, atol=1e-9)
    motion = armkit.quintic(q, robot.q_to_si([300, -20, 60, 0]), 2.0)
    played = armkit.show(robot, motion)
    assert len(played.frames) > 10 and played.layout.sliders
    path = next(t for t in played.data if t.name == "tool path")
    np.testing.assert_allclose([path.x[-1], path.y[-1], path.z[-1]],
                               armkit.fk(robot, motion.evaluate(2.0))[:3, 3] * 1000, atol=1e-9)


def test_names_from_files_reach_the_figure_as_text():
    robot = armkit.robot("ur5")
    scene = Scene([Box([0.1, 0.1, 0.1], np.eye(4), "<a href='http://x'>post</a> $x$")])
    fig = show(robot, np.zeros(6), scene=scene, title="<b>bold</b>")
    names = [trace.name for trace in fig.data]
    assert "&lt;a href=&#x27;http://x&#x27;&gt;post&lt;/a&gt; &#36;x&#36;" in names
    assert not any("<a" in (n or "") for n in names)
    assert fig.layout.title.text == "&lt;b&gt;bold&lt;/b&gt;"


def test_the_view_holds_the_floor_the_scene_and_every_frame():
    robot = armkit.robot("water_supply")
    scene = Scene([Box([0.2, 0.2, 1.4], np.eye(4), "post")])     # z from -0.7 to 0.7 m
    fig = show(robot, np.zeros(4), scene=scene)
    ranges = np.array([fig.layout.scene[f"{c}axis"].range for c in "xyz"])
    corners = np.array([[-100, -100, -700], [100, 100, 700]])     # mm
    points = np.vstack([armkit.fk_frames(robot, np.zeros(4))[:, :3, 3] * 1000, corners])
    assert ((points >= ranges[:, 0]) & (points <= ranges[:, 1])).all()
    floor = np.asarray(next(t for t in fig.data if t.name == "floor").z, float)
    np.testing.assert_allclose(floor[~np.isnan(floor)], -700)     # under everything
