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

_HOMES = {
    **dict.fromkeys(("dbscan", "euclidean_clusters"), "armkit.perception.clusters"),
    **dict.fromkeys(("remove_statistical_outliers", "statistical_outliers", "voxel_downsample"),
                    "armkit.perception.filters"),
    **dict.fromkeys(("Plane", "fit_plane_lsq", "ransac_plane"), "armkit.perception.plane"),
    **dict.fromkeys(("CLUTTER", "Clutter", "SyntheticScene", "cluttered_scene", "clutter_object",
                     "random_scene", "synthetic_scene", "target_frame"),
                    "armkit.perception.synthetic"),
    **dict.fromkeys(("Circle", "fit_circle"), "armkit.perception.circles"),
    **dict.fromkeys(("Candidate", "TargetResult", "detect_target"), "armkit.perception.target"),
    **dict.fromkeys(("Scan", "measure_scan"), "armkit.perception.scan"),
    **dict.fromkeys(("Opening", "row_openings", "grid_openings"), "armkit.perception.holes"),
}

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

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

__all__ = list(_HOMES)
