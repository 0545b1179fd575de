"""Pictures of maps and placements: sections coloured by the index with its colour bar, the
3-D view offline, the placement's region with the chosen base, axes in the file's units."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armkit
from armkit.model import SI
from armkit.reach import base_placement, floor_grid, rail_grid, reach_map
from armkit.report.reach import (
    default_height,
    map_figure,
    map_view,
    placement_figure,
    save_map_figures,
    save_placement_figure,
)
from armkit.spatial import pose_from_xyz_rpy

WATER = armkit.robot("water_supply")


@pytest.fixture(scope="module")
def water_map():
    return reach_map(WATER, 0.1, 6)


def test_sections_are_coloured_by_the_index(water_map):
    m = water_map
    fig = map_figure(m)
    level, upright, bar = fig.axes
    assert (level.get_xlabel(), level.get_ylabel()) == ("x (mm)", "y (mm)")
    assert (upright.get_xlabel(), upright.get_ylabel()) == (
        "r (mm), signed distance from the z axis", "z (mm)")
    z = default_height(m)
    assert f"z = {z * 1000:.6g} mm" == level.get_title()
    shown = level.get_images()[0].get_array()
    expected = m.horizontal_section(z).index
    np.testing.assert_array_equal(shown.mask, np.isnan(expected))
    np.testing.assert_array_equal(shown.data[~shown.mask], expected[~np.isnan(expected)])
    assert bar.get_ylabel().startswith("reachability index: share of the 6 orientations")
    assert bar.get_ylim() == (0.0, 1.0)
    assert "100 mm voxels x 6 orientations" in fig.get_suptitle()
    assert map_figure(m, units=SI).axes[0].get_xlabel() == "x (m)"


def test_the_3d_view_holds_the_reachable_voxels_and_opens_offline(water_map, tmp_path):
    m = water_map
    fig = map_view(m)
    points = [t for t in fig.data if t.name == "reachable voxels"][0]
    rows = np.flatnonzero(m.count > 0)
    np.testing.assert_allclose(np.c_[points.x, points.y, points.z], m.centers[rows] * 1000)
    np.testing.assert_array_equal(points.marker.color, m.index[rows])
    assert points.marker.colorbar.title.text == "index"
    png, html = save_map_figures(m, tmp_path)
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    page = html.read_text(encoding="utf-8")
    assert "reachable voxels" in page and '<script src="http' not in page


def test_a_floor_placement_shows_its_region_and_the_chosen_base(tmp_path):
    ur5 = armkit.robot("ur5")
    task = np.array([pose_from_xyz_rpy([0.6, y, 0.2], [math.pi, 0, 0]) for y in (-0.1, 0.1)])
    grid = floor_grid((-0.3, 0.3), (-0.3, 0.3), 0.1, yaw_step=math.radians(90))
    placement = base_placement(ur5, task, grid)
    fig = placement_figure(placement)
    best, share = fig.axes[0], fig.axes[2]
    assert (best.get_xlabel(), best.get_ylabel()) == ("x (m)", "y (m)")
    image = share.get_images()[0].get_array()
    expected = placement.feasible.reshape(grid.shape).mean(axis=2)
    np.testing.assert_allclose(image.filled(0.0), expected)
    star = [c for c in best.collections if c.get_label() == "chosen base"][0]
    np.testing.assert_allclose(star.get_offsets()[0], placement.T_world_base[:2, 3])
    assert fig.axes[1].get_ylabel() == "worst pose's manipulability"
    assert f"{int(placement.feasible.sum())} of {len(grid)} bases" in fig.get_suptitle()
    path = save_placement_figure(placement, tmp_path / "placement.png")
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_a_rail_placement_plots_the_score_along_the_rail(water_map):
    task = pose_from_xyz_rpy([1.2, 0.9, 0.8], [0, 0, -math.pi / 2])[None]
    grid = rail_grid([0, 0, 0], [3, 0, 0], 0.05, yaw=math.pi / 2)
    placement = base_placement(WATER, task, grid, reach_map=water_map)
    fig = placement_figure(placement, WATER.units)
    (ax,) = fig.axes
    assert ax.get_xlabel() == "s (mm), along the rail from its start"
    assert ax.get_ylabel() == "worst pose's reachability index"
    line = ax.get_lines()[0]
    np.testing.assert_allclose(line.get_xdata(), grid.axes["s"] * 1000)
    chosen = [t.get_text() for t in ax.get_legend().get_texts()
              if t.get_text().startswith("chosen")]
    s = grid.axes["s"][placement.best] * 1000
    assert chosen == [f"chosen: s = {s:.6g} mm"]
