"""Workspace pictures: four panels and two sections, axes in the robot file's units."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.model import SI
from armkit.report.workspace import default_height, section_figure, workspace_figure


@pytest.fixture(scope="module")
def ws() -> armkit.Workspace:
    return armkit.workspace(armkit.robot("inspection_6dof"), 20_000, cloud=2_000)


def test_cloud_and_projections_in_millimetres(ws):
    fig = workspace_figure(ws)
    cloud, *projections = fig.axes
    assert [cloud.get_xlabel(), cloud.get_ylabel(), cloud.get_zlabel()] == [
        "x (mm)", "y (mm)", "z (mm)"]
    assert [(a.get_xlabel(), a.get_ylabel()) for a in projections] == [
        ("x (mm)", "y (mm)"), ("x (mm)", "z (mm)"), ("y (mm)", "z (mm)")]
    xy = projections[0].collections[0].get_offsets()
    np.testing.assert_allclose(xy, ws.cloud[:, :2] * 1000)
    assert all(a.get_aspect() == 1.0 for a in projections)
    assert "20,000 samples (showing 2,000)" in fig.get_suptitle()


def test_sections_titled_with_their_areas(ws):
    z = default_height(ws)
    assert z == pytest.approx(0.075)          # the 50 .. 100 mm layer, around mid-height
    fig = section_figure(ws, units=SI)
    level, upright = fig.axes
    assert level.get_xlabel() == "x (m)" and upright.get_ylabel() == "z (m)"
    assert f"occupied area {ws.horizontal_section(z).area:.4g} m\u00b2" in level.get_title()
    assert "azimuth 0 rad" in upright.get_title()
    image = level.get_images()[0]
    np.testing.assert_array_equal(image.get_array(), ws.horizontal_section(z).occupied)


def test_projections_draw_the_reach_and_name_each_mark(ws):
    fig = workspace_figure(ws)
    _, *projections = fig.axes
    radii = [a.patches[0].get_radius() for a in projections]
    assert radii == pytest.approx([ws.radial_reach * 1000, ws.reach * 1000, ws.reach * 1000])
    # Every sample lies inside its reach circle: the bound is drawn where it holds.
    assert np.hypot(*(ws.cloud[:, :2].T * 1000)).max() <= radii[0] * (1 + 1e-12)
    labels = [[t.get_text() for t in a.get_legend().get_texts()] for a in projections]
    assert labels[0] == ["tool positions", "base origin", "reach from the z axis"]
    assert labels[1] == labels[2] == ["tool positions", "base origin", "reach"]
    level, upright = section_figure(ws).axes
    assert [t.get_text() for t in level.get_legend().get_texts()] == [
        "base origin", "occupied 50 mm cell"]
