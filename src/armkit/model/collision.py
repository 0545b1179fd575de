"""A robot's declared collision geometry, as its robot file gives it (SI).

The robot file's optional ``collision:`` section (lengths in the file's unit)::

    collision:
      radius: 40                  # capsules between consecutive joint origins, this radius
      shapes:                     # or shapes of your own, in link frames (replaces the default)
        - {link: 2, a: [0, 0, 0], b: [-500, 0, 0], radius: 45}     # a capsule
        - {link: 6, a: [0, 0, 80], radius: 60}                      # a sphere (no b)
      skip: [[2, 4], [wrist_1_link, ee_link]]   # link pairs never tested: numbers or names

Link 0 is the base frame, link i the frame after joint i (``armkit.fk_frames``), the last one
the tool frame; a URDF robot's links can be named (its URDF link names). A URDF robot file's
``srdf:`` names an SRDF whose ``disable_collisions`` pairs are left out (and then adjacent links
are tested unless disabled, as MoveIt does). `armkit.planning.ArmGeometry` turns this into the
checker's parts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True, eq=False)
class CollisionShape:
    """A capsule (a sphere when a == b) on one link: points a, b (3,) in the link frame, m;
    `name`, the body it belongs to (a URDF link's name), if the file gives one."""

    link: int
    a: NDArray
    b: NDArray
    radius: float
    name: str = ""


@dataclass(frozen=True, eq=False)
class CollisionSpec:
    """What a robot file declares: a default radius (m) or shapes, link pairs to skip (by
    number), body pairs to leave out (by name: the file's skip by name, its SRDF's pairs), and
    whether adjacent links are tested (as MoveIt does when an SRDF says which pairs are
    off)."""

    radius: float | None = None
    shapes: tuple[CollisionShape, ...] = ()
    skip: tuple[tuple[int, int], ...] = ()
    disabled: tuple[tuple[str, str], ...] = ()
    adjacent: bool = False

    def __post_init__(self):
        for s in self.shapes:
            for name in ("a", "b"):
                v = np.array(getattr(s, name), dtype=float)
                v.setflags(write=False)
                object.__setattr__(s, name, v)
