"""A point cloud as perception takes it: points in metres, with what else the sensor gave per
point (`Cloud`), and the check that points are in metres at all (`check_scale`).

Files become clouds in `armkit.io.clouds`; perception takes the objects, never paths.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError, ModelFileError

MIN_EXTENT = 0.05           # m: smaller scenes are taken for metres read as millimetres
MAX_RANGE = 1000.0          # m: larger median ranges are taken for millimetres read as metres


@dataclass(frozen=True)
class Cloud:
    """Points in metres, with what else their file (or sensor) holds per point.

    Attributes
    ----------
    points : ndarray, shape (N, 3)
        Finite points, m (whatever the file's unit).
    file_units : {"m", "mm"}
        The length unit the file's numbers are in (declared by the file or given by the caller);
        `points` are converted from it.
    dropped : int
        Points with NaN or inf that were dropped.
    path : str
        The file they were read from, as given ("" for none).
    fields : mapping of str to ndarray, shape (N,)
        Extra per-point fields kept by name (intensity, ring, timestamp, ...), as the file's
        numbers (not converted), for the points kept.
    index : ndarray, shape (N,), int
        Each point's place in the file (row-major in an organised cloud: row = index // width).
    width, height : int
        The file's grid: an organised cloud (a depth camera's image, a LiDAR's rings by
        columns) has height > 1; an unorganised one has height 1 and width the point count.
    """

    points: NDArray
    file_units: str
    dropped: int
    path: str
    fields: Mapping[str, NDArray] = field(default_factory=dict)
    index: NDArray | None = None
    width: int = 0
    height: int = 1

    def __post_init__(self):
        if self.index is None:
            object.__setattr__(self, "index", np.arange(len(self.points)))
        if not self.width:
            object.__setattr__(self, "width", len(self.points))
        for value in (self.points, self.index, *self.fields.values()):
            value.flags.writeable = False
        object.__setattr__(self, "fields", MappingProxyType(dict(self.fields)))

    @property
    def organized(self) -> bool:
        """Whether the file's points form a grid of more than one row."""
        return self.height > 1


def check_scale(points: NDArray, source: str, *, file: bool = True) -> None:
    """Refuse points (m) whose scale suggests the wrong unit.

    Parameters
    ----------
    points : ndarray, shape (N, 3), m
    source : str
        The file the points came from, or the argument's name.
    file : bool
        Whether `source` is a file (a ModelFileError) or an argument (an InputError).

    Raises
    ------
    ModelFileError or InputError
        When the middle 98 % of the points spans less than 5 cm, or their median distance from
        the sensor exceeds 1 km.
    """
    sample = points[::max(len(points) // 10_000, 1)]        # a few thousand points suffice
    lo, hi = np.percentile(sample, [1, 99], axis=0)
    extent = float(np.linalg.norm(hi - lo))
    median_range = float(np.median(np.linalg.norm(sample, axis=1)))
    problem = None
    if len(points) >= 10 and extent < MIN_EXTENT:
        problem = ("a scene at least 5 cm across (is the unit right? a cloud in metres read as "
                   "millimetres shrinks 1000 times)", f"{extent * 1e3:.3g} mm across")
    elif median_range > MAX_RANGE:
        problem = ("points within 1 km of the sensor (is the unit right? a cloud in "
                   "millimetres read as metres grows 1000 times)",
                   f"a median range of {median_range:.4g} m")
    if problem:
        if not file:
            raise InputError(f"{source}: expected {problem[0]}, found {problem[1]}")
        raise ModelFileError(source, "points", *problem)
