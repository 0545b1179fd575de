"""A robot's declared collision geometry, as its robot file gives it (SI).

The robot file's optional ``collision:`` section (lengths in the file's unit)::

    collision:
      radius: 40                  # capsules between consecutive joint origins, this radius
      shapes:                     # or shapes of your own, in link frames (replaces the default)
        - {link: 2, a: [0, 0, 0], b: [-500, 0, 0], radius: 45}     # a capsule
        - {link: 6, a: [0, 0, 80], radius: 60}                      # a sphere (no b)
      skip: [[2, 4]]              # link pairs never tested against each other

Link 0 is the base frame, link i the frame after joint i (``armkit.fk_frames``), the last one
the tool frame. `armkit.planning.ArmGeometry` turns this into capsules for the checker.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True, eq=False)
class CollisionShape:
    """A capsule (a sphere when a == b) on one link: points a, b (3,) in the link frame, m."""

    link: int
    a: NDArray
    b: NDArray
    radius: float


@dataclass(frozen=True, eq=False)
class CollisionSpec:
    """What a robot file declares: a default radius (m) or shapes, and link pairs to skip."""

    radius: float | None = None
    shapes: tuple[CollisionShape, ...] = ()
    skip: tuple[tuple[int, int], ...] = ()

    def __post_init__(self):
        for s in self.shapes:
            for name in ("a", "b"):
                v = np.array(getattr(s, name), dtype=float)
                v.setflags(write=False)
                object.__setattr__(s, name, v)
