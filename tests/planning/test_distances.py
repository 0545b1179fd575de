"""Each distance the checker uses, against closed forms and brute-force sampling."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.planning import Box, Capsule, Cylinder, Scene, Sphere
from armkit.planning.distances import obstacle_distance, segment_distance
from armkit.spatial import pose_from_xyz_rpy
from tests.planning.reference import point_distance, segment_obstacle, segment_segment


@pytest.mark.slow
def test_closed_forms():
    box = Box([2.0, 2.0, 2.0])                          # the cube |x| <= 1
    # A segment parallel to a face, 0.5 above it; one crossing the box; one past a corner.
    assert obstacle_distance(Scene([box]), [-3, 0, 1.5], [3, 0, 1.5])[0] == pytest.approx(0.5)
    assert obstacle_distance(Scene([box]), [-3, 0, 0], [3, 0, 0])[0] == 0.0
    assert obstacle_distance(Scene([box]), [2, 2, 2], [3, 3, 3])[0] == pytest.approx(np.sqrt(3))
    sphere = Sphere([0, 0, 0], 1.0)
    assert obstacle_distance(Scene([sphere]), [-1, 2, 0], [1, 2, 0])[0] == pytest.approx(1.0)
    assert obstacle_distance(Scene([sphere]), [0, 0.5, 0], [0, 0.5, 0])[0] == \
        pytest.approx(-0.5)
    cylinder = Cylinder(1.0, 2.0)                       # radius 1, z -1 .. 1
    assert obstacle_distance(Scene([cylinder]), [3, -1, 0], [3, 1, 0])[0] == \
        pytest.approx(2.0, abs=1e-8)
    assert obstacle_distance(Scene([cylinder]), [0, 0, 3], [0, 0, 4])[0] == \
        pytest.approx(2.0, abs=1e-8)
    assert obstacle_distance(Scene([cylinder]), [4, 0, 5], [4, 0, 5])[0] == \
        pytest.approx(5.0, abs=1e-8)                     # corner: hypot(3, 4)
    capsule = Capsule([0, 0, -1], [0, 0, 1], 0.5)
    assert obstacle_distance(Scene([capsule]), [2, -1, 0], [2, 1, 0])[0] == pytest.approx(1.5)
    assert segment_distance([0, 0, 0], [1, 0, 0], [0, 1, 1], [1, 1, 1]) == \
        pytest.approx(np.sqrt(2))                        # parallel segments
    assert segment_distance([0, 0, 0], [1, 0, 0], [2, 1, 0], [2, 2, 0]) == \
        pytest.approx(np.sqrt(2))                        # end to end
    assert segment_distance([-1, 0, 0], [1, 0, 0], [0, -1, 1], [0, 1, 1]) == pytest.approx(1)


def _random_obstacles(rng):
    pose = pose_from_xyz_rpy(rng.uniform(-0.5, 0.5, 3), rng.uniform(-np.pi, np.pi, 3))
    return [Box(rng.uniform(0.1, 1.0, 3), pose), Sphere(rng.uniform(-0.5, 0.5, 3),
                                                        rng.uniform(0.1, 0.5)),
            Cylinder(rng.uniform(0.1, 0.5), rng.uniform(0.1, 1.0), pose),
            Capsule(rng.uniform(-0.5, 0.5, 3), rng.uniform(-0.5, 0.5, 3), rng.uniform(0.05, 0.3))]


@pytest.mark.parametrize("seed", range(40))
def test_segments_against_sampling_and_minimisation(seed):
    rng = np.random.default_rng(seed)
    obstacles = _random_obstacles(rng)
    for _ in range(10):
        a, b = rng.uniform(-1.5, 1.5, (2, 3))
        if rng.random() < 0.2:
            b = a.copy()                                  # a point (a sphere on the arm)
        found = obstacle_distance(Scene(obstacles), a, b)
        t = np.linspace(0, 1, 2001)[:, None]
        for o, d in zip(obstacles, found):
            sampled = point_distance(o, a + t * (b - a)).min()
            # Never above what sampling finds (a lower bound), and equal to the minimum.
            assert d <= sampled + 1e-12
            assert d == pytest.approx(segment_obstacle(o, a, b), abs=1e-7)
        c, e = rng.uniform(-1.5, 1.5, (2, 3))
        if rng.random() < 0.2:
            e = c + rng.uniform(-1e-3, 1e-3) * (b - a)     # nearly parallel
        assert segment_distance(a, b, c, e) == pytest.approx(segment_segment(a, b, c, e),
                                                             abs=1e-7)
