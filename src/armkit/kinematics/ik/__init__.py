"""Inverse kinematics: closed forms with every solution, numeric solvers for any chain, the
optimal choice, and an honest result per target.

`IKSolver` holds what is derived from a robot (closed-form family, reach bound, seed bank):
build it once and call ``solver.solve(targets, q0)``, ``solver.solutions(targets)`` or
``solver.track(targets, q_start)``. ``ik`` and ``ik_solutions`` are one-call wrappers that
build a solver per call. Success is always decided by armkit's own forward kinematics of the
returned q: within the tolerances under the task mask, and within the joint limits. Failure
reasons come from `armkit.kinematics.ik.reasons`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armkit.kinematics.ik.choose import CRITERIA
from armkit.kinematics.ik.reasons import (OK, OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, REASONS,
                                          SINGULAR, not_converged)
from armkit.kinematics.ik.solver import (BANK_SAMPLES, METHODS, IKResult, IKSolutions, IKSolver,
                                         IKTrack, default_mask, reach_bound)

BANK_FROM = 64      # targets per ik() call from which a seed bank pays for its building
from armkit.kinematics.ik.masks import NAMED_MASKS
from armkit.model.robot import Robot


def ik(robot: Robot, target: ArrayLike, q0: ArrayLike | None = None, *,
       mask: str | ArrayLike | None = None, method: str = "auto", criterion: str = "nearest",
       weights: ArrayLike | None = None, tol_position: float = 1e-9, tol_rotation: float = 1e-9,
       max_iter: int = 20, restarts: int = 250, seed: int = 0,
       threads: int | None = None) -> IKResult:
    """Joint positions that put the tool at the target pose: ``IKSolver(robot).solve(...)``.

    Parameters and result as `IKSolver.solve` (`threads` as `IKSolver`). Each call derives
    the robot's solver anew and keeps nothing. The seed bank (4096 sampled configurations,
    about 1 ms to build) is built only for a batch of `BANK_FROM` targets or more; fewer
    targets start from q0 (or the middle of the limits), then from random configurations,
    which costs about as much per target as searching a bank. For many calls on one robot,
    hold an `IKSolver`: its bank is built once.

    Examples
    --------
    >>> import armkit
    >>> puma = armkit.robot("puma560")
    >>> T = armkit.fk(puma, [0.1, 0.5, -0.4, 0.3, 0.6, -0.2])
    >>> result = armkit.ik(puma, T)
    >>> result.success, result.reason, result.method
    (True, 'ok', 'analytic:spherical_wrist')
    """
    targets = np.size(target) // 16
    solver = IKSolver(robot, samples=BANK_SAMPLES if targets >= BANK_FROM else 0,
                      threads=threads)
    return solver.solve(
        target, q0, mask=mask, method=method, criterion=criterion, weights=weights,
        tol_position=tol_position, tol_rotation=tol_rotation, max_iter=max_iter,
        restarts=restarts, seed=seed)


def ik_solutions(robot: Robot, target: ArrayLike, *, mask: str | ArrayLike | None = None,
                 tol_position: float = 1e-9, tol_rotation: float = 1e-9) -> IKSolutions:
    """Every closed-form solution of one target (k, n), or of a batch (..., K, n) padded with
    a validity mask: ``IKSolver(robot).solutions(...)`` (see `IKSolutions`).

    Raises
    ------
    InputError
        If the robot's geometry has no closed form, or a target is not a pose.
    """
    return IKSolver(robot, samples=0).solutions(target, mask=mask, tol_position=tol_position,
                                                tol_rotation=tol_rotation)


__all__ = ["ik", "ik_solutions", "IKSolver", "IKResult", "IKSolutions", "IKTrack",
           "default_mask", "reach_bound", "NAMED_MASKS", "CRITERIA", "METHODS", "OK",
           "OUT_OF_REACH", "OUTSIDE_JOINT_LIMITS", "SINGULAR", "REASONS", "not_converged"]
