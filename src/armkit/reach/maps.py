"""Reachability maps: per voxel of space, the share of tool orientations inverse kinematics
reaches (within the joint limits, and free of collision with a scene), which ones, and the best
manipulability of the solutions.

The voxels are those the Monte Carlo workspace (`armkit.workspace`) occupies at the map's
resolution, and their neighbours (one voxel more all round, so that a voxel the sampling
missed at the rim is tried too); voxel ``(i, j, k)`` is the cube ``[i h, (i + 1) h) x ...``
of the workspace's grid, tried at its centre ``((i, j, k) + 1/2) h``. At every centre each
orientation of an `Orientations` set is one IK problem: every closed-form solution where the
arm has a closed form for the task (`IKSolver.family`), else one numeric solution
(Levenberg-Marquardt from the seed bank's nearest starts, then random restarts: a numeric map
is a lower bound, a problem it fails may still have a solution).

The voxels are solved chunk by chunk (`chunk` voxels at a time, all their orientations in one
batch) and each chunk is reduced at once to three small arrays per voxel (`MapChunk`), so
memory holds the map and a few chunks, never every solution. Chunks run on threads in this
process or as tasks on a Dask cluster given by its scheduler's address; a chunk's result
depends only on the settings and its index (the numeric solver's random restarts are seeded
from both), so the map is bit-identical wherever and in whatever order its chunks run. A
`checkpoint` store keeps finished chunks, and a run with the same settings takes them from it
instead of solving them again: an interrupted map resumes (`armkit.io.reach_maps` keeps them in
a folder).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.jit import kernel, numba_threads
from armkit.kinematics import core
from armkit.kinematics.ik import IKSolver
from armkit.kinematics.ik.analytic import candidates
from armkit.model.robot import Robot
from armkit.reach.orientations import Orientations, default_orientations
from armkit.sampled_workspace import (dask_client, default_resolution, finite_number,
                                      reach_bound, whole_number, workspace)
from armkit.threads import get_num_threads

TARGETS_PER_CHUNK = 16_384      # IK problems per chunk: about 50 ms of closed-form work
SAMPLES_PER_VOXEL = 32          # Monte Carlo samples per voxel of the reach ball
MIN_SAMPLES = 1_000_000
TOLERANCE = 1e-9                # m and rad: an IK solution reaches its target (IKSolver's)
RESTARTS = 8                    # numeric restarts per problem after the seed bank's starts
METHODS = ("auto", "analytic", "lm", "newton")
TASK_CHUNKS = 8                 # chunks per Dask task at most
# Voxel keys pack the three indices, each offset by 2**20, into 21 bits each.
_BITS = 21
_OFFSET = 1 << (_BITS - 1)


@dataclass(frozen=True, eq=False)
class MapChunk:
    """What a map keeps of one chunk of voxels (v of them, K orientations).

    Attributes
    ----------
    count : ndarray of int64, shape (v,)
        Orientations reached.
    reached : ndarray of uint8, shape (v, ceil(K / 8))
        Which: bit k of the voxel's row (``np.packbits(..., bitorder="little")``).
    manipulability : ndarray, shape (v,)
        The largest Yoshikawa manipulability of the solutions that reach any orientation; 0
        where none does.
    """

    count: NDArray
    reached: NDArray
    manipulability: NDArray


class Checkpoint(Protocol):
    """Where a map keeps its finished chunks (`armkit.io.reach_maps.ChunkFolder`)."""

    def start(self, key: str, sizes: list[int], orientations: int) -> dict[int, MapChunk]:
        """Begin (or resume) the map of settings `key`, whose chunk i holds sizes[i] voxels of
        `orientations` each: the chunks finished before, by index."""

    def save(self, index: int, chunk: MapChunk) -> None:
        """Keep chunk `index`, finished."""


@dataclass(frozen=True, eq=False)
class IndexSection:
    """The reachability index in one plane of a map, cell by cell.

    Attributes
    ----------
    plane : {"horizontal", "vertical"}
    position : float
        Height (m) of a horizontal plane, or azimuth (rad) of a vertical plane through the
        base z axis.
    index : ndarray, shape (rows, cols)
        ``index[j, i]`` for the cell ``[u0 + i h, u0 + (i + 1) h) x [v0 + j h, ...)``; NaN
        where the map has no voxel. Axes (u, v): (x, y), or (r, z) with r the signed
        horizontal distance from the z axis along the azimuth.
    extent : ndarray, shape (4,)
        ``u_min, u_max, v_min, v_max`` (m), matplotlib's extent for ``origin="lower"``.
    resolution : float
        Cell edge (m).
    """

    plane: str
    position: float
    index: NDArray
    extent: NDArray
    resolution: float


@dataclass(frozen=True, eq=False)
class ReachMap:
    """A reachability map of a robot's tool in its base frame, SI.

    Attributes
    ----------
    robot : Robot
    resolution : float
        Voxel edge h (m).
    voxels : ndarray of int64, shape (V, 3)
        Indices ``(i, j, k)``, lexicographic; voxel centres ``(voxels + 0.5) h``.
    count : ndarray of int64, shape (V,)
        Orientations reached per voxel.
    reached : ndarray of uint8, shape (V, ceil(K / 8))
        Which orientations, packed bits (see `reached_at`).
    manipulability : ndarray, shape (V,)
        Best Yoshikawa manipulability of the solutions per voxel (`armkit.manipulability`,
        all six rows); 0 where nothing is reached.
    orientations : Orientations
    settings : dict
        How the map was made: method, restarts, seed, samples, chunk, obstacles (their
        number, or None without a scene), collision_resolution, key (a hash of everything the
        chunks depend on), robot (`robot_key`) and armkit (the version).
    """

    robot: Robot
    resolution: float
    voxels: NDArray
    count: NDArray
    reached: NDArray
    manipulability: NDArray
    orientations: Orientations
    settings: dict = field(default_factory=dict)

    @property
    def index(self) -> NDArray:
        """The reachability index (V,): share of the orientations reached, 0 .. 1."""
        return self.count / len(self.orientations)

    @property
    def centers(self) -> NDArray:
        """Voxel centres (V, 3), m."""
        return (self.voxels + 0.5) * self.resolution

    @property
    def volume(self) -> float:
        """Volume of the voxels where some orientation is reached (m^3)."""
        return float(np.count_nonzero(self.count)) * self.resolution**3

    def reached_at(self, voxel: int) -> NDArray:
        """Which orientations voxel number `voxel` reaches, (K,) bool."""
        bits = np.unpackbits(self.reached[voxel], bitorder="little")
        return bits[:len(self.orientations)].astype(bool)

    def find(self, p: ArrayLike) -> NDArray:
        """Row of the voxel holding each point p (..., 3) m, or -1 where the map has none."""
        p = np.asarray(p, dtype=float)
        ijk = np.floor(p / self.resolution)
        inside = np.all(np.abs(ijk) < _OFFSET - 1, axis=-1) & np.isfinite(p).all(axis=-1)
        keys = voxel_keys(np.where(inside[..., None], ijk, 0).astype(np.int64))
        known = voxel_keys(self.voxels)                 # sorted: the voxels are lexicographic
        row = np.searchsorted(known, keys).clip(max=len(known) - 1)
        return np.where(inside & (known[row] == keys), row, -1)

    def index_at(self, p: ArrayLike) -> NDArray:
        """The reachability index (...,) of the voxel holding each point p (..., 3); 0 outside
        the map."""
        row = self.find(p)
        return np.where(row >= 0, self.index[row.clip(min=0)], 0.0)

    def lookup(self, T: ArrayLike) -> tuple[NDArray, NDArray]:
        """For tool poses T (..., 4, 4): the index of the voxel holding each position, and
        whether the map reached the orientation nearest it (`Orientations.nearest`) there.

        Returns
        -------
        index : ndarray, (...,)
        reached : ndarray of bool, (...,)
            False outside the map.
        """
        T = np.asarray(T, dtype=float)
        row = self.find(T[..., :3, 3])
        safe = row.clip(min=0)
        k = self.orientations.nearest(T[..., :3, :3], self.centers[safe], self.robot)
        bit = (self.reached[safe, k // 8] >> (k % 8)) & 1
        return (np.where(row >= 0, self.index[safe], 0.0),
                (row >= 0) & (bit == 1))

    def horizontal_section(self, height: float) -> IndexSection:
        """The index in the voxel layer holding the plane ``z = height`` (m)."""
        h = self.resolution
        layer = self.voxels[:, 2] == math.floor(finite_number("height", height) / h)
        (i0, j0), (i1, j1) = self.voxels[:, :2].min(axis=0), self.voxels[:, :2].max(axis=0) + 1
        index = np.full((j1 - j0, i1 - i0), np.nan)
        ij = self.voxels[layer, :2]
        index[ij[:, 1] - j0, ij[:, 0] - i0] = self.index[layer]
        return IndexSection("horizontal", float(height), index,
                            np.array([i0, i1, j0, j1], dtype=float) * h, h)

    def vertical_section(self, azimuth: float = 0.0) -> IndexSection:
        """The index in the vertical plane through the base z axis at `azimuth` (rad): cell
        (r, z) takes the voxel holding its centre ``(r cos(azimuth), r sin(azimuth), z)``."""
        azimuth = finite_number("azimuth", azimuth)
        h = self.resolution
        radial = np.hypot(self.centers[:, 0], self.centers[:, 1]).max() + h
        cells = math.ceil(radial / h)
        k0, k1 = self.voxels[:, 2].min(), self.voxels[:, 2].max() + 1
        r = (np.arange(-cells, cells) + 0.5) * h
        z = (np.arange(k0, k1) + 0.5) * h
        p = np.empty((z.size, r.size, 3))
        p[..., 0] = r * math.cos(azimuth)
        p[..., 1] = r * math.sin(azimuth)
        p[..., 2] = z[:, None]
        row = self.find(p)
        index = np.where(row >= 0, self.index[row.clip(min=0)], np.nan)
        return IndexSection("vertical", azimuth, index,
                            np.array([-cells * h, cells * h, k0 * h, k1 * h]), h)


def voxel_keys(ijk: NDArray) -> NDArray:
    """Voxel indices (..., 3) int64 packed into keys (...,) that sort as (i, j, k) do."""
    ijk = ijk + _OFFSET
    return (ijk[..., 0] << 2 * _BITS) | (ijk[..., 1] << _BITS) | ijk[..., 2]


# --- manipulability of many configurations ----------------------------------------------------

@kernel(cache=True, nogil=True)
def _manipulability(Q, F, I, out):
    """Yoshikawa's manipulability (M,) of configurations Q (M, n), all six Jacobian rows: the
    product of the singular values of J, which is ``|det R|`` of a Householder QR of J (six
    joints or fewer) or of J^T (more), a backward-stable factorisation; the same values as
    `armkit.manipulability`'s singular values (to round-off, also at a singularity) at a tenth
    of their cost."""
    n = Q.shape[1]
    pose = np.empty((4, 4))
    J = np.empty((6, n))
    rows, cols = (6, n) if n <= 6 else (n, 6)
    A = np.empty((rows, cols))
    for k in range(Q.shape[0]):
        core.pose_jacobian_one(Q[k], F, I, pose, J)
        for r in range(rows):
            for c in range(cols):
                A[r, c] = J[r, c] if n <= 6 else J[c, r]
        product = 1.0
        for c in range(cols):
            norm = 0.0
            for r in range(c, rows):
                norm += A[r, c] * A[r, c]
            norm = math.sqrt(norm)
            product *= norm                     # |R_cc|: the column's length below the diagonal
            if norm == 0.0:
                break
            # The reflection taking A[c:, c] to -sign(A[c, c]) norm e_c, applied to the rest.
            alpha = -norm if A[c, c] >= 0.0 else norm
            v0 = A[c, c] - alpha
            vv = v0 * v0
            for r in range(c + 1, rows):
                vv += A[r, c] * A[r, c]
            if vv == 0.0:
                continue
            for j in range(c + 1, cols):
                s = v0 * A[c, j]
                for r in range(c + 1, rows):
                    s += A[r, c] * A[r, j]
                f = 2.0 * s / vv
                A[c, j] -= f * v0
                for r in range(c + 1, rows):
                    A[r, j] -= f * A[r, c]
        out[k] = product


def manipulability_of(robot: Robot, Q: NDArray) -> NDArray:
    """Yoshikawa's manipulability (M,) of configurations Q (M, n), compiled (see
    `_manipulability`)."""
    Q = np.ascontiguousarray(Q, dtype=float)
    out = np.empty(Q.shape[0])
    k = robot.chain.kernel
    _manipulability.sized(Q.shape[0], Q, k.F, k.I, out)
    return out


# --- the plan of a map and its chunks ---------------------------------------------------------

@dataclass(frozen=True, eq=False)
class _Plan:
    """Everything a chunk depends on; sent once to each Dask worker."""

    robot: Robot
    resolution: float
    voxels: NDArray             # (V, 3)
    orientations: Orientations
    method: str                 # "analytic", "lm" or "newton"
    restarts: int
    seed: int
    chunk: int                  # voxels per chunk
    scene: Any                  # armkit.planning.Scene or None
    collision_resolution: float

    @property
    def chunks(self) -> int:
        return -(-len(self.voxels) // self.chunk)

    def size(self, index: int) -> int:
        return min(self.chunk, len(self.voxels) - index * self.chunk)


@dataclass(frozen=True, eq=False)
class _Tools:
    """What a process builds once from the plan: the IK solver and the collision checker."""

    solver: IKSolver
    checker: Any


def _tools(plan: _Plan) -> _Tools:
    checker = None
    if plan.scene is not None:
        from armkit.planning import CollisionChecker

        checker = CollisionChecker(plan.robot, plan.scene, resolution=plan.collision_resolution)
    return _Tools(IKSolver(plan.robot, threads=1), checker)


def voxel_targets(robot: Robot, centers: NDArray, orientations: Orientations) -> NDArray:
    """IK targets (V K, 4, 4): each voxel centre (V, 3) with every orientation, voxel by
    voxel."""
    R = orientations.in_base(centers, robot)
    T = np.zeros(R.shape[:2] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = centers[:, None]
    T[..., 3, 3] = 1.0
    return T.reshape(-1, 4, 4)


def reaching_solutions(solver: IKSolver, T: NDArray, mask: NDArray, method: str, *,
                       restarts: int = RESTARTS, seed: int = 0,
                       threads: int | None = None) -> tuple[NDArray, NDArray]:
    """IK for targets T (N, 4, 4): the solutions and which of them reach their target.

    Parameters
    ----------
    solver : IKSolver
    mask : ndarray of bool, (6,)
        The task.
    method : {"analytic", "lm", "newton"}
        "analytic": every closed-form branch (`serves` must hold); else one numeric solution
        per target, with `restarts` random restarts seeded by `seed`.
    threads : int, optional
        Most threads the batch may use.

    Returns
    -------
    Q : ndarray, (N, B, n)
        B = the closed form's branches, or 1; angles folded into the limits nearest their
        middle.
    ok : ndarray of bool, (N, B)
        Within `TOLERANCE` of the target under the mask (by forward kinematics) and inside
        the joint limits.
    """
    robot = solver.robot
    if method == "analytic":
        low, high = robot.sampling_limits
        q_ref = np.broadcast_to(0.5 * (low + high), (len(T), robot.n)).copy()
        Q, _, flags = candidates(robot.chain, solver.family, T, q_ref, mask, TOLERANCE,
                                 TOLERANCE, threads=threads)
        return Q, flags[..., 1] & flags[..., 2]
    result = solver.solve(T, mask=mask, method=method, restarts=restarts, seed=seed,
                          tol_position=TOLERANCE, tol_rotation=TOLERANCE)
    return result.q[:, None], np.asarray(result.success).reshape(-1, 1).copy()


def serves(solver: IKSolver, mask: NDArray) -> bool:
    """Whether the robot's closed form solves the task `mask`: its own task, or one that asks
    more (a looser task is the numeric solver's, as in `IKSolver.solve`)."""
    family = solver.family
    return family is not None and all(m or not f for m, f in zip(mask.tolist(), family.mask))


def _solve_chunk(plan: _Plan, tools: _Tools, index: int) -> MapChunk:
    """IK for every (voxel, orientation) of chunk `index`, reduced per voxel."""
    first = index * plan.chunk
    centers = (plan.voxels[first:first + plan.size(index)] + 0.5) * plan.resolution
    T = voxel_targets(plan.robot, centers, plan.orientations)
    Q, ok = reaching_solutions(tools.solver, T, plan.orientations.mask, plan.method,
                               restarts=plan.restarts, seed=_chunk_seed(plan.seed, index),
                               threads=1)
    if tools.checker is not None and ok.any():
        ok[ok] = tools.checker.valid(np.ascontiguousarray(Q[ok]))
    v, K = plan.size(index), len(plan.orientations)
    reached = ok.any(axis=1).reshape(v, K)
    best = np.zeros(ok.shape)
    if ok.any():
        best[ok] = manipulability_of(plan.robot, Q[ok])
    return MapChunk(reached.sum(axis=1), np.packbits(reached, axis=1, bitorder="little"),
                    best.reshape(v, -1).max(axis=1))


def _chunk_seed(seed: int, index: int) -> int:
    """The numeric solver's seed for chunk `index`: from the map's seed and the index only."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1, np.uint64)[0] >> 1)


# --- running the chunks -----------------------------------------------------------------------

def _run_local(plan: _Plan, todo: list[int], threads: int, finished: Callable) -> None:
    """Chunks `todo` on `threads` threads (the kernels release the GIL); the first alone, so
    that it compiles the kernels once, before the threads share them."""
    if not todo:
        return
    tools = _tools(plan)
    finished(todo[0], _solve_chunk(plan, tools, todo[0]))
    rest = iter(todo[1:])
    if threads <= 1:
        for i in rest:
            finished(i, _solve_chunk(plan, tools, i))
        return
    with ThreadPoolExecutor(threads) as pool:
        running = {}
        for i in rest:
            running[pool.submit(_solve_chunk, plan, tools, i)] = i
            if len(running) >= 2 * threads:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    finished(running.pop(future), future.result())
        for future in list(running):
            finished(running.pop(future), future.result())


def _run_dask(plan: _Plan, todo: list[int], scheduler: Any, finished: Callable) -> None:
    """Runs of up to TASK_CHUNKS chunks as tasks on the cluster, two per worker thread in
    flight; each chunk handed to `finished` as its task comes back."""
    from distributed import as_completed

    client, opened = dask_client(scheduler)
    try:
        threads = sum(client.nthreads().values()) or 1
        size = max(1, min(TASK_CHUNKS, len(todo) // (2 * threads)))
        runs = iter([todo[i:i + size] for i in range(0, len(todo), size)])
        shared = client.scatter(plan, broadcast=True, hash=False)
        chunks_of: dict[str, list[int]] = {}

        def submit() -> list:
            run = next(runs, None)
            if run is None:
                return []
            future = client.submit(_task_run, shared, run, pure=False)
            chunks_of[future.key] = run
            return [future]

        running = as_completed([f for _ in range(2 * threads) for f in submit()],
                               loop=client.loop)
        for future in running:
            try:
                results = future.result()
            except Exception as err:        # a worker's failure comes back as its error
                raise InputError(f"scheduler: expected workers that run armkit, found "
                                 f"{type(err).__name__}: {err}") from None
            for i, result in zip(chunks_of.pop(future.key), results):
                finished(i, result)
            running.update(submit())
    finally:
        if opened:
            client.close()


def _task_run(plan: _Plan, run: list[int]) -> list[MapChunk]:
    """The chunks of `run` (their indices) as one Dask task, on one thread (the worker's own
    threads fill its cores already)."""
    tools = _tools(plan)
    with numba_threads(1):
        return [_solve_chunk(plan, tools, i) for i in run]


# --- the map ----------------------------------------------------------------------------------

MOST_VOXELS = 20_000_000    # voxels in the ball the arm's links span, at most (memory)


def reach_map(robot: Robot, resolution: float | None = None,
              orientations: int | Orientations = 200, *, scene: Any = None,
              method: str = "auto", restarts: int = RESTARTS, samples: int | None = None,
              seed: int = 0, chunk: int | None = None, scheduler: Any = None,
              threads: int | None = None, collision_resolution: float = 0.005,
              progress: Callable[[int, int], None] | None = None,
              checkpoint: Checkpoint | None = None) -> ReachMap:
    """The reachability map of the tool: per voxel, the share of orientations IK reaches.

    Parameters
    ----------
    robot : Robot
    resolution : float or None
        Voxel edge (m). None: the Monte Carlo workspace's default (1/50 of the span of the
        arm's links, rounded down to 1, 2 or 5 times a power of ten).
    orientations : int or Orientations
        The orientations tried at every voxel, or how many of the robot's default set
        (`default_orientations`: approach directions times rolls for six joints or more).
    scene : armkit.planning.Scene, optional
        Obstacles: a solution counts only if the arm is free of them and of itself
        (`armkit.planning.CollisionChecker`, with `collision_resolution`, m). None: no
        collision test.
    method : {"auto", "analytic", "lm", "newton"}
        "auto": the closed form where the arm has one for the orientations' task, else
        Levenberg-Marquardt. "analytic" insists on the closed form.
    restarts : int
        Random restarts of the numeric solver after the seed bank's starts.
    samples : int or None
        Monte Carlo samples that find the voxels (default: 32 per voxel of the ball the
        links span, at least a million).
    seed : int
        Seed of the samples and of the numeric restarts.
    chunk : int or None
        Voxels per chunk (default: about 16,384 IK problems per chunk). The result depends on
        it only through the numeric solver's seeds.
    scheduler : None, str or distributed.Client
        A Dask scheduler's address (``"tcp://host:8786"``) or client: the chunks run there.
        The result is bit-identical to a local run with the same settings.
    threads : int or None
        Threads of a local run (default: `armkit.get_num_threads`).
    progress : callable, optional
        Called as ``progress(voxels_done, voxels)`` after each chunk.
    checkpoint : Checkpoint, optional
        Keeps finished chunks and gives them back to a run of the same settings
        (`armkit.io.reach_maps.ChunkFolder`), which then solves only the rest.

    Returns
    -------
    ReachMap

    Raises
    ------
    InputError
        An argument out of range, a resolution too fine for the arm's size, "analytic" for an
        arm without a closed form for the task, or a scheduler that cannot be reached.

    Example
    -------
    >>> arm = armkit.robot("water_supply")
    >>> m = armkit.reach_map(arm, 0.1, 12)
    >>> len(m.orientations), m.orientations.task, sorted(set(m.index.tolist()))
    (12, 'position+yaw', [0.0, 1.0])
    """
    if not isinstance(robot, Robot):
        raise InputError(f"robot: expected a Robot (see armkit.robot), found "
                         f"{type(robot).__name__}")
    lower, upper = robot.sampling_limits
    bound = reach_bound(robot, lower, upper)
    h = default_resolution(bound) if resolution is None else finite_number("resolution", resolution)
    if not h > 0:
        raise InputError(f"resolution: expected a positive voxel edge (m), found {h:g}")
    # The voxels of the ball the links span, at most MOST_VOXELS (compared as its radius in
    # voxels, which a tiny h cannot overflow).
    most_radius = (MOST_VOXELS * 3.0 / (4.0 * math.pi)) ** (1 / 3) - 1.0
    if not bound / h <= most_radius:
        raise InputError(f"resolution: expected at least {bound / most_radius:.3g} m for "
                         f"{robot.name} (at most {MOST_VOXELS:,} voxels), found {h:g}")
    ball = 4.0 / 3.0 * math.pi * (bound / h + 1.0) ** 3
    if isinstance(orientations, Orientations):
        chosen = orientations
    else:
        chosen = default_orientations(robot, whole_number("orientations", orientations, 1, 100_000))
    solver = IKSolver(robot)
    method = _method(solver, chosen, method)
    restarts = whole_number("restarts", restarts, 0, 10_000)
    seed = whole_number("seed", seed, 0, 2**63 - 1)
    samples = (max(MIN_SAMPLES, round(SAMPLES_PER_VOXEL * ball)) if samples is None
               else whole_number("samples", samples, 1, 10**12))
    collision_resolution = finite_number("collision_resolution", collision_resolution)
    if scene is not None:
        from armkit.planning import Scene

        if not isinstance(scene, Scene):
            raise InputError(f"scene: expected an armkit.planning.Scene, found "
                             f"{type(scene).__name__}")
    ws = workspace(robot, samples, seed=seed, resolution=h, cloud=0, scheduler=scheduler)
    voxels = dilated(ws.voxels)
    K = len(chosen)
    chunk = (max(1, TARGETS_PER_CHUNK // K) if chunk is None
             else whole_number("chunk", chunk, 1, 10**7))
    threads = get_num_threads() if threads is None else whole_number("threads", threads, 1, 1024)
    plan = _Plan(robot, h, voxels, chosen, method, restarts, seed, chunk, scene,
                 collision_resolution)
    key = settings_key(plan)
    results: dict[int, MapChunk] = {}
    if checkpoint is not None:
        results.update(checkpoint.start(key, [plan.size(i) for i in range(plan.chunks)],
                                        K))
    done = sum(plan.size(i) for i in results)
    if progress is not None:
        progress(done, len(voxels))

    def finished(i: int, result: MapChunk) -> None:
        nonlocal done
        results[i] = result
        if checkpoint is not None:
            checkpoint.save(i, result)
        done += plan.size(i)
        if progress is not None:
            progress(done, len(voxels))

    todo = [i for i in range(plan.chunks) if i not in results]
    if scheduler is None:
        _run_local(plan, todo, threads, finished)
    elif todo:
        _run_dask(plan, todo, scheduler, finished)
    from importlib.metadata import version

    ordered = [results[i] for i in range(plan.chunks)]
    arrays = dict(voxels=voxels,
                  count=np.concatenate([c.count for c in ordered]).astype(np.int64),
                  reached=np.concatenate([c.reached for c in ordered]),
                  manipulability=np.concatenate([c.manipulability for c in ordered]))
    for a in arrays.values():
        a.setflags(write=False)
    settings = {"method": method, "restarts": restarts, "seed": seed, "samples": samples,
                "chunk": chunk, "obstacles": None if scene is None else len(scene),
                "collision_resolution": collision_resolution, "key": key,
                "robot": robot_key(robot),
                "armkit": version("armkit")}
    return ReachMap(robot, h, orientations=chosen, settings=settings, **arrays)


def dilated(voxels: NDArray) -> NDArray:
    """The voxels (V, 3) and every neighbour of theirs (26 each), lexicographic."""
    steps = np.stack(np.meshgrid(*[np.arange(-1, 2)] * 3, indexing="ij"), -1).reshape(-1, 3)
    keys = np.unique(voxel_keys((voxels[:, None, :] + steps).reshape(-1, 3)))
    shifts = np.array([2 * _BITS, _BITS, 0])
    return ((keys[:, None] >> shifts) & ((1 << _BITS) - 1)) - _OFFSET


def _method(solver: IKSolver, orientations: Orientations, method: str) -> str:
    """The solver a map uses: "analytic" where the closed form serves the task (its own task
    or one that asks more), else the numeric method."""
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, found {method!r}")
    closed = serves(solver, orientations.mask)
    if method == "analytic" and not closed:
        raise InputError(f"method: expected 'auto', 'lm' or 'newton' for {solver.robot.name} "
                         f"with the task {orientations.task} (no closed form serves it), "
                         f"found 'analytic'")
    if method == "auto":
        return "analytic" if closed else "lm"
    return method


def _digest(arrays: list, extra: tuple) -> str:
    digest = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        digest.update(f"{a.dtype.str}{a.shape}".encode())
        digest.update(a.tobytes())
    digest.update(repr(extra).encode())
    return digest.hexdigest()


def robot_key(robot: Robot) -> str:
    """A hash of what a map depends on of a robot: its packed chain (kinematics, base and
    tool) and its joint limits."""
    k = robot.chain.kernel
    return _digest([k.floats, k.ints, robot.lower, robot.upper, *robot.sampling_limits], ())


def settings_key(plan: _Plan) -> str:
    """A hash of everything a map's chunks depend on: the robot (`robot_key`), voxels,
    orientations, solver settings and the collision model."""
    arrays = [plan.voxels, plan.orientations.rotations, plan.orientations.mask]
    if plan.scene is not None:
        arrays += list(_tools(plan).checker.arrays)       # chain, arm parts and scene
    return _digest(arrays, (robot_key(plan.robot), plan.resolution, plan.orientations.frame,
                            plan.method, plan.restarts, plan.seed, plan.chunk,
                            plan.scene is not None, plan.collision_resolution))
