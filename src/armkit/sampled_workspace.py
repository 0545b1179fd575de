"""Workspace by Monte Carlo: bounds, reach, voxel volume and sections, locally or on Dask.

Joint vectors are drawn uniformly inside the limits, chunk by chunk, and each chunk's tool
positions are reduced at once to a few numbers and a sparse set of occupied voxels; no chunk's
points are kept (beyond a bounded sample for pictures), so memory does not grow with the number
of samples. Chunk i draws from ``np.random.default_rng([seed, i])``, and every reduction (min,
max, sums of integer counts, set union) is exact and independent of order: the same seed and
chunk size give the same bounds and voxels in one process or on a Dask cluster.

The voxel grid is anchored at the base origin: voxel ``(i, j, k)`` is the cube
``[i h, (i + 1) h) x [j h, (j + 1) h) x [k h, (k + 1) h)`` for the resolution h.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.jit import numba_threads
from armkit.kinematics import fk
from armkit.model.robot import Robot

CHUNK = 2**17       # samples per chunk: 16 MB of poses, large enough for the parallel FK kernel
CLOUD = 20_000      # tool positions kept for pictures
HISTORY = 10        # volumes kept at n, n/2, n/4, ...
TASK_CHUNKS = 8     # chunks per Dask task at most: about a second of work

# A voxel's key packs its three indices, each offset by 2**13, into 42 bits; the sample's index
# within its chunk fills the 21 bits below, so that one plain sort of (key, index) gives each
# voxel's first sample. Hence at most 2**13 voxels on each side of the base origin.
_AXIS_BITS, _INDEX_BITS = 14, 21
_OFFSET = 1 << (_AXIS_BITS - 1)
_AXIS_MASK, _INDEX_MASK = (1 << _AXIS_BITS) - 1, (1 << _INDEX_BITS) - 1
MAX_VOXELS = _OFFSET - 2        # per side of the origin, with a margin for rounding
MAX_CHUNK = 1 << _INDEX_BITS


@dataclass(frozen=True, eq=False)
class Section:
    """The occupied cells of a workspace in one plane, at the workspace's resolution.

    Attributes
    ----------
    plane : {"horizontal", "vertical"}
        A horizontal plane ``z = position``, or a vertical plane through the base z axis at
        azimuth ``position`` from the x axis.
    position : float
        The height (m) or the azimuth (rad).
    occupied : ndarray of bool, shape (rows, cols)
        ``occupied[j, i]`` is the cell ``[u0 + i h, u0 + (i + 1) h) x [v0 + j h, v0 + (j + 1) h)``
        with ``(u0, _, v0, _) = extent`` and h the resolution. The plane's axes (u, v) are
        (x, y) for a horizontal plane, and (r, z) for a vertical one, r being the signed
        horizontal distance from the z axis along the azimuth.
    extent : ndarray, shape (4,)
        ``u_min, u_max, v_min, v_max`` (m): matplotlib's ``imshow`` extent for
        ``origin="lower"``.
    resolution : float
        Cell edge (m), the voxel edge of the workspace.
    area : float
        Occupied area (m^2): occupied cells times resolution squared.
    """

    plane: str
    position: float
    occupied: NDArray
    extent: NDArray
    resolution: float
    area: float


@dataclass(frozen=True, eq=False)
class Workspace:
    """Monte Carlo workspace of a robot's tool origin, in the base frame, SI.

    Attributes
    ----------
    robot : Robot
    samples : int
        Joint vectors drawn, n.
    seed : int
        The seed; chunk i drew from ``np.random.default_rng([seed, i])``.
    chunk : int
        Samples per chunk (the last chunk may hold fewer).
    resolution : float
        Voxel edge (m).
    lower, upper : ndarray, shape (3,)
        Axis-aligned bounds of the tool positions (m).
    reach : float
        Largest distance of the tool from the base origin (m).
    radial_reach : float
        Largest distance of the tool from the base z axis (m).
    volume : float
        Volume of the occupied voxels (m^3). It converges, as samples grow, on the volume of
        the voxels the workspace touches, which exceeds the workspace's own volume by up to
        one voxel layer over its surface.
    volume_change : float
        Relative growth of the volume over the last doubling of the samples,
        ``(V(n) - V(n // 2)) / V(n)``; near 0 once the estimate has converged at this
        resolution (NaN for n < 2 or an empty workspace).
    volume_history : ndarray, shape (k, 2)
        Rows ``(m, V(m))`` for m = ..., n // 4, n // 2, n: the volume the first m samples
        occupy (m^3).
    voxels : ndarray of int64, shape (V, 3)
        Indices ``(i, j, k)`` of the occupied voxels, in lexicographic order.
    counts : ndarray of int64, shape (V,)
        Samples in each voxel.
    first : ndarray of int64, shape (V,)
        Index of the first sample in each voxel (samples are numbered chunk after chunk).
    cloud : ndarray, shape (min(n, cloud), 3)
        Tool positions of the first samples (m), a uniform random subset for pictures.
    """

    robot: Robot
    samples: int
    seed: int
    chunk: int
    resolution: float
    lower: NDArray
    upper: NDArray
    reach: float
    radial_reach: float
    volume: float
    volume_change: float
    volume_history: NDArray
    voxels: NDArray
    counts: NDArray
    first: NDArray
    cloud: NDArray

    def horizontal_section(self, height: float) -> Section:
        """The occupied cells in the horizontal plane ``z = height``.

        Parameters
        ----------
        height : float
            m, in the base frame. The section is the voxel layer that holds the plane (the
            upper one when the plane lies on a voxel boundary).

        Returns
        -------
        Section
            Cells over the workspace's x-y extent; empty if the plane misses the workspace.
        """
        height = finite_number("height", height)
        h = self.resolution
        ij = self.voxels[self.voxels[:, 2] == math.floor(height / h), :2]
        (i0, j0), (i1, j1) = self.voxels[:, :2].min(axis=0), self.voxels[:, :2].max(axis=0) + 1
        occupied = np.zeros((j1 - j0, i1 - i0), dtype=bool)
        occupied[ij[:, 1] - j0, ij[:, 0] - i0] = True
        return _section("horizontal", height, occupied, np.array([i0, i1, j0, j1]) * h, h)

    def vertical_section(self, azimuth: float = 0.0) -> Section:
        """The occupied cells in the vertical plane through the base z axis at `azimuth`.

        Parameters
        ----------
        azimuth : float
            rad, from the base x axis towards y. A cell (r, z) of the plane is occupied if the
            voxel holding its centre ``(r cos(azimuth), r sin(azimuth), z)`` is.

        Returns
        -------
        Section
            Axes (r, z): r from -radial_reach to radial_reach, z over the workspace's height.
        """
        azimuth = finite_number("azimuth", azimuth)
        h = self.resolution
        r_cells = math.ceil(self.radial_reach / h) + 1
        k0, k1 = self.voxels[:, 2].min(), self.voxels[:, 2].max() + 1
        r = (np.arange(-r_cells, r_cells) + 0.5) * h
        cells = np.empty((k1 - k0, r.size, 3), dtype=np.int64)
        cells[..., :2] = np.floor(np.multiply.outer(r, [math.cos(azimuth),
                                                        math.sin(azimuth)]) / h)
        cells[..., 2] = np.arange(k0, k1)[:, None]
        occupied = _member(_keys(*np.moveaxis(cells, -1, 0)), _keys(*self.voxels.T))
        extent = np.array([-r_cells * h, r_cells * h, k0 * h, k1 * h])
        return _section("vertical", azimuth, occupied, extent, h)


def _section(plane: str, position: float, occupied: NDArray, extent: NDArray,
             h: float) -> Section:
    occupied.setflags(write=False)
    extent = np.asarray(extent, dtype=float)
    extent.setflags(write=False)
    return Section(plane, position, occupied, extent, h, float(occupied.sum()) * h * h)


def finite_number(name: str, value: Any) -> float:
    """`value` as a finite float; else an InputError naming `name`."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a number, found {value!r}") from None
    if not math.isfinite(x):
        raise InputError(f"{name}: expected a finite number, found {x}")
    return x


def whole_number(name: str, value: Any, low: int, high: int | None = None) -> int:
    """`value` as an int in [low, high]; integral floats such as 1e6 pass."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                    np.floating)):
        raise InputError(f"{name}: expected a whole number, found {value!r}")
    if not (math.isfinite(value) and value == int(value)):
        raise InputError(f"{name}: expected a whole number, found {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        limit = f"at least {low}" if high is None else f"{low} .. {high}"
        raise InputError(f"{name}: expected {limit}, found {value}")
    return value


def _require_bounded(robot: Robot) -> None:
    """A prismatic joint without finite limits has an unbounded workspace: refuse it."""
    endless = ~(np.isfinite(robot.lower) & np.isfinite(robot.upper))
    for name, revolute, lo, hi, bad in zip(robot.joint_names, robot.chain.revolute, robot.lower,
                                           robot.upper, endless):
        if bad and not revolute:
            raise InputError(f"robot: expected finite limits on prismatic joint {name}, "
                             f"found {lo} .. {hi}")


def reach_bound(robot: Robot, lower: NDArray, upper: NDArray) -> float:
    """An upper bound on the tool's distance from the base origin (m), from the link lengths.

    The tool position is a sum of the chain's fixed translations and the prismatic joints'
    travel, each turned by rotations, so its length is at most the sum of their lengths.
    """
    k = robot.chain.kernel
    travel = np.abs(k.motion_ends(lower, upper)).max(axis=0)
    return float(np.linalg.norm(k.pre[:3, 3]) + np.linalg.norm(k.links[:, :3, 3], axis=1).sum()
                 + travel[k.kinds == 1].sum())


def default_resolution(bound: float) -> float:
    """1/50 of the diameter `2 bound` of the ball that holds the workspace, rounded down to
    1, 2 or 5 times a power of ten (m)."""
    if not bound > 0:
        return 1.0
    step = 2.0 * bound / 50.0
    power = 10.0 ** math.floor(math.log10(step))
    return max(m for m in (1.0, 2.0, 5.0) if m * power <= step * (1 + 1e-12)) * power


@dataclass(frozen=True, eq=False)
class _Plan:
    """What every chunk needs; sent once to each Dask worker."""

    robot: Robot
    lower: NDArray
    upper: NDArray
    seed: int
    samples: int
    chunk: int
    resolution: float
    cloud: int

    @property
    def chunks(self) -> int:
        return -(-self.samples // self.chunk)


@dataclass(frozen=True, eq=False)
class _Partial:
    """The reduction of some chunks: bounds, largest squared reaches, sparse voxel counts."""

    lower: NDArray          # (3,)
    upper: NDArray          # (3,)
    reach2: float
    radial2: float
    keys: NDArray           # (V,) sorted voxel keys
    counts: NDArray         # (V,)
    first: NDArray          # (V,) global index of the first sample in the voxel
    cloud: tuple            # ((start, positions (k, 3)), ...), the pieces below plan.cloud


def _keys(i: NDArray, j: NDArray, k: NDArray) -> NDArray:
    """Voxel indices (int64, one shape) packed into keys that sort as (i, j, k) do."""
    return ((i + _OFFSET) << 2 * _AXIS_BITS) | ((j + _OFFSET) << _AXIS_BITS) | (k + _OFFSET)


def _member(keys: NDArray, sorted_keys: NDArray) -> NDArray:
    """Whether each key is in the sorted, non-empty `sorted_keys`; the shape of `keys`."""
    found = np.searchsorted(sorted_keys, keys).clip(max=sorted_keys.size - 1)
    return sorted_keys[found] == keys


def _indices(keys: NDArray) -> NDArray:
    """Inverse of `_keys`: (V,) keys to (V, 3) voxel indices."""
    shifts = np.array([2 * _AXIS_BITS, _AXIS_BITS, 0])
    return ((keys[:, None] >> shifts) & _AXIS_MASK) - _OFFSET


def _chunk(plan: _Plan, index: int) -> _Partial:
    """Sample chunk `index`, run FK, and reduce its tool positions."""
    start = index * plan.chunk
    size = min(plan.chunk, plan.samples - start)
    q = np.random.default_rng([plan.seed, index]).uniform(plan.lower, plan.upper,
                                                          (size, plan.robot.n))
    x, y, z = p = np.ascontiguousarray(fk(plan.robot, q)[:, :3, 3].T)     # (3, size)
    del q
    radial2 = x * x + y * y
    key = _keys(*np.floor(p / plan.resolution).astype(np.int64))
    tagged = np.sort((key << _INDEX_BITS) | np.arange(size))
    keys = tagged >> _INDEX_BITS
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    kept = min(size, max(0, plan.cloud - start))
    return _Partial(p.min(axis=1), p.max(axis=1), float((radial2 + z * z).max()),
                    float(radial2.max()), keys[starts], np.diff(np.r_[starts, size]),
                    (tagged[starts] & _INDEX_MASK) + start,
                    ((start, p[:, :kept].T.copy()),) if kept else ())


def _merge(a: _Partial, b: _Partial) -> _Partial:
    """One partial for the chunks of both; exact and independent of order."""
    keys = np.concatenate([a.keys, b.keys])
    order = np.argsort(keys, kind="stable")     # two sorted runs: a linear merge
    keys = keys[order]
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    return _Partial(np.minimum(a.lower, b.lower), np.maximum(a.upper, b.upper),
                    max(a.reach2, b.reach2), max(a.radial2, b.radial2), keys[starts],
                    np.add.reduceat(np.concatenate([a.counts, b.counts])[order], starts),
                    np.minimum.reduceat(np.concatenate([a.first, b.first])[order], starts),
                    tuple(sorted(a.cloud + b.cloud, key=lambda piece: piece[0])))


def _chunks(plan: _Plan, first: int, stop: int,
            progress: Callable[[int, int], None] | None = None) -> _Partial:
    """Chunks first .. stop - 1 in order, merged as a binary counter: a partial of level l
    holds 2**l chunks, so each voxel is merged about log2(chunks) times and at most
    log2(chunks) partials wait."""
    stack: list[tuple[int, _Partial]] = []
    for i in range(first, stop):
        part, level = _chunk(plan, i), 0
        while stack and stack[-1][0] == level:
            part, level = _merge(stack.pop()[1], part), level + 1
        stack.append((level, part))
        if progress is not None:
            progress(min((i + 1) * plan.chunk, plan.samples), plan.samples)
    part = stack.pop()[1]
    while stack:
        part = _merge(stack.pop()[1], part)
    return part


def _task(plan: _Plan, first: int, stop: int) -> _Partial:
    """`_chunks` as a Dask task, with one numba thread: the worker's own threads fill its
    cores already, and more threads than cores would only wait for each other."""
    with numba_threads(1):
        return _chunks(plan, first, stop)


def _scheduler_address(address: str) -> str:
    """`address` if it is a Dask address armkit can connect to, checked before any
    connection: a Client made from a malformed address fails, and then, when it is collected,
    hangs 20 s in its own close and prints a traceback."""
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port
    from distributed.comm.registry import backends

    expected = "an address such as tcp://127.0.0.1:8786"
    try:
        scheme, location = parse_address(address.strip(), strict=True)
    except (ValueError, TypeError):
        raise InputError(f"scheduler: expected {expected}, found {address!r}") from None
    if scheme not in backends:
        raise InputError(f"scheduler: expected {expected} (schemes: "
                         f"{', '.join(sorted(backends))}), found {address!r}")
    if scheme != "inproc":
        try:
            host, port = parse_host_port(location)
        except (ValueError, TypeError):
            raise InputError(f"scheduler: expected {expected} (a host and a port), "
                             f"found {address!r}") from None
        if not host or not 0 < port < 65536:
            raise InputError(f"scheduler: expected {expected} (a host and a port 1..65535), "
                             f"found {address!r}")
    return address.strip()


def dask_client(scheduler: Any):
    """(client, whether we opened it) for a `distributed.Client` or a scheduler address,
    checked before any connection (`_scheduler_address`); a missing dask or an unreachable
    scheduler is an InputError naming ``scheduler``."""
    try:
        from distributed import Client
    except ImportError:
        raise InputError("scheduler: expected dask.distributed to be installed "
                         "(pip install 'armkit[dask]'), found it missing") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str):
        raise InputError("scheduler: expected an address such as tcp://127.0.0.1:8786 or a "
                         f"distributed.Client, found {type(scheduler).__name__}")
    address = _scheduler_address(scheduler)
    try:
        return Client(address, timeout="10s", set_as_default=False), True
    except (OSError, TimeoutError, ValueError) as err:
        raise InputError(f"scheduler: expected a Dask scheduler at {address}, "
                         f"found none ({err})") from None


def _run_dask(plan: _Plan, client, progress: Callable[[int, int], None] | None) -> _Partial:
    """Runs of up to TASK_CHUNKS chunks as tasks, two in flight per worker thread; their
    partials merged pairwise on the workers as they come, so that one partial comes back."""
    from distributed import as_completed

    threads = sum(client.nthreads().values()) or 1
    size = max(1, min(TASK_CHUNKS, plan.chunks // (2 * threads)))
    runs = iter(range(0, plan.chunks, size))
    shared = client.scatter(plan, broadcast=True, hash=False)
    samples: dict[str, int] = {}            # key of a chunk run -> its samples

    def submit_run() -> list:
        first = next(runs, None)
        if first is None:
            return []
        stop = min(first + size, plan.chunks)
        future = client.submit(_task, shared, first, stop, pure=False)
        samples[future.key] = min(stop * plan.chunk, plan.samples) - first * plan.chunk
        return [future]

    # A Client made for this call is not the default one (set_as_default=False, so that a
    # user's own default stays theirs): as_completed must be given its loop.
    running = as_completed([f for _ in range(2 * threads) for f in submit_run()],
                           loop=client.loop)
    held, done = None, 0
    for future in running:
        if future.key in samples:
            done += samples.pop(future.key)
            running.update(submit_run())
            if progress is not None:
                progress(done, plan.samples)
        if held is None:
            held = future
        else:
            running.add(client.submit(_merge, held, future, pure=False))
            held = None
    try:
        return held.result()
    except Exception as err:            # a worker's failure comes back as the worker's error
        raise InputError(f"scheduler: expected workers that run armkit, found "
                         f"{type(err).__name__}: {err}") from None


def workspace(robot: Robot, n: int, *, seed: int | None = 0, resolution: float | None = None,
              chunk: int = CHUNK, cloud: int = CLOUD, scheduler: Any = None,
              progress: Callable[[int, int], None] | None = None) -> Workspace:
    """Monte Carlo workspace of the tool origin: bounds, reach, voxel volume, sections.

    Joint vectors are drawn uniformly inside the joint limits (rad for revolute, m for
    prismatic joints), `Robot.sampling_limits`: a revolute joint without finite limits, such
    as a URDF continuous joint, is drawn over one turn. Tool positions come from `armkit.fk`,
    chunk by chunk, and are reduced as they come: memory depends on the chunk size and the
    number of occupied voxels, not on n.

    Parameters
    ----------
    robot : Robot
    n : int
        Number of joint vectors to draw (>= 1).
    seed : int or None
        Seed (>= 0); chunk i draws from ``np.random.default_rng([seed, i])``. None draws a
        fresh seed, reported in the result.
    resolution : float or None
        Voxel edge (m). None: 1/50 of the diameter of a ball that surely holds the workspace
        (its radius is the sum of the link lengths and prismatic travels), rounded down to
        1, 2 or 5 times a power of ten. At most 8190 voxels fit on each side of the base
        origin.
    chunk : int
        Samples per chunk, 1 .. 2**21. Results depend on (seed, chunk), not on where or in
        which order chunks run.
    cloud : int
        How many tool positions to keep for pictures (the first ones drawn).
    scheduler : None, str or distributed.Client
        None runs in this process. An address (``"tcp://host:8786"``) or a Client runs the
        chunks as tasks on that Dask cluster, whose workers must be able to import armkit;
        the result is identical to a local run with the same seed and chunk.
    progress : callable or None
        Called as ``progress(samples_done, n)`` after each chunk.

    Returns
    -------
    Workspace

    Raises
    ------
    InputError
        If an argument is out of range, a prismatic joint has no finite limits, the resolution
        is too fine for the robot's size, or the scheduler cannot be reached.

    Example
    -------
    >>> ws = armkit.workspace(armkit.robot("inspection_6dof"), 200_000, resolution=0.1)
    >>> round(ws.reach, 2)              # m: the arm's full reach (1.5620 m), nearly attained
    1.56
    >>> round(ws.volume, 1), round(ws.volume_change, 2)    # m^3, and its growth from n/2 to n
    (13.7, 0.09)
    """
    if not isinstance(robot, Robot):
        raise InputError(f"robot: expected a Robot (see armkit.robot), "
                         f"found {type(robot).__name__}")
    n = whole_number("n", n, 1)
    seed = (int(np.random.SeedSequence().entropy) if seed is None
            else whole_number("seed", seed, 0))
    chunk = whole_number("chunk", chunk, 1, MAX_CHUNK)
    cloud = whole_number("cloud", cloud, 0)
    _require_bounded(robot)
    lower, upper = robot.sampling_limits
    bound = reach_bound(robot, lower, upper)
    if resolution is None:
        resolution = default_resolution(bound)
    resolution = finite_number("resolution", resolution)
    if not resolution > 0:
        raise InputError(f"resolution: expected a positive voxel edge (m), found {resolution}")
    if bound / resolution > MAX_VOXELS:
        raise InputError(f"resolution: expected at least {bound / MAX_VOXELS:.3g} m for "
                         f"{robot.name} (at most {MAX_VOXELS} voxels on each side of the base), "
                         f"found {resolution:g}")
    plan = _Plan(robot, lower, upper, seed, n, chunk, resolution, cloud)
    if scheduler is None:
        part = _chunks(plan, 0, plan.chunks, progress)
    else:
        client, opened = dask_client(scheduler)
        try:
            part = _run_dask(plan, client, progress)
        finally:
            if opened:
                client.close()
    return _result(plan, part)


def _result(plan: _Plan, part: _Partial) -> Workspace:
    h, n = plan.resolution, plan.samples
    first_sorted = np.sort(part.first)
    sizes = np.unique([n >> j for j in range(HISTORY) if n >> j >= 1])
    volumes = np.searchsorted(first_sorted, sizes) * h**3
    history = np.column_stack([sizes, volumes])
    volume = float(volumes[-1])
    change = ((volume - volumes[-2]) / volume if sizes.size >= 2 and volume > 0
              else float("nan"))
    cloud = (np.concatenate([p for _, p in part.cloud]) if part.cloud else np.empty((0, 3)))
    arrays = dict(lower=part.lower, upper=part.upper, volume_history=history,
                  voxels=_indices(part.keys), counts=part.counts, first=part.first, cloud=cloud)
    for a in arrays.values():
        a.setflags(write=False)
    return Workspace(robot=plan.robot, samples=n, seed=plan.seed, chunk=plan.chunk,
                     resolution=h, reach=math.sqrt(part.reach2),
                     radial_reach=math.sqrt(part.radial2), volume=volume,
                     volume_change=float(change), **arrays)
