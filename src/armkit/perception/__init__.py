"""The target from a point cloud (paper 1): the train's side, the inlet, its centre and axis.

Each step is a function of its own: `voxel_downsample`, `statistical_outliers`, `ransac_plane`,
`dbscan`, `euclidean_clusters`, `fit_circle`; `detect_target` runs them all. Synthetic scans
with their ground truth come from `synthetic_scene` and `random_scene`.
"""

from armkit.perception.clusters import dbscan, euclidean_clusters
from armkit.perception.filters import (
                                       remove_statistical_outliers,
                                       statistical_outliers,
                                       voxel_downsample,
)
from armkit.perception.plane import Plane, fit_plane_lsq, ransac_plane
from armkit.perception.synthetic import SyntheticScene, random_scene, synthetic_scene, target_frame
from armkit.perception.target import Circle, TargetResult, detect_target, fit_circle

__all__ = ["dbscan", "euclidean_clusters", "voxel_downsample", "statistical_outliers",
           "remove_statistical_outliers", "Plane", "fit_plane_lsq", "ransac_plane",
           "SyntheticScene", "synthetic_scene", "random_scene", "target_frame", "Circle",
           "TargetResult", "detect_target", "fit_circle"]
