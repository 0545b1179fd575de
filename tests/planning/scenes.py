"""The benchmark's shelf (issue 15) and random scenes, shared by the planning tests."""

from __future__ import annotations

import numpy as np

from armkit.planning import Box, Capsule, Cylinder, Scene, Sphere
from armkit.spatial import pose_from_xyz_rpy

MM = 1e-3
SHELF_START = np.array([0.5567789, -1.5882119, 1.3545770, -2.3713940, 2.2182614, -2.4618970])
SHELF_GOAL = np.array([-0.8764912, -0.4068011, -1.3528886, 1.6921273, -0.9314323, 2.2978917])


def shelf() -> Scene:
    """Three plates (x 650-1100, y -500..500 mm, z 200-240, 560-600, 920-960) and a back wall
    (x 1100-1140, z 0-1000)."""
    plates = [Box.from_bounds(np.array([650, -500, z0]) * MM, np.array([1100, 500, z1]) * MM)
              for z0, z1 in ((200, 240), (560, 600), (920, 960))]
    wall = Box.from_bounds(np.array([1100, -500, 0]) * MM, np.array([1140, 500, 1000]) * MM)
    return Scene(plates + [wall])


def random_scene(seed: int, count: int = 5, reach: float = 1.2) -> Scene:
    """A few obstacles of every kind, placed around the arm (not on its base)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        while True:
            c = rng.uniform(-reach, reach, 3)
            c[2] = abs(c[2])
            if np.linalg.norm(c[:2]) > 0.35:
                break
        pose = pose_from_xyz_rpy(c, rng.uniform(-np.pi, np.pi, 3))
        kind = i % 4
        if kind == 0:
            out.append(Box(rng.uniform(0.05, 0.3, 3), pose))
        elif kind == 1:
            out.append(Sphere(c, rng.uniform(0.05, 0.15)))
        elif kind == 2:
            out.append(Cylinder(rng.uniform(0.03, 0.1), rng.uniform(0.1, 0.4), pose))
        else:
            out.append(Capsule(c, c + rng.uniform(-0.2, 0.2, 3), rng.uniform(0.03, 0.08)))
    return Scene(out)
