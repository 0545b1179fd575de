"""Inverse kinematics: closed forms with every solution, numeric solvers for any chain, the
optimal choice, and an honest result per target.

``ik`` returns one `IKResult` for a batch of targets; ``ik_solutions`` lists every closed-form
solution of one target. Success is always decided by armkit's own forward kinematics of the
returned q: within the tolerances under the task mask, and within the joint limits.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk
from armkit.kinematics.ik import analytic, numeric
from armkit.kinematics.ik.choose import CRITERIA, fold_into_limits, scores, within_limits
from armkit.kinematics.ik.task import NAMED_MASKS, as_mask, mask_name, task_errors
from armkit.kinematics.jacobian import pose_and_jacobian
from armkit.model.robot import Robot, joint_array
from armkit.spatial import as_transform

METHODS = ("auto", "analytic", "lm", "newton")
SEEDS = 8           # nearest sampled configurations tried first by the numeric solvers


@dataclass(frozen=True)
class IKResult:
    """IK outcome per target; leading shape (...) as the targets.

    Attributes
    ----------
    success : ndarray of bool, (...,)
        Within both tolerances under the mask, and within the joint limits.
    q : ndarray, (..., n)
        The chosen solution. On failure the best configuration found: for "outside joint
        limits" the solution the criterion prefers (nearest q0 by default), outside the
        limits; otherwise the one closest to the target.
    position_error : ndarray, (...,)
        m, by forward kinematics of q.
    rotation_error : ndarray, (...,)
        rad, by forward kinematics of q (see `armkit.kinematics.ik.task` for the measure).
    iterations : ndarray of int, (...,)
        Numeric iterations (0 for a closed form).
    reason : ndarray of str, (...,)
        "ok", "out of reach", "outside joint limits", "singular", or
        "did not converge in N iterations x M starts".
    method : ndarray of str, (...,)
        The solver that produced q: "analytic:<family>", "analytic:<family>+lm" (a closed-form
        branch polished by Levenberg-Marquardt), "lm" or "newton".
    criterion : str
        How the solution was chosen among several.
    mask : str
        The task mask: its name or its six flags.
    """

    success: NDArray
    q: NDArray
    position_error: NDArray
    rotation_error: NDArray
    iterations: NDArray
    reason: NDArray
    method: NDArray
    criterion: str
    mask: str


@dataclass(frozen=True)
class IKSolutions:
    """Every closed-form solution of one target, each reaching it (checked by FK).

    q (k, n); within_limits (k,) bool; position_error (k,) m; rotation_error (k,) rad;
    family: the closed-form family's name; mask: the task they satisfy.
    """

    q: NDArray
    within_limits: NDArray
    position_error: NDArray
    rotation_error: NDArray
    family: str
    mask: str


def default_mask(robot: Robot, family: analytic.Family | None = None) -> NDArray:
    """The task a robot can do exactly: a closed form's own task, a full pose for six or more
    joints, else the position."""
    family = family or analytic.family_of(robot.chain)
    if family is not None:
        return np.array(family.mask, dtype=bool)
    return as_mask("pose" if robot.n >= 6 else "position")


@functools.lru_cache(maxsize=64)
def reach_bound(robot: Robot) -> float:
    """An upper bound (m) on the distance from joint 1's axis point to the tool point (kept
    per robot: robots are immutable).

    Consecutive axis points are fixed in the link between them, so the tool can be no farther
    than the sum of those distances, plus the longest stroke of each prismatic joint.
    """
    chain = robot.chain
    points = np.vstack([chain.points, chain.T_home[:3, 3]])
    strokes = np.where(chain.revolute, 0.0, np.maximum(np.abs(chain.lower), np.abs(chain.upper)))
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)) + strokes.sum())


def _start(robot: Robot, q0: ArrayLike | None, lead: tuple[int, ...]) -> NDArray:
    if q0 is None:
        lower, upper = robot.chain.sampling_limits
        return np.broadcast_to(0.5 * (lower + upper), lead + (robot.n,))
    q0 = joint_array(robot, q0, "q0")
    try:
        return np.broadcast_to(q0, lead + (robot.n,))
    except ValueError:
        raise InputError(f"q0: expected shape (..., {robot.n}) matching the targets' "
                         f"{lead}, found {q0.shape}") from None


def _check(robot, T, q, mask, tol_position, tol_rotation):
    pe, re = task_errors(fk(robot, q), T, mask)
    return pe, re, (pe < tol_position) & (re < tol_rotation), within_limits(robot, q)


def ik(robot: Robot, target: ArrayLike, q0: ArrayLike | None = None, *,
       mask: str | ArrayLike | None = None, method: str = "auto", criterion: str = "nearest",
       weights: ArrayLike | None = None, tol_position: float = 1e-9, tol_rotation: float = 1e-9,
       max_iter: int = 20, restarts: int = 250, seed: int = 0) -> IKResult:
    """Joint positions that put the tool at the target pose.

    Parameters
    ----------
    robot : Robot
    target : array_like, shape (..., 4, 4)
        Tool poses in the base frame (m).
    q0 : array_like, shape (n,) or (..., n), optional
        Current configuration: the first numeric start and the reference of the "nearest"
        choice (the middle of the limits if omitted; the numeric solver then starts from the
        sampled configurations nearest the target).
    mask : str or 6 flags, optional
        The task (see `armkit.kinematics.ik.task`): "pose", "position", "position+yaw",
        "position+pitch", "position+axis" or flags (x, y, z, rx, ry, rz). Default: the task the
        robot can do exactly (a full pose for six joints or more).
    method : {"auto", "analytic", "lm", "newton"}
        "auto" takes the closed form where the chain has one, else Levenberg-Marquardt.
    criterion : {"nearest", "least_travel", "manipulability", "limits"}
        How to choose among several solutions (closed forms).
    weights : array_like, shape (n,), optional
        Per-joint weights of the "nearest" criterion.
    tol_position, tol_rotation : float
        Success tolerances, m and rad.
    max_iter, restarts : int
        Numeric iterations per attempt, and the attempts after the first: from q0 (if given),
        then from the nearest of a few thousand configurations sampled inside the limits, then
        from random ones.
    seed : int
        Seed of the restarts; the same seed gives the same result.

    Returns
    -------
    IKResult
        Per target; an unreachable target is a failed result with its reason, not an error.

    Raises
    ------
    InputError
        Bad shapes or values of the arguments (never for an unreachable target).
    """
    T = as_transform(target, "target")
    lead = T.shape[:-2]
    flat_T = T.reshape(-1, 4, 4)
    q_ref = np.ascontiguousarray(_start(robot, q0, lead).reshape(-1, robot.n))
    family = analytic.family_of(robot.chain)
    mask = default_mask(robot, family) if mask is None else as_mask(mask)
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, found {method!r}")
    if criterion not in CRITERIA:
        raise InputError(f"criterion: expected one of {', '.join(CRITERIA)}, found {criterion!r}")
    if weights is not None:
        weights = joint_array(robot, weights, "weights")
        if weights.shape != (robot.n,) or (weights < 0).any():
            raise InputError(f"weights: expected {robot.n} non-negative numbers, found "
                             f"{weights.tolist()}")
    if not (isinstance(seed, (int, np.integer)) and 0 <= seed < 2**63):
        raise InputError(f"seed: expected a non-negative whole number, found {seed!r}")
    for name, value in (("tol_position", tol_position), ("tol_rotation", tol_rotation)):
        if not value > 0:
            raise InputError(f"{name}: expected a positive tolerance, found {value}")
    if max_iter < 1 or restarts < 0:
        raise InputError(f"max_iter, restarts: expected >= 1 and >= 0, found {max_iter}, "
                         f"{restarts}")
    if method == "analytic" and family is None:
        raise InputError(f"method: expected 'auto', 'lm' or 'newton' for {robot.name}, found "
                         f"'analytic' (its geometry has no closed form here)")
    # A closed form solves its own task; a looser task (fewer flags) is the numeric solver's.
    if family is not None and not np.all(mask >= np.array(family.mask, dtype=bool)):
        if method == "analytic":
            raise InputError(f"mask: expected one that includes {mask_name(np.array(family.mask, bool))} "
                             f"for the closed form of {robot.name}, found {mask_name(mask)}")
        family = None
    N = flat_T.shape[0]
    bound = reach_bound(robot)
    # Past this bound no configuration reaches the target: no search is worth the time.
    beyond = (np.linalg.norm(flat_T[:, :3, 3] - robot.chain.points[0], axis=-1)
              > bound * (1 + 1e-9))
    q = q_ref.copy()
    iterations = np.zeros(N, dtype=np.int64)
    reason = np.full(N, "ok", dtype=object)
    numeric_method = method if method in ("lm", "newton") else "lm"
    solver = np.full(N, numeric_method, dtype=object)
    numeric_targets = np.ones(N, dtype=bool)
    if family is not None and method in ("auto", "analytic"):
        q, found, reason_cf = _closed_form(robot, family, flat_T, q_ref, mask, criterion, weights,
                                           tol_position, tol_rotation)
        solver[:] = f"analytic:{family.name}"
        reason[:] = reason_cf
        # What the closed form misses short of the reach bound goes to the numeric solver,
        # from the closest branch: at a singularity (a wrist with axes 4 and 6 aligned) the
        # solutions form a continuum, and the one branch the closed form picks may not close.
        numeric_targets = ~found & ~beyond if method == "auto" else np.zeros(N, bool)
        solver[numeric_targets] = f"analytic:{family.name}+lm"
    if numeric_targets.any():
        idx = np.flatnonzero(numeric_targets)
        starts = numeric.seed_starts(robot, flat_T[idx], mask, bound / 10, count=SEEDS,
                                     seed=seed)
        # The closed form's nearest branch (polishing), or else the given q0, goes first.
        polishing = family is not None and method == "auto"
        if polishing or q0 is not None:
            first = q[idx] if polishing else q_ref[idx]
            starts = np.concatenate([first[:, None, :], starts[:, :-1]], axis=1)
        # Beyond the reach bound no start can succeed: one attempt finds the closest pose.
        for part, tries in ((~beyond[idx], restarts), (beyond[idx], 0)):
            if part.any():
                q[idx[part]], _, iterations[idx[part]] = numeric.solve(
                    robot, flat_T[idx[part]], starts[part], mask, numeric_method, tol_position,
                    tol_rotation, max_iter, tries, seed)
    pe, re, reached, inside = _check(robot, flat_T, q, mask, tol_position, tol_rotation)
    success = reached & inside
    if numeric_targets.any():
        failed = numeric_targets & ~success
        reason[numeric_targets & success] = "ok"
        numeric_reason = _numeric_reasons(robot, q[failed], beyond[failed], mask, max_iter,
                                          restarts)
        # Where the closed form had a verdict ("out of reach": no branch reaches the pose;
        # "outside joint limits": the limits refuse it) and the numeric solver agrees by
        # failing too, the closed form's verdict says more than "singular" or "did not
        # converge".
        keep = np.isin(reason[failed], ("out of reach", "outside joint limits"))
        reason[failed] = np.where(keep, reason[failed], numeric_reason)
    shape = lambda a: a.reshape(lead + a.shape[1:])     # noqa: E731
    return IKResult(shape(success), shape(q), shape(pe), shape(re), shape(iterations),
                    shape(reason.astype(str)), shape(solver.astype(str)), criterion,
                    mask_name(mask))


def _closed_form(robot, family, T, q_ref, mask, criterion, weights, tol_position, tol_rotation):
    """Best closed-form solution per target: (q (N, n), found (N,), reason (N,) of str).

    reason: "ok", "outside joint limits" (a branch reaches the target, none inside the
    limits; q is the one the criterion prefers), or "out of reach" (no branch reaches it; q
    is the closest).
    """
    N = T.shape[0]
    C = analytic.candidates(robot.chain, family, T)                       # (N, K, n)
    real = np.isfinite(C).all(axis=-1)
    C = fold_into_limits(robot, np.where(real[..., None], C, 0.0), q_ref[:, None, :])
    pe, re, reached, inside = _check(robot, T[:, None], C, mask, tol_position, tol_rotation)
    reached &= real
    usable = reached & inside
    score = scores(robot, C, q_ref, criterion, weights)
    # The best usable branch; else the best that reaches the target (outside the limits);
    # else the closest to it.
    pick = np.select([usable.any(axis=1), reached.any(axis=1)],
                     [np.argmin(np.where(usable, score, np.inf), axis=1),
                      np.argmin(np.where(reached, score, np.inf), axis=1)],
                     np.argmin(np.where(real, pe + re, np.inf), axis=1))
    q = np.where(real.any(axis=1)[:, None], C[np.arange(N), pick], q_ref)
    reason = np.select([usable.any(axis=1), reached.any(axis=1)],
                       ["ok", "outside joint limits"], "out of reach")
    return q, usable.any(axis=1), reason


def _task_rank(J: NDArray, rows: NDArray) -> NDArray:
    """Numerical rank (...,) of the task rows of Jacobians (..., 6, n)."""
    s = np.linalg.svd(J[..., rows, :], compute_uv=False)
    return np.sum(s > 1e-6 * s[..., :1], axis=-1)


def _numeric_reasons(robot, q, beyond, mask, max_iter, restarts) -> NDArray:
    """Why numeric solves failed: out of reach, at a singularity, or not converged.

    "singular" means the task Jacobian at the best q has lower rank than the arm has in
    general for that task (an arm that never spans the task is not called singular for it).
    """
    if q.shape[0] == 0:
        return np.array([], dtype=object)
    rows = np.flatnonzero(mask)
    general = np.random.default_rng(0).uniform(*robot.chain.sampling_limits, (8, robot.n))
    generic = _task_rank(pose_and_jacobian(robot, general)[1], rows).max()
    rank = _task_rank(pose_and_jacobian(robot, q)[1], rows)
    return np.select([beyond, rank < generic], ["out of reach", "singular"],
                     f"did not converge in {max_iter} iterations x {restarts + 1} starts")


def ik_solutions(robot: Robot, target: ArrayLike, *, mask: str | ArrayLike | None = None,
                 tol_position: float = 1e-9, tol_rotation: float = 1e-9) -> IKSolutions:
    """Every closed-form solution of one target, each checked by forward kinematics.

    Parameters
    ----------
    target : array_like, shape (4, 4)
    mask : str or 6 flags, optional
        The task the solutions must meet; the closed form's own task if omitted.

    Returns
    -------
    IKSolutions
        Distinct solutions (angles folded into the limits where a turn allows it), with which
        are within the limits; none if the target is out of reach.

    Raises
    ------
    InputError
        If the robot's geometry has no closed form, or the target is not one pose.
    """
    family = analytic.family_of(robot.chain)
    if family is None:
        raise InputError(f"robot: expected an arm with a closed form (lift-and-swing, yaw and "
                         f"three pitches, three parallel joints and a wrist, or a spherical "
                         f"wrist), found {robot.name}, which only the numeric solvers serve")
    T = as_transform(target, "target")
    if T.shape != (4, 4):
        raise InputError(f"target: expected one pose (4, 4), found {T.shape}")
    mask = np.array(family.mask, bool) if mask is None else as_mask(mask)
    C = analytic.candidates(robot.chain, family, T[None])[0]
    C = C[np.isfinite(C).all(axis=1)]
    C = fold_into_limits(robot, C, np.zeros_like(C))
    pe, re, reached, inside = _check(robot, T, C, mask, tol_position, tol_rotation)
    keep = np.flatnonzero(reached)
    distinct: list[int] = []
    for i in keep:
        if all(np.abs(C[i] - C[j]).max() > 1e-9 for j in distinct):
            distinct.append(i)
    k = np.array(distinct, dtype=int)
    return IKSolutions(C[k].reshape(-1, robot.n), inside[k], pe[k], re[k], family.name,
                       mask_name(mask))


__all__ = ["ik", "ik_solutions", "IKResult", "IKSolutions", "default_mask", "reach_bound",
           "NAMED_MASKS", "CRITERIA", "METHODS"]
