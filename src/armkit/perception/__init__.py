"""The target from a point cloud (paper 1): the train's side, the inlet, its centre and axis.

Each step is a function of its own: `voxel_downsample`, `statistical_outliers`, `ransac_plane`,
`dbscan`, `euclidean_clusters`, `fit_circle`; `detect_target` runs them all. Synthetic scans
with their ground truth come from `synthetic_scene` and `random_scene`.

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
    **dict.fromkeys(("SyntheticScene", "random_scene", "synthetic_scene", "target_frame"),
                    "armkit.perception.synthetic"),
    **dict.fromkeys(("Circle", "TargetResult", "detect_target", "fit_circle"),
                    "armkit.perception.target"),
}

if TYPE_CHECKING:
    from armkit.perception.clusters import dbscan, euclidean_clusters
    from armkit.perception.filters import (remove_statistical_outliers, statistical_outliers,
                                           voxel_downsample)
    from armkit.perception.plane import Plane, fit_plane_lsq, ransac_plane
    from armkit.perception.synthetic import (SyntheticScene, random_scene, synthetic_scene,
                                             target_frame)
    from armkit.perception.target import Circle, TargetResult, detect_target, fit_circle

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

__all__ = list(_HOMES)
