"""Laws that hold for every input (hypothesis): the orientations' nearest, the voxel look-up,
and placement's indifference to where the world's origin is."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import armkit
from armkit.kinematics.ik.masks import task_errors
from armkit.reach import Orientations, base_placement, floor_grid
from armkit.reach.maps import voxel_keys
from armkit.reach.orientations import radial_frames
from armkit.spatial import pose_from_xyz_rpy

UR5 = armkit.robot("ur5")
MODULAR = armkit.robot("modular_4dof")
SETS = {"sphere": Orientations.sphere(60), "axis": Orientations.axis(40, "x"),
        "about": Orientations.about(armkit.robot("water_supply"), 24),
        "pitch": Orientations.pitch(24, "x")}
FINITE = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=30)
@given(kind=st.sampled_from(sorted(SETS)), seed=st.integers(0, 2**32 - 1),
       point=st.tuples(FINITE, FINITE, FINITE))
def test_nearest_is_the_orientation_of_least_task_error(kind, seed, point):
    o = SETS[kind]
    centre = np.array(point)
    # Each orientation of the set is its own nearest.
    own = o.in_base(centre[None], MODULAR)[0]
    np.testing.assert_array_equal(o.nearest(own, np.repeat(centre[None], len(o), 0), MODULAR),
                                  np.arange(len(o)))
    # Any rotation: the nearest has the least task error (`task_errors`, the IK solver's
    # measure of success) of the whole set.
    R = Rotation.random(5, random_state=seed).as_matrix()
    k = o.nearest(R, np.repeat(centre[None], 5, 0), MODULAR)
    T = np.tile(np.eye(4), (5, len(o), 1, 1))
    T[..., :3, :3] = own
    S = np.tile(np.eye(4), (5, 1, 1, 1))
    S[..., :3, :3] = R[:, None]
    _, error = task_errors(T, S, o.mask)
    assert np.allclose(error[np.arange(5), k], error.min(axis=1), atol=1e-9)


@settings(max_examples=30)
@given(point=st.tuples(FINITE, FINITE, FINITE))
def test_radial_frames_point_from_the_first_axis_to_the_point(point):
    p = np.array(point)[None]
    F = radial_frames(MODULAR, p)[0]
    np.testing.assert_allclose(F.T @ F, np.eye(3), atol=1e-12)
    assert np.linalg.det(F) > 0 and np.allclose(F[:, 2], [0, 0, 1])
    if np.hypot(*p[0, :2]) > 1e-9:
        np.testing.assert_allclose(F[:2, 0] * np.hypot(*p[0, :2]), p[0, :2], atol=1e-12)


@settings(max_examples=30)
@given(ijk=st.lists(st.tuples(*[st.integers(-2**19, 2**19)] * 3), min_size=2, max_size=20))
def test_voxel_keys_sort_as_the_voxels_do(ijk):
    v = np.array(ijk, dtype=np.int64)
    by_key = v[np.argsort(voxel_keys(v), kind="stable")]
    by_index = v[np.lexsort(v.T[::-1])]
    np.testing.assert_array_equal(by_key, by_index)


MAP = armkit.reach_map(UR5, 0.2, 8, samples=100_000)


@settings(max_examples=30)
@given(point=st.tuples(*[st.floats(-1.2, 1.2, allow_nan=False)] * 3))
def test_find_gives_the_voxel_that_holds_the_point(point):
    p = np.array(point)
    row = MAP.find(p)
    ijk = np.floor(p / MAP.resolution).astype(np.int64)
    held = np.flatnonzero((MAP.voxels == ijk).all(axis=1))
    assert row == (held[0] if held.size else -1)
    assert MAP.index_at(p) == (MAP.index[row] if row >= 0 else 0.0)


@settings(max_examples=8)
@given(shift=st.tuples(*[st.floats(-3, 3, allow_nan=False)] * 2), seed=st.integers(0, 1000))
def test_placement_does_not_care_where_the_world_origin_is(shift, seed):
    rng = np.random.default_rng(seed)
    task = np.array([pose_from_xyz_rpy([0.55 + 0.1 * rng.standard_normal(),
                                        0.1 * rng.standard_normal(), 0.2],
                                       [math.pi, 0, rng.uniform(-1, 1)]) for _ in range(3)])
    grid = floor_grid((-0.2, 0.2), (-0.2, 0.2), 0.1, yaw_step=math.radians(90))
    moved_task = task.copy()
    moved_task[:, :2, 3] += shift
    moved_grid = floor_grid((-0.2 + shift[0], 0.2 + shift[0]), (-0.2 + shift[1], 0.2 + shift[1]),
                            0.1, yaw_step=math.radians(90))
    a = base_placement(UR5, task, grid)
    b = base_placement(UR5, moved_task, moved_grid)
    if len(moved_grid) != len(grid):            # rounding of the range gave another count
        return
    np.testing.assert_array_equal(a.feasible, b.feasible)
    np.testing.assert_allclose(a.score, b.score, rtol=1e-6, equal_nan=True)
