"""Reachability maps and base placement (SPEC.md section 5b).

`reach_map` solves IK for every voxel of the workspace and every orientation of a set
(`Orientations`), and keeps per voxel the share reached, which ones and the best
manipulability (a `ReachMap`); `base_placement` finds where to stand the robot so that it
reaches every pose of a task (a `Placement`).
"""

from armkit.lazy import public_names
from armkit.reach.maps import IndexSection, MapChunk, ReachMap, reach_map
from armkit.reach.orientations import Orientations, default_orientations
from armkit.reach.placement import BaseGrid, Placement, base_placement, floor_grid, rail_grid

__all__ = public_names(__name__)
