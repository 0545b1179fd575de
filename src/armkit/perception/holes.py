"""Round openings in a wall, found with evidence: the rim's points fit a circle to within what
the scan's spacing and noise allow, and no wall point lies inside it.

Where the scan has rows (a spinning LiDAR's rings, a scanner's rows), the opening is looked for
along them: a row that crosses an opening breaks off at its rim and goes on beyond it, so an
opening is a run of gaps, far longer than the row's own step, on neighbouring rows, lined up
across them. The space between two rings is never taken for an opening: it is not a gap along
any ring. Each gap gives two rim estimates: midway between the last wall point and the first
return through the opening (carried back along its ray to the wall), or, without returns
through it, half a step beyond the last wall point. A gap with something standing in front of
it on the same row is a shadow, not an opening.

A cloud without rows (merged or resampled scans) is searched on an occupancy grid of the wall's
points instead (`grid_openings`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from armkit.perception.circles import Circle, fit_circle
from armkit.perception.scan import Scan

GAP_STEPS = 2.5          # a row's break longer than this many of its steps is a gap
MIN_COVERAGE = np.pi     # rad: the rim seen on both sides of the opening
MIN_USED = 0.8           # share of an opening's rim estimates its circle's robust fit keeps
SIGHT_RADII = 2.0        # the line of sight to an opening must be clear this many radii around
MIN_COVERING = 10        # points standing off the wall there that make it a shadow (not the
#                          few outliers a scan has there: 0 to 4 in the synthetic scans)
INSIDE_SHARE = 0.02      # wall points inside an opening, at most this share of its rim points
MAX_GAPS = 20_000        # gaps weighed at most (a scan with more is not of a wall)


@dataclass(frozen=True)
class Opening:
    """An opening weighed as the inlet: its circle in the wall's (u, v) coordinates and what
    speaks for or against it.

    Attributes
    ----------
    circle : Circle or None
    rim : ndarray, shape (k, 2)
        The rim estimates the circle was fitted to, m.
    rim_mask : ndarray, shape (N,), bool
        The wall points at its rim.
    rows : int
        Rows (rings) that cross it (0 on the grid).
    rms_limit : float
        The largest rim fit RMS its scan allows, m.
    inside : int
        Wall points inside the circle.
    reason : str
        "ok" or why it is not a round opening.
    """

    circle: Circle | None
    rim: NDArray
    rim_mask: NDArray
    rows: int
    rms_limit: float
    inside: int
    reason: str


BEAM = 1e-3              # rad: a LiDAR beam's footprint, 1 mm per m of range (0.06 deg)


def rim_tolerance(spacing: float, distance: float) -> float:
    """The largest RMS (m) of a round opening's rim estimates about their circle, for points
    `spacing` apart along the rows at `distance` (m) from the sensor: half a spacing (the
    sampling alone gives 0.29 spacings rms), the beam's footprint (`BEAM`, a beam that grazes
    the rim returns from part of it) and 1 mm."""
    return 0.5 * spacing + BEAM * distance + 1e-3


def _crossing(points: NDArray, normal: NDArray, offset: float) -> NDArray:
    """Where the rays to `points` (k, 3) cross the plane n . x + d = 0."""
    dn = points @ normal
    dn = np.where(np.abs(dn) < 1e-12, 1e-12, dn)
    return points * (-offset / dn)[:, None]


def _in_sight(front: NDArray, centre: NDArray, reach: float) -> int:
    """Points standing in front of the wall (k, 3) within `reach` (m) of the line of sight from
    the sensor to `centre` (3,) on the wall: what hides it (a shadow) or stands over it (a
    pipe's dark mouth hides the wall beyond it, with no return of its own)."""
    distance = float(np.linalg.norm(centre))
    d = centre / max(distance, 1e-12)
    t = front @ d
    off = np.linalg.norm(front - np.outer(t, d), axis=1)
    return int(((off < reach) & (t > 0) & (t < distance)).sum())


def _judge(rim: NDArray, rim_mask: NDArray, rows: int, radius: float | None,
           wall_xy: NDArray, front: NDArray, frame: tuple, limit: float, max_extent: float,
           min_rows: int) -> Opening:
    """Fit the rim's circle and weigh it: RMS, coverage, size, wall points inside it, and
    points in front of the wall whose rays cross it (a shadow)."""
    if len(rim) < 2 * min_rows or rows < min_rows:
        return Opening(None, rim, rim_mask, rows, limit, 0,
                       f"crossed by {rows} row(s): too few to show a round opening "
                       f"(at least {min_rows})" if rows else "too few points on its rim")
    circle = fit_circle(rim, radius, keep_within=limit)
    used = circle.used.mean()
    mm = 1e3
    if used < MIN_USED:
        return Opening(circle, rim, rim_mask, rows, limit, 0,
                       f"only {used:.0%} of its rim estimates fit one circle (at least "
                       f"{MIN_USED:.0%}: not a round opening)")
    near = np.linalg.norm(wall_xy - circle.centre, axis=1)
    inside = int((near < circle.radius - limit * 3).sum())
    origin, u, v = frame
    covering = _in_sight(front, origin + circle.centre[0] * u + circle.centre[1] * v,
                         SIGHT_RADII * circle.radius) if np.isfinite(circle.radius) else 0
    rms = circle.rms
    if not (np.isfinite(circle.radius) and 0 < circle.radius <= max_extent):
        why = (f"its rim fits a circle of radius {circle.radius * mm:.0f} mm, beyond "
               f"{max_extent * mm:.0f} mm")
    elif rms > limit:
        why = (f"its rim fits a circle with an RMS of {rms * mm:.2f} mm where the scan's spacing "
               f"and noise allow {limit * mm:.2f} mm (not a round opening)")
    elif circle.coverage < MIN_COVERAGE:
        why = (f"its rim spans {np.degrees(circle.coverage):.0f} deg of the circle, fewer "
               f"than {np.degrees(MIN_COVERAGE):.0f}")
    elif inside > max(2, INSIDE_SHARE * len(rim)):
        why = (f"{inside} wall point(s) lie inside the circle its rim fits (r "
               f"{circle.radius * mm:.0f} mm): gaps between rows, not an opening")
    elif covering >= MIN_COVERING:
        why = (f"{covering} points standing off the wall lie within {SIGHT_RADII:g} radii of the "
               "line of sight to it (the shadow of an object, or a pipe's dark mouth, not an "
               "opening in the wall)")
    else:
        why = "ok"
    return Opening(circle, rim, rim_mask, rows, limit, inside, why)


def row_openings(p: NDArray, scan: Scan, u: NDArray, v: NDArray, radius: float | None,
                 max_extent: float) -> list[Opening]:
    """Openings found along the scan's rows (see the module's note), each weighed.

    Parameters
    ----------
    p : ndarray, shape (N, 3), m
    scan : Scan
        With rows (`scan.rings`).
    u, v : ndarray, shape (3,)
        The wall's in-plane directions.
    radius : float or None
        The opening's known radius (m).
    max_extent : float
        The largest radius an opening may have (m).
    """
    plane, rings = scan.plane, scan.rings
    n = len(p)
    origin = -plane.offset * plane.normal
    wall = np.flatnonzero(plane.inliers & (rings >= 0))
    az = np.arctan2(p[:, 1], p[:, 0])
    on_wall = _crossing(p[wall], plane.normal, plane.offset) - origin
    wall_xy = np.column_stack([on_wall @ u, on_wall @ v])
    order = np.lexsort((az[wall], rings[wall]))
    ring_sorted, az_sorted = rings[wall][order], az[wall][order]
    same = ring_sorted[1:] == ring_sorted[:-1]
    step = np.diff(az_sorted)
    # Each row's own step: the median of its steps.
    ids, row_index = np.unique(ring_sorted[1:][same], return_inverse=True)
    if not len(ids):
        return []
    medians = np.array([np.median(step[same][row_index == k]) for k in range(len(ids))]) \
        if len(ids) <= 4096 else np.full(len(ids), np.median(step[same]))
    row_step = np.zeros(len(step))
    row_step[same] = medians[row_index]
    gap = np.flatnonzero(same & (step > GAP_STEPS * np.maximum(row_step, 1e-9)))
    if len(gap) > MAX_GAPS:
        return [Opening(None, np.zeros((0, 2)), np.zeros(n, bool), 0, np.nan, 0,
                        f"{len(gap)} breaks along the rows: not a wall with an opening")]
    first, last = wall[order][gap], wall[order][gap + 1]          # the gap's two wall points
    a1, a2 = az[first], az[last]
    ring_of = rings[first]
    xy1, xy2 = wall_xy[order][gap], wall_xy[order][gap + 1]
    chord = np.linalg.norm(xy2 - xy1, axis=1)
    toward = (xy2 - xy1) / np.maximum(chord, 1e-12)[:, None]
    step_wall = np.linalg.norm(np.diff(wall_xy[order], axis=0), axis=1)[same]
    spacing = float(np.median(step_wall)) if len(step_wall) else scan.spacing
    h = p @ plane.normal + plane.offset
    # Returns through the opening (behind the wall) and shadows (in front of it), per gap.
    behind = np.flatnonzero((h < -scan.band) & (rings >= 0))
    front = np.flatnonzero((h > scan.band) & (rings >= 0))
    front_points = p[h > scan.band]
    edge1 = xy1 + 0.5 * spacing * toward
    edge2 = xy2 - 0.5 * spacing * toward
    shadow = np.zeros(len(gap), bool)
    if len(front):
        shadow = _any_between(rings[front], az[front], ring_of, a1, a2)
    if len(behind):
        through = _crossing(p[behind], plane.normal, plane.offset) - origin
        through_xy = np.column_stack([through @ u, through @ v])
        lo, hi = _first_last_between(rings[behind], az[behind], ring_of, a1, a2)
        has = lo >= 0
        edge1[has] = 0.5 * (xy1[has] + through_xy[lo[has]])
        edge2[has] = 0.5 * (xy2[has] + through_xy[hi[has]])
    keep = ~shadow & (chord <= 2 * max_extent + 2 * spacing)
    gap, ring_of, edge1, edge2, xy1, xy2 = (x[keep] for x in (gap, ring_of, edge1, edge2, xy1, xy2))
    first, last = first[keep], last[keep]
    if not len(gap):
        return []
    # Gaps of neighbouring rows that overlap along the rows make one opening.
    rank = np.searchsorted(np.unique(rings[wall]), ring_of)
    direction = np.median(toward[keep], axis=0)
    direction /= max(np.linalg.norm(direction), 1e-12)
    s1, s2 = edge1 @ direction, edge2 @ direction
    lo_u, hi_u = np.minimum(s1, s2), np.maximum(s1, s2)
    i, j = np.triu_indices(len(gap), 1)
    linked = (np.abs(rank[i] - rank[j]) <= 2) & (rank[i] != rank[j]) & \
        (lo_u[i] <= hi_u[j]) & (lo_u[j] <= hi_u[i])
    graph = coo_matrix((np.ones(linked.sum()), (i[linked], j[linked])),
                       shape=(len(gap), len(gap)))
    count, group = connected_components(graph, directed=False)
    # Rim estimates are rays' crossings with the wall (no range noise in them): their error
    # is the row's sampling, up to half a step either way (0.29 steps rms), and beam width.
    tol = rim_tolerance(spacing, plane.offset)
    openings = []
    for g in range(count):
        members = np.flatnonzero(group == g)
        rim = np.concatenate([edge1[members], edge2[members]])
        rim_mask = np.zeros(n, bool)
        rim_mask[first[members]] = True
        rim_mask[last[members]] = True
        rows = len(np.unique(ring_of[members]))
        limit = tol + (0.01 * radius if radius else 0.0)
        openings.append(_judge(rim, rim_mask, rows, radius, wall_xy, front_points,
                               (origin, u, v), limit, max_extent, 2 if radius is not None else 3))
    return openings


def _any_between(ring: NDArray, az: NDArray, gap_ring: NDArray, a1: NDArray,
                 a2: NDArray) -> NDArray:
    """Per gap, whether a point of its ring has an azimuth strictly between a1 and a2."""
    lo, _ = _first_last_between(ring, az, gap_ring, a1, a2)
    return lo >= 0


def _first_last_between(ring: NDArray, az: NDArray, gap_ring: NDArray, a1: NDArray,
                        a2: NDArray) -> tuple[NDArray, NDArray]:
    """Per gap, the index (into ring/az) of the first and last point of its ring with an
    azimuth between a1 and a2 (-1 where none), by one sort and two binary searches."""
    order = np.lexsort((az, ring))
    key_ring, key_az = ring[order], az[order]
    # Points sorted by (ring, azimuth): search within each gap's ring for its azimuth range.
    lo_key = np.searchsorted(key_ring, gap_ring, side="left")
    hi_key = np.searchsorted(key_ring, gap_ring, side="right")
    first = np.full(len(gap_ring), -1)
    last = np.full(len(gap_ring), -1)
    for k in np.flatnonzero(hi_key > lo_key):        # per gap: tens, not points
        seg = key_az[lo_key[k]:hi_key[k]]
        s = lo_key[k] + np.searchsorted(seg, a1[k], side="right")
        e = lo_key[k] + np.searchsorted(seg, a2[k], side="left") - 1
        if e >= s:
            first[k], last[k] = order[s], order[e]
    return first, last


def grid_openings(p: NDArray, scan: Scan, u: NDArray, v: NDArray, radius: float | None,
                  max_extent: float) -> list[Opening]:
    """Openings of a cloud without rows: empty regions of an occupancy grid of the wall's
    points, each rim fitted and weighed (see the module's note)."""
    plane = scan.plane
    n = len(p)
    origin = -plane.offset * plane.normal
    inl = plane.inliers
    on_wall = _crossing(np.compress(inl, p, axis=0), plane.normal, plane.offset) - origin
    xy = np.column_stack([on_wall @ u, on_wall @ v])
    cell = 2.5 * scan.spacing
    lo = xy.min(axis=0)
    ij = np.floor((xy - lo) / cell).astype(np.int64)
    shape = ij.max(axis=0) + 1
    if shape.prod() > 4_000_000:
        return [Opening(None, np.zeros((0, 2)), np.zeros(n, bool), 0, np.nan, 0,
                        "the wall is too sparse for an opening search")]
    occupied = np.zeros(shape, bool)
    occupied[ij[:, 0], ij[:, 1]] = True
    regions, count = ndimage.label(~occupied)
    if count == 0:
        return []
    border = np.unique(np.concatenate([regions[0], regions[-1], regions[:, 0], regions[:, -1]]))
    sizes = np.bincount(regions.ravel(), minlength=count + 1).astype(float)
    sizes[0] = 0
    sizes[border] = 0
    area = sizes * cell * cell
    r_area = np.sqrt(area / np.pi)
    ok = (area > 0) & (r_area <= max_extent) & (r_area >= cell)
    h_all = p @ plane.normal + plane.offset
    front_points = p[h_all > scan.band]
    front_wall = _crossing(front_points, plane.normal, plane.offset) - origin
    front_xy = np.column_stack([front_wall @ u, front_wall @ v])
    behind = h_all < -scan.band
    through = _crossing(p[behind], plane.normal, plane.offset) - origin
    through_xy = np.column_stack([through @ u, through @ v])
    wall_idx = np.flatnonzero(inl)
    spacing = scan.spacing
    limit = rim_tolerance(spacing, plane.offset) + (0.01 * radius if radius else 0.0)
    openings = []
    for best in np.flatnonzero(ok)[:50]:              # regions: a handful, not points
        cells = np.argwhere(regions == best)
        rough = lo + (cells.mean(axis=0) + 0.5) * cell
        rho = float(np.sqrt(len(cells) / np.pi) * cell)
        covering = int((np.linalg.norm(front_xy - rough, axis=1) < rho + cell).sum())
        if covering >= 10:
            openings.append(Opening(None, np.zeros((0, 2)), np.zeros(n, bool), 0, limit, 0,
                                    f"the gap in the wall lies behind {covering} points "
                                    "standing off it (a shadow, not an opening)"))
            continue
        rim, rim_mask = _grid_rim(xy, through_xy, rough, rho, cell, spacing, wall_idx, n)
        openings.append(_judge(rim, rim_mask, 0, radius, xy, front_points, (origin, u, v),
                               limit, max_extent, 0))
    return openings


def _grid_rim(xy, through_xy, rough, rho, cell, spacing, wall_idx, n):
    """Rim estimates of a grid opening: per angular sector the innermost wall point, moved
    half a spacing inward, or midway to the outermost return through the opening."""
    sectors = 90

    def innermost(points2: NDArray, outer: bool) -> tuple[NDArray, NDArray]:
        d = points2 - rough
        r = np.linalg.norm(d, axis=1)
        s = np.floor((np.arctan2(d[:, 1], d[:, 0]) + np.pi) / (2 * np.pi) * sectors)
        s = np.clip(s.astype(np.int64), 0, sectors - 1)
        order = np.lexsort((-r if outer else r, s))
        first = np.ones(len(order), bool)
        first[1:] = s[order][1:] != s[order][:-1]
        pick = order[first]
        return s[pick], pick

    near = np.linalg.norm(xy - rough, axis=1) < rho + 4 * cell
    sec_w, pick_w = innermost(xy[near], outer=False)
    rim_wall = np.full((sectors, 2), np.nan)
    rim_wall[sec_w] = xy[near][pick_w]
    rim_mask = np.zeros(n, bool)
    rim_mask[wall_idx[np.flatnonzero(near)[pick_w]]] = True
    radial = rim_wall - rough
    radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-12)
    rim = rim_wall - 0.5 * spacing * radial
    inside = np.linalg.norm(through_xy - rough, axis=1) < rho + 4 * cell
    if inside.sum() >= 3:
        sec_b, pick_b = innermost(through_xy[inside], outer=True)
        through = np.full((sectors, 2), np.nan)
        through[sec_b] = through_xy[inside][pick_b]
        both = ~np.isnan(rim_wall[:, 0]) & ~np.isnan(through[:, 0])
        both[both] = (np.linalg.norm(through[both] - rough, axis=1)
                      < np.linalg.norm(rim_wall[both] - rough, axis=1))
        rim[both] = 0.5 * (rim_wall[both] + through[both])
    return rim[~np.isnan(rim[:, 0])], rim_mask
