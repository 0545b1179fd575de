"""Spheres that cover a triangle mesh: a collision link given only as a mesh, as spheres.

`spheres_from_mesh` voxelises the mesh's solid (its surface, then the holes filled), finds for
each voxel inside how far the surface is (a Euclidean distance transform), and keeps the voxels
where that distance peaks (the medial axis, where the largest spheres that stay inside sit).
Each such voxel offers a sphere of its distance plus the tolerance; a greedy cover picks, again
and again, the offer holding the most surface points not yet held (the mesh's vertices and
points spread over its triangles). Surface points no offer holds (thin fins, sharp edges) are
covered by small spheres of their own. Last, a sphere grows where needed so that every vertex of
the mesh lies inside a sphere.

So every vertex is inside the spheres, the surface between vertices within the sampling's
spacing, and a sphere reaches about `tolerance` (plus half a voxel) past the surface: a smaller
tolerance gives more, smaller spheres that hug the mesh closer.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage, sparse
from scipy.spatial import cKDTree

from armkit.errors import InputError

TOLERANCE = 0.02        # m: how far the spheres may reach past the mesh, by default
MAX_VOXELS = 2_000_000  # the finest grid voxelised (the pitch grows for a large mesh)
MAX_CANDIDATES = 600    # sphere centres offered to the greedy cover (a seeded subset)


def surface_points(vertices: NDArray, faces: NDArray, spacing: float) -> NDArray:
    """The vertices and points spread over each triangle, no two neighbours more than about
    `spacing` (m) apart: (k, 3)."""
    T = vertices[faces]                                         # (f, 3, 3)
    edge = np.linalg.norm(T[:, [1, 2, 0]] - T, axis=2).max(axis=1)
    steps = np.minimum(np.ceil(edge / spacing).astype(np.int64), 64)
    out = [vertices]
    for k in np.unique(steps[steps > 1]):
        # Barycentric points of a triangle split k times along each edge.
        u, v = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = u + v <= k
        u, v = u[keep] / k, v[keep] / k
        tri = T[steps == k]
        out.append((tri[:, None, 0] + u[:, None] * (tri[:, None, 1] - tri[:, None, 0])
                    + v[:, None] * (tri[:, None, 2] - tri[:, None, 0])).reshape(-1, 3))
    return np.vstack(out)


def _solid(points: NDArray, pitch: float) -> tuple[NDArray, NDArray]:
    """The voxels (a boolean grid) on the surface points or enclosed by them, and the grid's
    origin (the centre of voxel 0, 0, 0)."""
    lo = points.min(axis=0) - 2 * pitch
    shape = np.ceil((points.max(axis=0) + 2 * pitch - lo) / pitch).astype(np.int64) + 1
    grid = np.zeros(shape, bool)
    index = np.round((points - lo) / pitch).astype(np.int64)
    grid[index[:, 0], index[:, 1], index[:, 2]] = True
    # Close the gaps the surface points leave between voxels, then fill the inside.
    grid = ndimage.binary_closing(grid, structure=np.ones((3, 3, 3)), border_value=0)
    return ndimage.binary_fill_holes(grid), lo


def spheres_from_mesh(vertices: ArrayLike, faces: ArrayLike, tolerance: float = TOLERANCE
                      ) -> tuple[NDArray, NDArray]:
    """Spheres that hold a triangle mesh (see the module's note).

    Parameters
    ----------
    vertices : array_like, (v, 3)
        m.
    faces : array_like of int, (f, 3)
        Vertex indices of each triangle.
    tolerance : float
        m: about how far a sphere may reach past the mesh's surface.

    Returns
    -------
    centres : ndarray, (k, 3)
        m, in the mesh's frame.
    radii : ndarray, (k,)
        m; every vertex lies within some sphere.

    Raises
    ------
    InputError
        If the mesh has no vertices, a vertex is not finite, a face names a vertex it does not
        have, or the tolerance is not a positive length.
    """
    V = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces).reshape(-1, 3)
    if not (isinstance(tolerance, (int, float, np.floating)) and math.isfinite(tolerance)
            and tolerance > 0):
        raise InputError(f"tolerance: expected a positive length (m), found {tolerance!r}")
    if len(V) == 0 or not np.isfinite(V).all():
        raise InputError(f"mesh: expected finite vertices, found {len(V)} vertices"
                         + ("" if len(V) == 0 else " with some not finite"))
    if faces.size and (not np.issubdtype(faces.dtype, np.integer) or faces.min() < 0
                       or faces.max() >= len(V)):
        raise InputError(f"mesh faces: expected vertex indices 0 .. {len(V) - 1}, found "
                         f"{faces.min()} .. {faces.max()}")
    extent = float(np.ptp(V, axis=0).max())
    if extent <= tolerance:
        # Smaller than the tolerance: one sphere about its box.
        centre = 0.5 * (V.min(axis=0) + V.max(axis=0))
        return centre[None], np.array([np.linalg.norm(V - centre, axis=1).max() + 1e-9])
    pitch = max(tolerance / 2, extent / MAX_VOXELS ** (1 / 3))
    inside, origin = _solid(surface_points(V, faces, pitch) if faces.size else V, pitch)
    points = surface_points(V, faces, tolerance) if faces.size else V
    depth = ndimage.distance_transform_edt(inside) * pitch      # to the nearest outside voxel
    # The ridge of the depth: voxels at least as deep as both neighbours along some axis.
    ridge = np.zeros_like(inside)
    for axis in range(3):
        ridge |= (depth >= np.roll(depth, 1, axis)) & (depth >= np.roll(depth, -1, axis))
    peaks = inside & ridge & (depth > pitch)
    if peaks.sum() > MAX_CANDIDATES:            # a seeded subset, for a large mesh
        keep = np.flatnonzero(peaks)
        peaks = np.zeros_like(peaks)
        peaks.flat[np.random.default_rng(0).choice(keep, MAX_CANDIDATES, replace=False)] = True
    centres = origin + np.argwhere(peaks) * pitch
    radii = depth[peaks] - pitch / 2 + tolerance
    chosen_c, chosen_r = [], []
    uncovered = np.ones(len(points), bool)
    if len(centres):
        held = cKDTree(points).query_ball_point(centres, radii)
        rows = np.repeat(np.arange(len(held)), [len(h) for h in held])
        cover = sparse.csr_matrix((np.ones(len(rows)), (rows, np.concatenate(held).astype(
            np.int64) if len(rows) else rows)), shape=(len(held), len(points)))
        while uncovered.any():
            gains = cover @ uncovered.astype(float)
            best = int(np.argmax(gains))
            if gains[best] == 0:
                break
            uncovered[cover.indices[cover.indptr[best]:cover.indptr[best + 1]]] = False
            chosen_c.append(centres[best])
            chosen_r.append(radii[best])
    # What the medial spheres leave: small spheres over nearby points.
    rest = points[uncovered]
    while len(rest):
        d = np.linalg.norm(rest - rest[0], axis=1)
        group = rest[d <= 2 * tolerance]
        centre = 0.5 * (group.min(axis=0) + group.max(axis=0))
        chosen_c.append(centre)
        chosen_r.append(np.linalg.norm(group - centre, axis=1).max() + 1e-9)
        rest = rest[d > 2 * tolerance]
    C, R = np.array(chosen_c).reshape(-1, 3), np.array(chosen_r, dtype=float)
    # Every vertex inside: the nearest sphere grows to hold one left out.
    gap = np.linalg.norm(V[:, None] - C[None], axis=2) - R[None]          # (v, k)
    nearest = np.argmin(gap, axis=1)
    out = gap[np.arange(len(V)), nearest] > 0
    for v, k in zip(np.flatnonzero(out), nearest[out]):
        R[k] = max(R[k], np.linalg.norm(V[v] - C[k]) * (1 + 1e-12) + 1e-12)
    return C, R
