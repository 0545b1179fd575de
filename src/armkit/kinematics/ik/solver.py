"""`IKSolver`: what inverse kinematics derives from a robot, built once and held by the user,
and the result records it returns.

Like Pinocchio's Model/Data split, the solver is what the robot's IK *is* (its closed-form
family, reach bound, kernel arrays, seed bank), constant across calls; every solve returns a
new result and changes nothing. Nothing is kept anywhere else: a robot that is dropped (a
calibration loop makes a new one per iteration) takes its solver's data with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics import core
from armkit.kinematics.forward import FLOAT
from armkit.kinematics.ik import analytic, numeric
from armkit.kinematics.ik.choose import (CRITERIA, CRITERION_CODES, USABLE, pick, scores)
from armkit.kinematics.ik.reasons import (OK, OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, SINGULAR,
                                          not_converged)
from armkit.kinematics.ik.seeds import SeedBank
from armkit.kinematics.ik.masks import MASK_FORMS, NAMED_MASKS, as_mask, mask_name
from armkit.kinematics.jacobian import pose_and_jacobian
from armkit.model.robot import Robot, joint_array
from armkit.spatial import as_transform

METHODS = ("auto", "analytic", "lm", "newton")
_NO_SCORES = np.empty((0, 0))       # `pick` computes its own scores
_ONES = np.ones(64)                 # "nearest"'s weights when none are given
SEEDS = 8           # nearest sampled configurations tried first by the numeric solvers
BANK_SAMPLES = 4096


def _plain(value):
    """JSON-ready: arrays to nested lists, NumPy scalars to Python ones, NaN and inf to None."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value] if value.ndim else _plain(value.item())
    if isinstance(value, (np.generic,)):
        return _plain(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _one_or_many(a: NDArray, lead: tuple[int, ...]):
    """a (N, ...) reshaped to lead + (...); for one target (lead ()) a scalar field becomes a
    plain Python value."""
    a = a.reshape(lead + a.shape[1:])
    return a.item() if a.ndim == 0 else a


@dataclass(frozen=True)
class IKResult:
    """IK outcome per target; leading shape (...) as the targets.

    For one target (a (4, 4) pose) the scalar fields are plain Python values (``bool``,
    ``float``, ``int``, ``str``) and q is an array (n,); for a batch each field is an array of
    the targets' leading shape. `to_dict` gives JSON-ready values either way.

    Attributes
    ----------
    success : bool or ndarray of bool, (...,)
        Within both tolerances under the mask, and within the joint limits.
    q : ndarray, (..., n)
        The chosen solution. On failure the best configuration found: for "outside joint
        limits" the solution the criterion prefers (nearest q0 by default), outside the
        limits; otherwise the one closest to the target.
    position_error : float or ndarray, (...,)
        m, by forward kinematics of q.
    rotation_error : float or ndarray, (...,)
        rad, by forward kinematics of q (see `armkit.kinematics.ik.masks` for the measure).
    iterations : int or ndarray of int, (...,)
        Numeric iterations (0 for a closed form).
    reason : str or ndarray of str, (...,)
        One of `armkit.kinematics.ik.reasons`: "ok", "out of reach", "outside joint limits",
        "singular", or "did not converge in N iterations x M starts".
    method : str or ndarray of str, (...,)
        The solver that produced q: "analytic:<family>", "analytic:<family>+lm" (a closed-form
        branch polished by Levenberg-Marquardt), "lm" or "newton".
    criterion : str
        How the solution was chosen among several.
    mask : str
        The task mask: its name or its six flags.
    """

    success: bool | NDArray
    q: NDArray
    position_error: float | NDArray
    rotation_error: float | NDArray
    iterations: int | NDArray
    reason: str | NDArray
    method: str | NDArray
    criterion: str
    mask: str

    def to_dict(self) -> dict:
        """The result as JSON-serialisable values (lists for arrays, None for NaN/inf)."""
        return {name: _plain(getattr(self, name)) for name in self.__dataclass_fields__}


_RESULT_FIELDS = tuple(IKResult.__dataclass_fields__)


@dataclass(frozen=True)
class IKSolutions:
    """Every closed-form solution, each reaching its target (checked by forward kinematics).

    For one target (a (4, 4) pose): q (k, n), the k distinct solutions; valid, within_limits,
    position_error, rotation_error (k,). For a batch of targets (..., 4, 4): padded to the
    family's branch count K, q (..., K, n) with the distinct solutions of each target first and
    NaN rows after them; valid (..., K) marks the real rows (``q[i][valid[i]]`` is what the
    single call for target i gives); the other per-solution fields (..., K) are False or NaN on
    padding rows; count (...,) is the number of solutions per target.

    family: the closed-form family's name; mask: the task they satisfy.
    """

    q: NDArray
    valid: NDArray
    within_limits: NDArray
    position_error: NDArray
    rotation_error: NDArray
    count: int | NDArray
    family: str
    mask: str

    def to_dict(self) -> dict:
        """The solutions as JSON-serialisable values (lists for arrays, None for NaN/inf)."""
        return {name: _plain(getattr(self, name)) for name in self.__dataclass_fields__}


@dataclass(frozen=True)
class IKTrack:
    """A moving target followed from one solution to the next (`IKSolver.track`).

    q (k, n): the solutions of the first k targets followed; followed: k; success: all were;
    reason: "ok", "singular" (a joint step over the bound: the arm would jump) or "did not
    converge in N iterations x 1 starts" (the next target was not reached from the previous
    solution; `IKSolver.solve` with restarts says whether it can be reached at all).
    """

    q: NDArray
    followed: int
    success: bool
    reason: str

    def to_dict(self) -> dict:
        return {name: _plain(getattr(self, name)) for name in self.__dataclass_fields__}


def _one_result(*fields) -> IKResult:
    """An IKResult of one target from its fields in order, already the right types: what the
    dataclass's own __init__ does, without its nine frozen-attribute writes (a single call's
    result is built in a fraction of a microsecond)."""
    result = object.__new__(IKResult)
    result.__dict__.update(zip(_RESULT_FIELDS, fields))
    return result


def _pose_fast(target) -> tuple[NDArray, list] | None:
    """One pose (4, 4) checked in plain Python (for 16 numbers several times cheaper than the
    NumPy checks of `as_transform`, with the same tolerance): the pose as a new float array
    and its 16 values row by row; None if it is not one valid pose, and the caller lets
    `as_transform` say why."""
    try:
        T = np.array(target, dtype=float)
    except (TypeError, ValueError):
        return None
    if T.shape != (4, 4):
        return None
    v = T.ravel().tolist()
    if not all(map(math.isfinite, v)):
        return None
    a0, a1, a2, _, b0, b1, b2, _, c0, c1, c2 = v[:11]
    off = max(abs(a0 * a0 + a1 * a1 + a2 * a2 - 1.0), abs(b0 * b0 + b1 * b1 + b2 * b2 - 1.0),
              abs(c0 * c0 + c1 * c1 + c2 * c2 - 1.0), abs(a0 * b0 + a1 * b1 + a2 * b2),
              abs(a0 * c0 + a1 * c1 + a2 * c2), abs(b0 * c0 + b1 * c1 + b2 * c2))
    det = a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
    last = max(abs(v[12]), abs(v[13]), abs(v[14]), abs(v[15] - 1.0))
    return (T, v) if off <= 1e-6 and det > 0 and last <= 1e-6 else None


def reach_bound(robot: Robot) -> float:
    """An upper bound (m) on the distance from joint 1's axis point to the tool point:
    `Chain.reach` (see there), which the chain computes once. A target farther than this is out
    of reach, whatever the solver."""
    return robot.chain.reach


_UNKNOWN = object()


def default_mask(robot: Robot, family=_UNKNOWN) -> NDArray:
    """The task a robot can do exactly: a closed form's own task, a full pose for six or more
    joints, else the position. `family`: the chain's closed-form family if already known."""
    family = analytic.family_of(robot.chain) if family is _UNKNOWN else family
    if family is not None:
        return np.array(family.mask, dtype=bool)
    return as_mask("pose" if robot.n >= 6 else "position")


@dataclass(frozen=True)
class _Request:
    """One solve's validated arguments (targets flattened to N)."""

    T: NDArray                  # (N, 4, 4)
    lead: tuple
    q_ref: NDArray              # (N, n): q0, or the middle of the limits
    q0_given: bool
    mask: NDArray               # (6,) bool
    family: analytic.Family | None   # None when the mask is looser than the closed form's
    method: str
    criterion: str
    weights: NDArray | None
    tol_position: float
    tol_rotation: float
    max_iter: int
    restarts: int
    seed: int
    seeds: bool


class IKSolver:
    """Inverse kinematics of one robot, derived once: hold it and call `solve` many times.

    Parameters
    ----------
    robot : Robot
    samples : int
        Configurations in the seed bank the numeric solver picks its first starts from (0: no
        bank; starts from q0, then random).
    seed : int
        Seed of the bank's samples.
    threads : int, optional
        Most threads a batch may use (default: `armkit.threads`' choice, the idle cores or the
        bound set by `armkit.set_num_threads`); a batch uses one thread per 256 targets at
        most, so small batches stay on the calling thread.

    Attributes
    ----------
    robot : Robot
    family : Family or None
        The closed-form family recognised in the chain's geometry.
    reach : float
        `reach_bound` of the robot, m.
    default_mask : ndarray of bool, (6,)
        The task solved when none is given.
    default_name : str
        Its name (`armkit.kinematics.ik.masks.mask_name`).

    Notes
    -----
    The seed bank (about 1 ms for 4096 samples) is built the first time a solve needs a start
    that q0 or a closed form does not give, and kept by the solver: a closed-form robot, or a
    solve from a good q0, never pays for it. The solver holds nothing else that grows.

    Examples
    --------
    >>> import armkit, numpy as np
    >>> ur5 = armkit.robot("ur5")
    >>> solver = armkit.IKSolver(ur5)
    >>> T = armkit.fk(ur5, [0.1, -1.0, 1.2, -0.3, 1.4, 0.2])
    >>> result = solver.solve(T)
    >>> result.success, result.reason
    (True, 'ok')
    """

    def __init__(self, robot: Robot, *, samples: int = BANK_SAMPLES, seed: int = 0,
                 threads: int | None = None):
        if not isinstance(robot, Robot):
            raise InputError(f"robot: expected a Robot, found {type(robot).__name__}")
        for name, value, low in (("samples", samples, 0), ("seed", seed, 0),
                                 ("threads", 1 if threads is None else threads, 1)):
            if not (isinstance(value, (int, np.integer)) and low <= value < 2**63):
                raise InputError(f"{name}: expected a whole number >= {low}, found {value!r}")
        family = analytic.family_of(robot.chain)
        # The default task's arrays are the read-only ones fixed at import (`MASK_FORMS`).
        forms = MASK_FORMS[family.mask if family is not None
                           else NAMED_MASKS["pose" if robot.n >= 6 else "position"]]
        # One update of the instance's dict (`__setattr__` refuses every change).
        self.__dict__.update(
            robot=robot, family=family, default_mask=forms.flags, default_name=forms.name,
            _reach_point=None, _kernel_args=None, _samples=int(samples), _seed=int(seed),
            _threads=threads, _bank=None, _middle=None, _pick_bounds=None,
            _one_shape=(robot.n,))

    def __setattr__(self, name, value):
        raise AttributeError(f"IKSolver is immutable: cannot set {name}")

    def __repr__(self) -> str:
        family = self.family.name if self.family else "none"
        return f"IKSolver({self.robot.name}, closed form: {family}, reach {self.reach:.4g} m)"

    @property
    def reach(self) -> float:
        """`reach_bound` of the robot, m (`Chain.reach`, computed once by the chain)."""
        return self.robot.chain.reach

    @property
    def _reach_test(self) -> tuple[float, float, float, float]:
        """Joint 1's axis point (x, y, z) and the distance from it beyond which a target is out
        of reach (on first use)."""
        if self._reach_point is None:
            x, y, z = self.robot.chain.points[0].tolist()
            object.__setattr__(self, "_reach_point", (x, y, z, self.reach * (1 + 1e-9)))
        return self._reach_point

    @property
    def _mid(self) -> NDArray:
        """The middle of the sampling limits (n,): q_ref when no q0 is given (on first use)."""
        if self._middle is None:
            low, high = self.robot.chain.sampling_limits
            object.__setattr__(self, "_middle", 0.5 * (low + high))
        return self._middle

    @property
    def _kernel(self) -> numeric.KernelArgs:
        """The numeric solver's kernel arrays (built on first use)."""
        if self._kernel_args is None:
            object.__setattr__(self, "_kernel_args", numeric.KernelArgs.of(self.robot))
        return self._kernel_args

    @property
    def bank(self) -> SeedBank | None:
        """The seed bank (built on first use; None with samples=0)."""
        if self._bank is None and self._samples > 0:
            object.__setattr__(self, "_bank", SeedBank.build(self.robot, self._samples,
                                                             self.reach / 10, self._seed))
        return self._bank

    # --- solve: validate, closed form, numeric polish, verdict --------------------------------

    def solve(self, targets: ArrayLike, q0: ArrayLike | None = None, *,
              mask: str | ArrayLike | None = None, method: str = "auto",
              criterion: str = "nearest", weights: ArrayLike | None = None,
              tol_position: float = 1e-9, tol_rotation: float = 1e-9, max_iter: int = 20,
              restarts: int = 250, seed: int = 0, seeds: bool = True) -> IKResult:
        """Joint positions that put the tool at the target poses.

        Parameters
        ----------
        targets : array_like, shape (..., 4, 4)
            Tool poses in the base frame (m).
        q0 : array_like, shape (n,) or (..., n), optional
            Current configuration: the first numeric start and the reference of the "nearest"
            choice (the middle of the limits if omitted; the numeric solver then starts from
            the sampled configurations nearest the target).
        mask : str or 6 flags, optional
            The task (see `armkit.kinematics.ik.masks`): "pose", "position", "position+yaw",
            "position+pitch", "position+axis" or flags (x, y, z, rx, ry, rz). Default: the
            task the robot can do exactly (a full pose for six joints or more).
        method : {"auto", "analytic", "lm", "newton"}
            "auto" takes the closed form where the chain has one, else Levenberg-Marquardt.
        criterion : {"nearest", "least_travel", "manipulability", "limits"}
            How to choose among several solutions (closed forms).
        weights : array_like, shape (n,), optional
            Per-joint weights of the "nearest" criterion.
        tol_position, tol_rotation : float
            Success tolerances, m and rad.
        max_iter, restarts : int
            Numeric iterations per attempt, and the attempts after the first: from q0 (if
            given), then from the nearest of the seed bank's configurations, then from random
            ones.
        seed : int
            Seed of the random restarts; the same seed gives the same result.
        seeds : bool
            Take starts from the seed bank. False: q0 (or the closed form's branch) first, then
            only random restarts (`restarts=0` follows from q0 alone).

        Returns
        -------
        IKResult
            Per target; an unreachable target is a failed result with its reason, not an
            error.

        Raises
        ------
        InputError
            Bad shapes or values of the arguments (never for an unreachable target).
        """
        one = _pose_fast(targets)
        if one is not None and (q0 is None or getattr(q0, "shape", None) == self._one_shape
                                or np.shape(q0) == self._one_shape):
            task_mask = self.default_mask if mask is None else as_mask(mask)
            family = self._family_for(task_mask, method)
            if family is None:
                return self._solve_one(*one, q0, task_mask, method, criterion, weights,
                                       tol_position, tol_rotation, max_iter, restarts, seed,
                                       seeds)
            result = self._solve_one_closed(*one, q0, task_mask, family, method, criterion,
                                            weights, tol_position, tol_rotation, max_iter,
                                            restarts, seed)
            if result is not None:
                return result
        request = self._validate(targets, q0, mask, method, criterion, weights, tol_position,
                                 tol_rotation, max_iter, restarts, seed, seeds)
        beyond = self._beyond(request.T)
        state = self._closed_form(request, beyond)
        self._numeric(request, beyond, state)
        return self._verdict(request, beyond, state)

    def _solve_one(self, T, values, q0, mask, method, criterion, weights, tol_position,
                   tol_rotation, max_iter, restarts, seed, seeds) -> IKResult:
        """One target, numeric only: the batch path's steps without its batch work (the same
        starts, kernel and verdict, so the same result as that target in a batch). From a
        given q0 the seed bank is searched only if q0 alone does not converge.

        T (4, 4) is the checked target (a new array) and values its 16 numbers row by row
        (`_pose_fast`): what a single call needs is read from them in plain Python, which for
        a handful of numbers costs a fraction of NumPy's calls on tiny arrays.
        """
        self._check_options(method, criterion, weights, tol_position, tol_rotation, max_iter,
                            restarts, seed)
        n = self.robot.n
        first = None if q0 is None else self._start(q0)
        x0, y0, z0, farthest = self._reach_test
        dx, dy, dz = values[3] - x0, values[7] - y0, values[11] - z0
        beyond = math.sqrt(dx * dx + dy * dy + dz * dz) > farthest
        label = method if method in ("lm", "newton") else "lm"
        code = numeric.METHOD_CODES[label]
        task = numeric.task_args(mask, tol_position, tol_rotation)
        targets = T[None]
        q, converged = np.empty((1, n)), np.zeros(1, dtype=np.bool_)
        iterations, errors = np.zeros(1, dtype=np.int64), np.empty((1, 2))
        kernel = self._kernel
        if first is not None and not beyond:
            numeric.solve_targets.light(0, 1, targets, first, kernel.chain, kernel.limits,
                                        task, (int(max_iter), 0, code, int(seed), 0, 0.0, 0),
                                        q, converged, iterations, errors)
        if not converged[0]:
            bank = self.bank if seeds else None
            if bank is not None:
                starts = bank.starts(targets, mask, SEEDS)
                if first is not None:
                    starts[0, 1:] = starts[0, :-1].copy()
                    starts[0, 0] = first[0, 0]
            else:
                starts = first if first is not None else self._mid.reshape(1, 1, n).copy()
            numeric.solve_targets.light(0, 1, targets, starts, kernel.chain, kernel.limits,
                                        task, (int(max_iter), 0 if beyond else int(restarts),
                                               code, int(seed), 0, 0.0, 1),
                                        q, converged, iterations, errors)
        pe, re = errors[0].tolist()
        success = pe < tol_position and re < tol_rotation
        if success:
            reason = OK
        elif beyond:
            reason = OUT_OF_REACH
        else:
            reason = str(self._numeric_reasons(q, np.zeros(1, bool), mask, int(max_iter),
                                               int(restarts))[0])
        name = self.default_name if mask is self.default_mask else mask_name(mask)
        return _one_result(success, q[0], pe, re, int(iterations[0]), reason, label, criterion,
                        name)

    def _solve_one_closed(self, T, values, q0, mask, family, method, criterion, weights,
                          tol_position, tol_rotation, max_iter, restarts, seed
                          ) -> IKResult | None:
        """One target whose closed form gives a usable branch: the batch path's candidates and
        choice without its batch work (the same kernels, so the same result as that target in
        a batch); None where the closed form alone does not settle it (out of reach, outside
        the limits, a branch to polish), which the batch path then takes."""
        weights = self._check_options(method, criterion, weights, tol_position, tol_rotation,
                                      max_iter, restarts, seed)
        x0, y0, z0, farthest = self._reach_test
        dx, dy, dz = values[3] - x0, values[7] - y0, values[11] - z0
        if math.sqrt(dx * dx + dy * dy + dz * dz) > farthest:
            return None
        q_ref = (self._mid if q0 is None else self._start(q0)[0, 0])[None]
        C, errors, flags = analytic.candidates(self.robot.chain, family, T[None], q_ref, mask,
                                               tol_position, tol_rotation)
        branch, found = self._pick(C, errors, flags, q_ref, criterion, weights)[0].tolist()
        if found != USABLE:
            return None
        pe, re = errors[0, branch].tolist()
        name = self.default_name if mask is self.default_mask else mask_name(mask)
        return _one_result(True, C[0, branch], pe, re, 0, OK, f"analytic:{family.name}", criterion,
                        name)

    def _start(self, q0) -> NDArray:
        """One q0 (n,) as a start (1, 1, n): a new float array of finite joint values."""
        n = self.robot.n
        if type(q0) is np.ndarray and q0.dtype is FLOAT and q0.shape == (n,):
            values = q0.tolist()
            if all(map(math.isfinite, values)):
                return np.array(values).reshape(1, 1, n)
        return np.array(joint_array(self.robot, q0, "q0").reshape(1, 1, n))

    def _validate(self, targets, q0, mask, method, criterion, weights, tol_position,
                  tol_rotation, max_iter, restarts, seed, seeds) -> _Request:
        robot = self.robot
        T = as_transform(targets, "target")
        lead = T.shape[:-2]
        flat_T = T.reshape(-1, 4, 4)
        N = flat_T.shape[0]
        if q0 is None:
            q_ref = np.broadcast_to(self._mid, (N, robot.n))
        else:
            q0 = joint_array(robot, q0, "q0")
            try:
                q_ref = np.broadcast_to(q0, lead + (robot.n,)).reshape(N, robot.n)
            except ValueError:
                raise InputError(f"q0: expected shape (..., {robot.n}) matching the targets' "
                                 f"{lead}, found {q0.shape}") from None
        mask = self.default_mask if mask is None else as_mask(mask)
        weights = self._check_options(method, criterion, weights, tol_position, tol_rotation,
                                      max_iter, restarts, seed)
        family = self._family_for(mask, method)
        return _Request(flat_T, lead, q_ref, q0 is not None, mask, family, method, criterion,
                        weights, float(tol_position), float(tol_rotation), int(max_iter),
                        int(restarts), int(seed), bool(seeds))

    def _check_options(self, method, criterion, weights, tol_position, tol_rotation, max_iter,
                       restarts, seed):
        """Check the scalar options of a solve; returns the weights as an array (or None)."""
        robot = self.robot
        if method not in METHODS:
            raise InputError(f"method: expected one of {', '.join(METHODS)}, found {method!r}")
        if criterion not in CRITERIA:
            raise InputError(f"criterion: expected one of {', '.join(CRITERIA)}, found "
                             f"{criterion!r}")
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
        return weights

    def _family_for(self, mask: NDArray, method: str) -> analytic.Family | None:
        """The closed form that serves this task and method, or None (numeric only)."""
        robot, family = self.robot, self.family
        if method == "analytic" and family is None:
            raise InputError(f"method: expected 'auto', 'lm' or 'newton' for {robot.name}, "
                             f"found 'analytic' (its geometry has no closed form here)")
        # A closed form solves its own task; a looser task (fewer flags) is the numeric solver's.
        if family is not None and not all(m or not f for m, f in zip(mask.tolist(),
                                                                      family.mask)):
            if method == "analytic":
                raise InputError(f"mask: expected one that includes "
                                 f"{mask_name(np.array(family.mask, bool))} for the closed "
                                 f"form of {robot.name}, found {mask_name(mask)}")
            family = None
        return None if method in ("lm", "newton") else family

    def _beyond(self, T: NDArray) -> NDArray:
        """(N,) Targets past the reach bound: no configuration reaches them."""
        d = T[:, :3, 3] - self.robot.chain.points[0]
        return np.sqrt(np.sum(d * d, axis=-1)) > self.reach * (1 + 1e-9)

    def _closed_form(self, request: _Request, beyond: NDArray) -> dict:
        """Best closed-form branch per target, or where the numeric solver must go."""
        N = request.T.shape[0]
        numeric_label = request.method if request.method in ("lm", "newton") else "lm"
        state = {"q": np.array(request.q_ref), "iterations": np.zeros(N, dtype=np.int64),
                 "reason": np.full(N, OK, dtype=object),
                 "method": np.full(N, numeric_label, dtype=object),
                 "numeric": np.ones(N, dtype=bool), "errors": np.zeros((N, 2)),
                 "inside": np.ones(N, dtype=bool)}
        family = request.family
        if family is None:
            return state
        C, errors, flags = analytic.candidates(self.robot.chain, family, request.T,
                                               request.q_ref, request.mask,
                                               request.tol_position, request.tol_rotation,
                                               self._threads)
        picked = self._pick(C, errors, flags, request.q_ref, request.criterion,
                            request.weights)
        rows, branch, found = np.arange(N), picked[:, 0], picked[:, 1]
        any_usable = found == USABLE
        has_real = flags[:, :, 0].any(axis=1)
        state["q"] = np.where(has_real[:, None], C[rows, branch], request.q_ref)
        state["errors"] = errors[rows, branch]
        state["inside"] = flags[rows, branch, 2]
        state["reason"] = np.array([OK, OUTSIDE_JOINT_LIMITS, OUT_OF_REACH],
                                   dtype=object)[found]
        state["method"][:] = f"analytic:{family.name}"
        # What the closed form misses goes to the numeric solver, from the closest branch: at a
        # singularity (a wrist with axes 4 and 6 aligned) the solutions form a continuum, and
        # the one branch the closed form picks may not close. Past the reach bound one attempt
        # finds the closest pose inside the limits (a telescope's branch may reach the target
        # outside them).
        state["numeric"] = (~any_usable if request.method == "auto"
                            else np.zeros(N, dtype=bool))
        state["method"][state["numeric"]] = f"analytic:{family.name}+lm"
        state["polish"] = True
        return state

    def _pick(self, C, errors, flags, q_ref, criterion, weights) -> NDArray:
        """(N, 2) int: each target's chosen branch and what it is (`choose.pick`)."""
        N = C.shape[0]
        given = (scores(self.robot, C, q_ref, criterion, weights)
                 if criterion == "manipulability" else _NO_SCORES)
        out = np.empty((N, 2), dtype=np.int64)
        pick.sized(N, C, errors, flags, np.ascontiguousarray(q_ref),
                   CRITERION_CODES[criterion],
                   _ONES[:self.robot.n] if weights is None else weights, self._bounds,
                   given, out)
        return out

    @property
    def _bounds(self) -> NDArray:
        """(3, n): the velocity limits (1 where none), lower and upper limits, as `pick` takes
        them (on first use)."""
        if self._pick_bounds is None:
            chain = self.robot.chain
            v = chain.velocity_limits
            object.__setattr__(self, "_pick_bounds", np.array(
                [np.where(np.isfinite(v), v, 1.0), chain.lower, chain.upper]))
        return self._pick_bounds

    def _poses(self, Q: NDArray) -> NDArray:
        """Tool poses (..., 4, 4) of Q (..., n) by the serial FK loop: checking candidates is
        a few microseconds per target, and threads on a busy machine would cost more."""
        flat = np.ascontiguousarray(Q.reshape(-1, self.robot.n))
        out = np.empty((flat.shape[0], 4, 4))
        k = self.robot.chain.kernel
        core.poses.sized(flat.shape[0], flat, k.F, k.I, out,
                             few=core.LIGHT_CONFIGURATIONS)
        return out.reshape(Q.shape[:-1] + (4, 4))

    def _numeric(self, request: _Request, beyond: NDArray, state: dict) -> None:
        """Levenberg-Marquardt (or Newton) where the closed form did not settle the target:
        from the closed form's branch, or q0, then the seed bank's nearest starts, then random
        ones. Beyond the reach bound one attempt finds the closest pose."""
        idx = np.flatnonzero(state["numeric"])
        if idx.size == 0:
            return
        first = None
        if state.get("polish"):
            first = state["q"][idx]
        elif request.q0_given:
            first = request.q_ref[idx]
        bank = self.bank if request.seeds else None
        if bank is not None:
            starts = bank.starts(request.T[idx], request.mask, SEEDS)
            if first is not None:
                starts = np.concatenate([first[:, None, :], starts[:, :-1]], axis=1)
        else:
            starts = (first if first is not None else request.q_ref[idx])[:, None, :]
        task = numeric.task_args(request.mask, request.tol_position, request.tol_rotation)
        method = request.method if request.method in ("lm", "newton") else "lm"
        for part, tries in ((~beyond[idx], request.restarts), (beyond[idx], 0)):
            if part.any():
                at = idx[part]
                q, _, iterations, errors = numeric.solve(
                    self._kernel, request.T[at], starts[part], task, method, request.max_iter,
                    tries, request.seed, self._threads)
                state["q"][at], state["iterations"][at], state["errors"][at] = q, iterations, errors
                state["inside"][at] = True      # the numeric solver stays inside the limits

    def _verdict(self, request: _Request, beyond: NDArray, state: dict) -> IKResult:
        """Success by forward kinematics and the limits; a reason for every failure."""
        pe, re = state["errors"][:, 0], state["errors"][:, 1]
        success = (pe < request.tol_position) & (re < request.tol_rotation) & state["inside"]
        reason = state["reason"]
        polished = state["numeric"]
        reason[polished & success] = OK
        failed = polished & ~success
        if failed.any():
            numeric_reason = self._numeric_reasons(state["q"][failed], beyond[failed],
                                                   request.mask, request.max_iter,
                                                   request.restarts)
            # Where the closed form had a verdict ("out of reach": no branch reaches the pose;
            # "outside joint limits": the limits refuse it) and the numeric solver agrees by
            # failing too, the closed form's verdict says more than "singular" or "did not
            # converge".
            keep = np.isin(reason[failed], (OUT_OF_REACH, OUTSIDE_JOINT_LIMITS))
            reason[failed] = np.where(keep, reason[failed], numeric_reason)
        # Past the reach bound no configuration reaches the target, whatever a closed form
        # with a long enough stroke would say about the limits.
        reason[beyond & ~success] = OUT_OF_REACH
        lead = request.lead
        return IKResult(_one_or_many(success, lead), state["q"].reshape(lead + (self.robot.n,)),
                        _one_or_many(pe, lead), _one_or_many(re, lead),
                        _one_or_many(state["iterations"], lead),
                        _one_or_many(reason.astype(str), lead),
                        _one_or_many(state["method"].astype(str), lead), request.criterion,
                        mask_name(request.mask))

    def _numeric_reasons(self, q, beyond, mask, max_iter, restarts) -> NDArray:
        """Why numeric solves failed: out of reach, at a singularity, or not converged.

        "singular" means the task Jacobian at the best q has lower rank than the arm has in
        general for that task (an arm that never spans the task is not called singular).
        """
        rows = np.flatnonzero(mask)
        general = np.random.default_rng(0).uniform(*self.robot.chain.sampling_limits,
                                                   (8, self.robot.n))
        generic = _task_rank(pose_and_jacobian(self.robot, general)[1], rows).max()
        rank = _task_rank(pose_and_jacobian(self.robot, q)[1], rows)
        return np.select([beyond, rank < generic], [OUT_OF_REACH, SINGULAR],
                         not_converged(max_iter, restarts + 1))

    # --- every closed-form solution -----------------------------------------------------------

    def solutions(self, targets: ArrayLike, *, mask: str | ArrayLike | None = None,
                  tol_position: float = 1e-9, tol_rotation: float = 1e-9) -> IKSolutions:
        """Every closed-form solution of each target, each checked by forward kinematics.

        Parameters
        ----------
        targets : array_like, shape (4, 4) or (..., 4, 4)
        mask : str or 6 flags, optional
            The task the solutions must meet; the closed form's own task if omitted.

        Returns
        -------
        IKSolutions
            One target: its distinct solutions (k, n). A batch: padded (..., K, n) with a
            validity mask (see `IKSolutions`). Angles are folded into the limits where a turn
            allows it; no solution if the target is out of reach.

        Raises
        ------
        InputError
            If the robot's geometry has no closed form, or a target is not a pose.
        """
        family = self.family
        if family is None:
            raise InputError(f"robot: expected an arm with a closed form (lift-and-swing, yaw "
                             f"and three pitches, three parallel joints and a wrist, or a "
                             f"spherical wrist), found {self.robot.name}, which only the "
                             f"numeric solvers serve")
        one = _pose_fast(targets)
        lead = ()
        if one is not None:
            T = one[0]
        else:
            T = as_transform(targets, "target")
            lead = T.shape[:-2]
        flat = T.reshape(-1, 4, 4)
        mask = self.default_mask if mask is None else as_mask(mask)
        name = self.default_name if mask is self.default_mask else mask_name(mask)
        N, n = flat.shape[0], self.robot.n
        # The kernel folds angles nearest 0 and marks the valid branches: those that reach
        # the target and differ from every earlier valid one (a degenerate subproblem gives
        # one solution twice).
        C, errors, flags = analytic.candidates(self.robot.chain, family, flat, np.zeros((N, n)),
                                               mask, tol_position, tol_rotation, self._threads)
        if lead == ():
            # `compress` on basic-indexed views: NumPy's mixed integer and array indexing
            # (C[0, rows]) costs several times as much for a handful of rows.
            valid = flags[0, :, 3]
            q = C[0].compress(valid, axis=0)
            pe, re = errors[0].T.compress(valid, axis=1)
            return IKSolutions(q, valid.compress(valid), flags[0, :, 2].compress(valid), pe, re,
                               len(q), family.name, name)
        valid = flags[..., 3]
        order = np.argsort(~valid, axis=1, kind="stable")      # real rows first, in order
        take = lambda a: np.take_along_axis(a, order, axis=1)  # noqa: E731
        valid = take(valid)
        q = np.where(valid[..., None], np.take_along_axis(C, order[..., None], axis=1), np.nan)
        fields = (np.where(valid, take(flags[..., 2]), False),
                  np.where(valid, take(errors[..., 0]), np.nan),
                  np.where(valid, take(errors[..., 1]), np.nan))
        count = valid.sum(axis=1)
        shape = lambda a: a.reshape(lead + a.shape[1:])        # noqa: E731
        return IKSolutions(shape(q), shape(valid), *(shape(f) for f in fields), shape(count),
                           family.name, name)

    # --- following a moving target ------------------------------------------------------------

    def track(self, targets: ArrayLike, q_start: ArrayLike, *,
              mask: str | ArrayLike | None = None, tol_position: float = 1e-9,
              tol_rotation: float = 1e-9, max_iter: int = 50,
              max_joint_step: float = np.inf) -> IKTrack:
        """Follow a sequence of targets, each solve starting from the previous solution.

        No restart and no closed form: the solution moves continuously on the branch q_start
        picks, and the sequence stops at the first target not reached from the previous
        solution, or (after the first target) whose solution moved a joint by more than
        `max_joint_step` (the arm would jump).

        Parameters
        ----------
        targets : array_like, shape (K, 4, 4)
        q_start : array_like, shape (n,)
            A configuration at or near the first target.
        mask : str or 6 flags, optional
            The task; the robot's default if omitted.
        tol_position, tol_rotation : float
            m and rad, per target.
        max_iter : int
            Iterations per target.
        max_joint_step : float
            rad for revolute joints, m for prismatic ones.

        Returns
        -------
        IKTrack
        """
        T = as_transform(targets, "targets")
        if T.ndim != 3:
            raise InputError(f"targets: expected a sequence of poses (K, 4, 4), found {T.shape}")
        q_start = joint_array(self.robot, q_start, "q_start")
        if q_start.shape != (self.robot.n,):
            raise InputError(f"q_start: expected one configuration ({self.robot.n},), found "
                             f"{q_start.shape}")
        mask = self.default_mask if mask is None else as_mask(mask)
        for name, value in (("tol_position", tol_position), ("tol_rotation", tol_rotation),
                            ("max_joint_step", max_joint_step)):
            if not value > 0:
                raise InputError(f"{name}: expected a positive number, found {value}")
        if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
            raise InputError(f"max_iter: expected a whole number >= 1, found {max_iter!r}")
        q, followed, cause = numeric.track(
            self._kernel, T, q_start, numeric.task_args(mask, tol_position, tol_rotation),
            max_iter, max_joint_step)
        reason = (OK, not_converged(max_iter, 1), SINGULAR)[cause]
        return IKTrack(q, followed, cause == 0, reason)


def _task_rank(J: NDArray, rows: NDArray) -> NDArray:
    """Numerical rank (...,) of the task rows of Jacobians (..., 6, n)."""
    s = np.linalg.svd(J[..., rows, :], compute_uv=False)
    return np.sum(s > 1e-6 * s[..., :1], axis=-1)
