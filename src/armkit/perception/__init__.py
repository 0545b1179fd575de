"""The target from a point cloud (paper 1): the train's side, the inlet, its centre and axis.

Each step is a function of its own: `voxel_downsample`, `statistical_outliers`, `ransac_plane`,
`dbscan`, `euclidean_clusters`, `measure_scan`, `fit_circle`, `row_openings`; `detect_target`
runs them all and weighs the evidence. Synthetic scans with their ground truth come from
`synthetic_scene`, `random_scene` and `cluttered_scene` (walls with domes, boxes, bars, bolts
and handles beside the inlet, or instead of it).

The names are loaded on first use (PEP 562), and SciPy with the steps that need it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.perception.clusters import dbscan, euclidean_clusters
    from armkit.perception.filters import (remove_statistical_outliers, statistical_outliers,
                                           voxel_downsample)
    from armkit.perception.plane import Plane, fit_plane_lsq, ransac_plane
    from armkit.perception.circles import Circle, fit_circle
    from armkit.perception.holes import Opening, grid_openings, row_openings
    from armkit.perception.scan import Scan, measure_scan
    from armkit.perception.synthetic import (CLUTTER, Clutter, SyntheticScene, clutter_object,
                                             cluttered_scene, random_scene, synthetic_scene,
                                             target_frame)
    from armkit.perception.target import Candidate, TargetResult, detect_target

__getattr__, __dir__, __all__ = lazy_names(__name__)

