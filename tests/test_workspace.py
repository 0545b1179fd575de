"""Monte Carlo workspace: bounds, reach, volume and sections against shapes known by hand;
the same result in one process and on a Dask cluster; clear errors for bad arguments."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.model import (DHRow, DHTable, Limits, Robot, ScrewRow, ScrewTable, chain_from_dh,
                          chain_from_poe)
from armkit.spatial import transform
from armkit.sampled_workspace import CHUNK, default_resolution, reach_bound

H2R = 0.02      # voxel edge for the planar arm; its plane sits mid-layer, at z = H2R / 2


def planar_2r(a1: float = 1.0, a2: float = 0.5, continuous: bool = False) -> Robot:
    """Two revolute joints about z, links a1 and a2, in the plane z = H2R / 2."""
    full = Limits(-np.inf, np.inf) if continuous else Limits(-np.pi, np.pi)
    rows = (DHRow("revolute", 0.0, a1, H2R / 2, 0.0, limits=full),
            DHRow("revolute", 0.0, a2, 0.0, 0.0, limits=full))
    return Robot("planar_2r", chain_from_dh(DHTable(rows)))


def cartesian(origin, sides) -> Robot:
    """Three prismatic joints along x, y, z: the box origin + [0, sides)."""
    rows = tuple(ScrewRow("prismatic", axis, Limits(0.0, s)) for axis, s in zip(np.eye(3), sides))
    return Robot("cartesian", chain_from_poe(ScrewTable(rows, transform(p=origin))))


def cells_touching_annulus(r_in: float, r_out: float, h: float) -> set[tuple[int, int]]:
    """Cells [i h, (i+1) h) x [j h, (j+1) h) that meet the annulus r_in < r < r_out."""
    i = np.arange(-math.ceil(r_out / h) - 1, math.ceil(r_out / h) + 1)
    I, J = np.meshgrid(i, i, indexing="ij")
    x0, y0 = I * h, J * h
    nearest = np.hypot(np.clip(0.0, x0, x0 + h), np.clip(0.0, y0, y0 + h))
    farthest = np.hypot(np.maximum(abs(x0), abs(x0 + h)), np.maximum(abs(y0), abs(y0 + h)))
    hit = (nearest < r_out) & (farthest > r_in)
    return set(zip(I[hit].tolist(), J[hit].tolist()))


def test_planar_2r_fills_its_annulus():
    ws = armkit.workspace(planar_2r(), 400_000, resolution=H2R)
    assert ws.radial_reach == pytest.approx(1.5, abs=1e-6) and ws.radial_reach <= 1.5
    assert ws.reach == pytest.approx(math.hypot(1.5, H2R / 2), abs=1e-6)
    assert np.all(ws.lower[:2] >= -1.5) and np.all(ws.upper[:2] <= 1.5)
    np.testing.assert_allclose([ws.lower[:2], ws.upper[:2]], [[-1.5, -1.5], [1.5, 1.5]],
                               atol=1e-3)
    assert ws.lower[2] == pytest.approx(H2R / 2) and ws.upper[2] == pytest.approx(H2R / 2)
    section = ws.horizontal_section(H2R / 2)
    rows, cols = np.nonzero(section.occupied)
    i0, _, j0, _ = np.round(section.extent / H2R).astype(int)
    hit = set(zip((cols + i0).tolist(), (rows + j0).tolist()))
    exact = cells_touching_annulus(0.5, 1.5, H2R)
    assert hit <= exact                             # no cell outside the annulus, ever
    assert len(hit) >= 0.995 * len(exact)           # and almost all of it sampled
    # The cells' area exceeds pi (1.5^2 - 0.5^2) = 2 pi by at most a cell diagonal of rim.
    rim = 2 * math.pi * (1.5 + 0.5) * H2R * math.sqrt(2)
    assert 2 * math.pi - 0.01 <= section.area <= 2 * math.pi + rim
    assert section.area == pytest.approx(len(hit) * H2R**2)
    assert ws.volume == pytest.approx(section.area * H2R)     # one layer of voxels
    assert ws.horizontal_section(H2R * 1.5).area == 0.0


def test_a_continuous_joint_samples_one_turn():
    robot = planar_2r(continuous=True)
    lower, upper = robot.sampling_limits
    np.testing.assert_array_equal([lower, upper], [[-np.pi, -np.pi], [np.pi, np.pi]])
    ws = armkit.workspace(robot, 200_000, resolution=H2R)
    assert ws.radial_reach == pytest.approx(1.5, abs=1e-4)
    assert ws.horizontal_section(H2R / 2).area == pytest.approx(2 * math.pi, rel=0.05)


def test_tool_changer_reaches_2800_mm_along_x():
    # Home tool at (2000, 0, 500) mm with the arm along +x; joint 4 adds up to 800 mm along
    # the arm, so x peaks at 2800 mm (pitches 0, fully extended); pointing straight up the
    # tool reaches z = 500 + 2800 mm, the farthest from the base origin.
    robot = armkit.robot("tool_changer_6dof")
    ws = armkit.workspace(robot, 200_000)
    assert 2.7 < ws.upper[0] <= 2.8 and 2.75 < ws.radial_reach <= 2.8
    assert ws.lower[0] >= -2.8 and np.all(np.abs(ws.lower[1:2]) <= 2.8)
    assert 3.25 < ws.upper[2] <= 3.3 and ws.reach <= 3.3
    assert reach_bound(robot, *robot.sampling_limits) == pytest.approx(3.3)
    x = armkit.fk(robot, robot.q_to_si([0, 0, 0, 800, 0, 0]))[0, 3]
    assert x == pytest.approx(2.8)


def test_water_supply_fills_a_cylinder_of_reach_and_lift():
    # Lift 0 .. 600 mm above the 525.5 mm base; swings about vertical axes reach
    # 214 + 760 + 352.5 = 1326.5 mm from the z axis. Every horizontal section is the same.
    ws = armkit.workspace(armkit.robot("water_supply"), 200_000, resolution=0.05)
    assert 0.5255 <= ws.lower[2] < 0.5256 and 1.1254 < ws.upper[2] <= 1.1255
    assert 1.3264 < ws.radial_reach <= 1.3265 and ws.upper[0] <= 1.3265
    assert ws.reach <= math.hypot(1.3265, 1.1255)
    low, high = ws.horizontal_section(0.6), ws.horizontal_section(1.0)
    assert np.mean(low.occupied != high.occupied) < 0.01       # the same, but for sampling
    assert low.area < math.pi * 1.3265**2
    layers = math.floor(1.1255 / 0.05) - math.floor(0.5255 / 0.05) + 1
    assert ws.volume == pytest.approx(low.area * layers * 0.05, rel=0.02)


def test_volume_converges_on_a_box():
    # A box 0.3 x 0.2 x 0.1 m from (5, 5, 5) mm. With 10 mm voxels it touches 31 x 21 x 11;
    # with 5 mm voxels its faces lie on the grid, and the voxels hold exactly its 0.006 m^3.
    robot = cartesian([0.005] * 3, [0.3, 0.2, 0.1])
    coarse = armkit.workspace(robot, 400_000, resolution=0.01)
    assert coarse.volume == pytest.approx(31 * 21 * 11 * 1e-6)
    assert coarse.volume_change == 0.0
    fine = armkit.workspace(robot, 400_000, resolution=0.005)
    assert fine.volume == pytest.approx(0.006, rel=2e-3) and fine.volume <= 0.006 + 1e-12
    assert 0 < fine.volume_change < 0.02
    history = fine.volume_history
    assert history[-1, 0] == 400_000 and history[-2, 0] == 200_000
    assert np.all(np.diff(history[:, 1]) >= 0) and history[0, 1] < 0.5 * fine.volume
    np.testing.assert_allclose(fine.lower, 0.005, atol=1e-4)
    np.testing.assert_allclose(fine.upper, [0.305, 0.205, 0.105], atol=1e-4)


def test_history_is_the_volume_of_the_first_samples():
    # Chunk i draws from default_rng([seed, i]): a shorter run draws a prefix of a longer one.
    robot = armkit.robot("inspection_6dof")
    full = armkit.workspace(robot, 100_000, chunk=30_000, resolution=0.1, seed=7)
    half = armkit.workspace(robot, 50_000, chunk=30_000, resolution=0.1, seed=7)
    assert full.volume_history[-2, 0] == 50_000
    assert full.volume_history[-2, 1] == half.volume
    assert full.volume_change == pytest.approx((full.volume - half.volume) / full.volume)


def test_counts_first_samples_and_cloud_agree_with_fk():
    robot = armkit.robot("ur5")
    ws = armkit.workspace(robot, 70_000, chunk=25_000, cloud=30_000, resolution=0.05, seed=3)
    lower, upper = robot.sampling_limits
    q = np.concatenate([np.random.default_rng([3, i]).uniform(lower, upper, (25_000, 6))
                        for i in range(2)])[:30_000]
    np.testing.assert_array_equal(ws.cloud, armkit.fk(robot, q)[:, :3, 3])
    assert ws.counts.sum() == 70_000 and ws.first.max() < 70_000 and 0 in ws.first
    assert len(np.unique(ws.voxels, axis=0)) == len(ws.voxels)
    cloud_voxels = np.unique(np.floor(ws.cloud / 0.05).astype(int), axis=0)
    assert {tuple(v) for v in cloud_voxels} <= {tuple(v) for v in ws.voxels}
    assert np.all(ws.lower <= ws.cloud.min(axis=0)) and np.all(ws.upper >= ws.cloud.max(axis=0))
    small = armkit.workspace(robot, 10, cloud=100)
    assert small.cloud.shape == (10, 3) and small.volume_change >= 0


def test_sections_of_a_box():
    # Box [5, 305) x [5, 205) x [5, 105) mm, 10 mm cells.
    ws = armkit.workspace(cartesian([0.005] * 3, [0.3, 0.2, 0.1]), 400_000, resolution=0.01)
    level = ws.horizontal_section(0.05)
    assert level.occupied.shape == (21, 31) and level.occupied.all()
    np.testing.assert_allclose(level.extent, [0, 0.31, 0, 0.21])
    assert level.area == pytest.approx(31 * 21 * 1e-4)
    # The plane y = 0 lies in the voxel layer [0, 10) mm of y, which the box enters.
    upright = ws.vertical_section(0.0)
    assert upright.area == pytest.approx(31 * 11 * 1e-4)
    assert upright.extent[2:] == pytest.approx([0, 0.11])
    assert ws.vertical_section(np.pi / 2).area == pytest.approx(21 * 11 * 1e-4)
    assert ws.vertical_section(np.pi).area == 0.0


def test_a_revolving_shell_has_two_rectangles_as_vertical_section():
    # Swing about z, lift 0 .. 0.3 m, radius 0.2 .. 0.5 m: through the axis, two 0.3 x 0.3 m
    # rectangles; across it, the annulus pi (0.5^2 - 0.2^2).
    rows = (ScrewRow("revolute", [0, 0, 1], Limits(-np.pi, np.pi), point=np.zeros(3)),
            ScrewRow("prismatic", [0, 0, 1], Limits(0.0, 0.3)),
            ScrewRow("prismatic", [1, 0, 0], Limits(0.0, 0.3)))
    robot = Robot("shell", chain_from_poe(ScrewTable(rows, transform(p=[0.2, 0, 0.11]))))
    h = 0.02
    ws = armkit.workspace(robot, 300_000, resolution=h)
    # Cells reach past the true outline by up to one cell (the diagonal, across the annulus).
    for azimuth in (0.0, 1.0, -2.5):
        assert 0.98 * 0.18 <= ws.vertical_section(azimuth).area <= 2 * (0.3 + 2 * h) ** 2
    d = math.sqrt(2) * h
    annulus = ws.horizontal_section(0.25).area
    assert 0.98 * math.pi * 0.21 <= annulus <= math.pi * ((0.5 + d) ** 2 - (0.2 - d) ** 2)


def test_default_resolution_is_a_fiftieth_of_the_span_rounded_down():
    assert default_resolution(1.655) == pytest.approx(0.05)
    assert default_resolution(3.3) == pytest.approx(0.1)
    assert default_resolution(0.6) == pytest.approx(0.02)
    assert default_resolution(1.0) == pytest.approx(0.02)
    assert armkit.workspace(armkit.robot("tool_changer_6dof"), 10).resolution == 0.1


def test_same_seed_same_result_and_none_draws_a_seed():
    robot = armkit.robot("puma560")
    a = armkit.workspace(robot, 30_000, seed=5)
    b = armkit.workspace(robot, 30_000, seed=5)
    assert np.array_equal(a.voxels, b.voxels) and np.array_equal(a.upper, b.upper)
    assert not np.array_equal(armkit.workspace(robot, 30_000, seed=6).upper, a.upper)
    fresh = armkit.workspace(robot, 1_000, seed=None)
    again = armkit.workspace(robot, 1_000, seed=fresh.seed)
    assert np.array_equal(fresh.cloud, again.cloud)


def test_progress_reaches_n():
    calls = []
    armkit.workspace(planar_2r(), 25_000, chunk=10_000, progress=lambda d, t: calls.append(d))
    assert calls == [10_000, 20_000, 25_000]


def assert_same(a, b):
    for name in ("lower", "upper", "voxels", "counts", "first", "cloud", "volume_history"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert (a.reach, a.radial_reach, a.volume, a.samples) == (b.reach, b.radial_reach, b.volume,
                                                               b.samples)


def test_dask_gives_the_local_result(dask_client):
    robot = armkit.robot("inspection_6dof")
    args = dict(seed=11, chunk=20_000, resolution=0.1, cloud=50_000)
    local = armkit.workspace(robot, 250_001, **args)
    done = []
    remote = armkit.workspace(robot, 250_001, scheduler=dask_client,
                              progress=lambda d, t: done.append(d), **args)
    assert_same(local, remote)
    assert done[-1] == 250_001 and done == sorted(done)
    address = armkit.workspace(robot, 250_001, scheduler=dask_client.scheduler.address, **args)
    assert_same(local, address)


@pytest.mark.parametrize("kwargs, message", [
    (dict(n=0), "n: expected at least 1, found 0"),
    (dict(n=1.5), "n: expected a whole number, found 1.5"),
    (dict(n="many"), "n: expected a whole number, found 'many'"),
    (dict(seed=-1), "seed: expected at least 0, found -1"),
    (dict(resolution=0), "resolution: expected a positive voxel edge (m), found 0.0"),
    (dict(resolution=float("nan")), "resolution: expected a finite number, found nan"),
    (dict(resolution=1e-5), "resolution: expected at least 0.000202 m for inspection_6dof"),
    (dict(chunk=0), "chunk: expected 1 .. 2097152, found 0"),
    (dict(cloud=-1), "cloud: expected at least 0, found -1"),
    (dict(scheduler=8786), "scheduler: expected an address such as tcp://127.0.0.1:8786 or a "
                           "distributed.Client, found int"),
])
def test_bad_arguments_say_what_was_expected(kwargs, message):
    args = dict(robot=armkit.robot("inspection_6dof"), n=1000) | kwargs
    with pytest.raises(InputError) as err:
        armkit.workspace(args.pop("robot"), args.pop("n"), **args)
    assert message in str(err.value)


def test_bad_robots_and_planes():
    with pytest.raises(InputError, match="robot: expected a Robot"):
        armkit.workspace("ur5", 10)
    rows = (ScrewRow("prismatic", [1, 0, 0], Limits(0.0, np.inf)),)
    endless = Robot("rail", chain_from_poe(ScrewTable(rows, np.eye(4))))
    with pytest.raises(InputError, match="robot: expected finite limits on prismatic joint q1"):
        armkit.workspace(endless, 10)
    ws = armkit.workspace(planar_2r(), 100, resolution=H2R)
    with pytest.raises(InputError, match="height: expected a finite number, found inf"):
        ws.horizontal_section(np.inf)
    with pytest.raises(InputError, match="azimuth: expected a number, found 'north'"):
        ws.vertical_section("north")


def test_results_are_read_only():
    ws = armkit.workspace(planar_2r(), 100, resolution=H2R)
    with pytest.raises(ValueError):
        ws.voxels[0, 0] = 5
    assert CHUNK == ws.chunk
