"""Each step alone: plane, filters, clustering (against scikit-learn's DBSCAN), circle fit,
synthetic scenes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sklearn.cluster import DBSCAN

from armkit.errors import InputError
from armkit.perception import (
    dbscan,
    euclidean_clusters,
    fit_circle,
    fit_plane_lsq,
    random_scene,
    ransac_plane,
    remove_statistical_outliers,
    statistical_outliers,
    synthetic_scene,
    voxel_downsample,
)


def blobs(seed: int, n_blobs: int = 5, per: int = 200, noise: int = 200) -> np.ndarray:
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 1, (n_blobs, 3))
    parts = [rng.normal(c, rng.uniform(0.01, 0.06), (per, 3)) for c in centres]
    return np.concatenate(parts + [rng.uniform(0, 1, (noise, 3))])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("eps, min_samples", [(0.02, 3), (0.03, 5), (0.05, 10), (0.1, 1),
                                              (0.04, 25)])
def test_dbscan_labels_equal_scikit_learns(seed, eps, min_samples):
    p = blobs(seed)
    ours = dbscan(p, eps, min_samples)
    theirs = DBSCAN(eps=eps, min_samples=min_samples).fit(p).labels_
    np.testing.assert_array_equal(ours, theirs)


def test_dbscan_on_a_scene_equals_scikit_learn():
    scene = random_scene(3, n_points=20_000, noise=0.005)
    p = scene.points[scene.points @ scene.plane_normal + scene.plane_offset > 0.02]
    ours = dbscan(p, 0.02, 5)
    np.testing.assert_array_equal(ours, DBSCAN(eps=0.02, min_samples=5).fit(p).labels_)
    assert ours.max() >= 0


@given(st.integers(0, 10_000), st.floats(0.01, 0.2), st.integers(1, 12))
def test_dbscan_law_matches_scikit_learn(seed, eps, min_samples):
    p = np.random.default_rng(seed).uniform(0, 1, (150, 3))
    np.testing.assert_array_equal(dbscan(p, eps, min_samples),
                                  DBSCAN(eps=eps, min_samples=min_samples).fit(p).labels_)


def test_euclidean_clusters_by_size_and_min_size():
    rng = np.random.default_rng(1)
    small = rng.normal([0, 0, 0], 0.005, (10, 3))
    big = rng.normal([1, 0, 0], 0.005, (50, 3))
    labels = euclidean_clusters(np.concatenate([small, big]), 0.05, min_size=20)
    assert (labels[:10] == -1).all() and (labels[10:] == 0).all()
    labels = euclidean_clusters(np.concatenate([small, big]), 0.05)
    assert (labels[:10] == 1).all() and (labels[10:] == 0).all()


def test_ransac_plane_finds_the_wall_among_outliers():
    scene = synthetic_scene(noise=0.002, n_points=20_000, outliers=0.2, seed=5)
    plane = ransac_plane(scene.points, 0.01, seed=1)
    assert abs(plane.normal @ scene.plane_normal) > np.cos(np.deg2rad(0.05))
    assert plane.normal @ scene.plane_normal > 0 and plane.offset > 0   # sensor side positive
    assert plane.offset == pytest.approx(scene.plane_offset, abs=5e-4)
    assert 0.0015 < plane.rms < 0.0025
    assert plane.inliers[~scene.outlier].mean() > 0.9
    assert plane.iterations < 200          # adaptive: a wall of 75 % needs a few dozen


def test_plane_lsq_exact_and_orientation():
    rng = np.random.default_rng(0)
    xy = rng.uniform(-1, 1, (100, 2))
    p = np.column_stack([xy, 0.5 * xy[:, 0] - 2.0])      # z = 0.5 x - 2
    normal, offset, rms = fit_plane_lsq(p)
    expected = np.array([-0.5, 0, 1]) / np.sqrt(1.25)
    assert abs(normal @ expected) == pytest.approx(1, abs=1e-12)
    assert offset >= 0 and rms < 1e-12
    np.testing.assert_allclose(p @ normal + offset, 0, atol=1e-12)


def test_ransac_on_too_few_points_has_no_support():
    plane = ransac_plane([[0, 0, 0], [1, 0, 0]])
    assert plane.inliers.sum() == 0


def test_voxel_downsample_is_the_centroid_per_voxel():
    rng = np.random.default_rng(2)
    p = rng.uniform(-0.3, 0.3, (3000, 3))
    out = voxel_downsample(p, 0.1)
    keys = np.floor(p / 0.1).astype(int)
    expected = {tuple(k): p[(keys == k).all(axis=1)].mean(axis=0) for k in np.unique(keys, axis=0)}
    assert len(out) == len(expected)
    got = {tuple(np.floor(c / 0.1).astype(int)): c for c in out}
    for key, centroid in expected.items():
        np.testing.assert_allclose(got[key], centroid, atol=1e-12)


def test_statistical_outliers_flags_the_isolated_points():
    rng = np.random.default_rng(3)
    dense = rng.normal(0, 0.01, (2000, 3))
    far = rng.uniform(0.5, 1.0, (10, 3))
    flags = statistical_outliers(np.concatenate([dense, far]))
    assert flags[-10:].all() and flags[:-10].mean() < 0.05
    assert len(remove_statistical_outliers(np.concatenate([dense, far]))) == (~flags).sum()


@pytest.mark.parametrize("known", [True, False])
def test_circle_fit_on_a_half_arc(known):
    rng = np.random.default_rng(4)
    a = rng.uniform(0, np.pi, 300)
    xy = np.column_stack([3 + 0.04 * np.cos(a), -1 + 0.04 * np.sin(a)])
    xy += rng.normal(0, 0.0005, xy.shape)
    xy[:5] += 0.02                                              # gross errors set aside
    c = fit_circle(xy, 0.04 if known else None)
    np.testing.assert_allclose(c.centre, [3, -1], atol=1.5e-4)
    assert c.radius == pytest.approx(0.04, abs=0 if known else 1.5e-4)
    assert not c.used[:5].any() and c.rms < 0.0007
    assert np.pi * 0.9 < c.coverage < np.pi * 1.05


def test_synthetic_scene_truth():
    scene = synthetic_scene("pipe", noise=0.0, outliers=0.0, n_points=5000, seed=0)
    h = scene.points @ scene.plane_normal + scene.plane_offset
    off = h > 1e-9
    assert (np.abs(h[~off]) < 1e-9).mean() == 1.0                 # wall points on the plane
    T = scene.T_sensor_target
    axis, mouth = T[:3, 2], T[:3, 3]
    base = mouth - 0.10 * axis
    d = scene.points[off] - base
    radial = np.linalg.norm(d - np.outer(d @ axis, axis), axis=1)
    np.testing.assert_allclose(radial, 0.04, atol=1e-9)          # pipe points on the cylinder
    assert ((d @ axis) <= 0.10 + 1e-9).all()
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    assert T[:3, 2] @ scene.plane_normal == pytest.approx(1)
    rings = synthetic_scene("hole", noise=0.0, n_points=5000, rings=16, seed=0)
    z_angles = np.round(np.arcsin(rings.points[~rings.outlier, 2]
                                  / np.linalg.norm(rings.points[~rings.outlier], axis=1)), 9)
    assert len(np.unique(z_angles)) == 16


@pytest.mark.parametrize("call", [
    lambda: dbscan(np.zeros((5, 2)), 0.1),
    lambda: dbscan(np.zeros((5, 3)), -1.0),
    lambda: dbscan(np.zeros((5, 3)), 0.1, 0),
    lambda: ransac_plane(np.full((5, 3), np.nan)),
    lambda: ransac_plane(np.zeros((0, 3))),
    lambda: ransac_plane(np.zeros((5, 3)), threshold=0.0),
    lambda: voxel_downsample(np.zeros((5, 3)), 0.0),
    lambda: statistical_outliers(np.zeros((5, 3)), k=0),
    lambda: fit_circle(np.zeros((2, 2))),
    lambda: fit_circle(np.zeros((5, 2)), radius=-1.0),
    lambda: synthetic_scene("slot"),
])
def test_bad_arguments_are_input_errors(call):
    with pytest.raises(InputError, match="expected"):
        call()
