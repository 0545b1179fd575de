"""Kinematic calibration: the arm's geometric parameters from measured tool positions or poses.

The robot's own table (standard DH, modified DH, or screws) is written as a product of
elementary motions, each a rotation about or a translation along one local axis whose amount is
a parameter (plus a joint value, for the joint's own motion):

    standard DH row   Rz(theta) Tz(d) Tx(a) Rx(alpha)
    modified DH row   Rx(alpha) Tx(a) Rz(theta) Tz(d)
    screw row         H P Rz(offset) P^-1 H^-1, P = Tx(shift_x) Ty(shift_y) Rx(tilt_x) Ry(tilt_y)
    base, tool        T_base Tx Ty Tz Rx Ry Rz,  ... T_tool Tx Ty Tz Rx Ry Rz

(H puts z on the screw's nominal axis through its point). The identification Jacobian is then
analytic: a rotation about the unit axis w through o moves the tool point p by ``w x (p - o)``
per radian and turns the tool by w; a translation along w moves it by w.

Identifiability: QR with column pivoting of the Jacobian with unit columns (Hollerbach and
Wampler, 1996). Parameters past the numerical rank are held at nominal, and each is named with
the identifiable combination that has the same effect. Only the identifiable set is fitted
(Gauss-Newton on the normal equations). Nominal values can hide parameters that the true arm
shows (a tool point on the last axis makes two of the wrist's parameters act as others do), so
a second pass at the fitted values adds each held parameter whose effect there is distinct and
significant against the residual noise (a score test), and fits again. The standard deviations
come from the residuals, and the observability from the scaled Jacobian's singular values: the
condition number and O1 = (s_1 ... s_L)^(1/L) / sqrt(m) (Borm and Menq, 1991).
`select_poses` picks, from a pool, the configurations that maximise det(J^T J) of the
identifiable set (greedy D-optimal design).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from armkit.jit import kernel
from armkit.errors import InputError
from armkit.kinematics.forward import fk
from armkit.model.dh import DHTable, chain_from_dh
from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
from armkit.model.robot import Robot, joint_array
from armkit.spatial import as_array, as_transform, invert, log_so3, translation

PARTS = ("table", "base", "tool")
_AXES = {"rx": (0, True), "ry": (1, True), "rz": (2, True),
         "tx": (0, False), "ty": (1, False), "tz": (2, False)}


@dataclass(frozen=True)
class _Motion:
    kind: str           # rx ry rz tx ty tz
    param: int          # index into the parameters, -1 for none
    joint: int          # index of the joint whose value adds in, -1 for none
    sign: float = 1.0


@dataclass(frozen=True)
class ParametricModel:
    """A robot's table as a product of constants and elementary motions, with its parameters.

    Attributes
    ----------
    names : tuple of str
        ``row.column`` (``swing1.a``), ``T_base.x`` .. ``T_base.rz``, ``T_tool.x`` ...
    nominal : ndarray, shape (P,)
        The parameters' values in the robot's table, SI (m, rad).
    angular : ndarray of bool, shape (P,)
        True for angles (rad), False for lengths (m).
    factors : tuple
        Constant (4, 4) arrays and elementary motions, in product order.
    codes, signs, constants : ndarray, shapes (F, 3), (F,), (F, 4, 4)
        The factors as the compiled kernel takes them: per factor its kind (0-2 rotation
        about x, y, z; 3-5 translation along x, y, z; 6 constant), parameter and joint index
        (-1 for none), the motion's sign, and the constant (identity for a motion).
    """

    robot: Robot
    names: tuple[str, ...]
    nominal: NDArray
    angular: NDArray
    factors: tuple
    inner: tuple[int, int]
    codes: NDArray
    signs: NDArray
    constants: NDArray


def _frame_aligning(axis: NDArray, point: NDArray) -> NDArray:
    """A frame at `point` whose z is `axis` (unit)."""
    x = np.cross(np.eye(3)[np.argmin(np.abs(axis))], axis)
    x /= np.linalg.norm(x)
    T = translation(point)
    T[:3, :3] = np.column_stack([x, np.cross(axis, x), axis])
    return T


def parametric_model(robot: Robot, parts=PARTS) -> ParametricModel:
    """The robot's table (DH, modified DH or screws) with its base and tool as parameters.

    Parameters
    ----------
    parts : sequence of {"table", "base", "tool"}
        Which parameters to free; the others stay constant.

    Raises
    ------
    InputError
        If the robot was not built from a DH, modified-DH or screw table (e.g. a URDF).
    """
    table = robot.table
    if not isinstance(table, (DHTable, ScrewTable)):
        raise InputError(f"robot {robot.name}: expected one built from a DH, modified DH or "
                         f"screw table for kinematic calibration, found "
                         f"{type(table).__name__}")
    unknown = set(parts) - set(PARTS)
    if unknown:
        raise InputError(f"parts: expected some of {', '.join(PARTS)}, found "
                         f"{', '.join(sorted(unknown))}")
    names, nominal, angular, factors = [], [], [], []

    def param(name, value, is_angle, free=True):
        if not free:
            return -1
        names.append(name)
        nominal.append(float(value))
        angular.append(is_angle)
        return len(names) - 1

    def frame_params(prefix, free):
        return [_Motion(k, param(f"{prefix}.{k[1] if k[0] == 't' else k}", 0.0, k[0] == "r",
                                 free), -1)
                for k in ("tx", "ty", "tz", "rx", "ry", "rz")]

    free_table = "table" in parts
    factors.append(np.array(table.T_base))
    if "base" in parts:
        factors += frame_params("T_base", True)
    start = len(factors)
    if isinstance(table, DHTable):
        joint = 0
        for k, row in enumerate(table.rows):
            label = row.name or f"row{k + 1}"
            j_theta = joint if row.kind == "revolute" else -1
            j_d = joint if row.kind == "prismatic" else -1
            motions = {
                "alpha": _Motion("rx", param(f"{label}.alpha", row.alpha, True, free_table), -1),
                "a": _Motion("tx", param(f"{label}.a", row.a, False, free_table), -1),
                "theta": _Motion("rz", param(f"{label}.theta", row.theta, True, free_table),
                                 j_theta),
                "d": _Motion("tz", param(f"{label}.d", row.d, False, free_table), j_d)}
            order = (("alpha", "a", "theta", "d") if table.modified
                     else ("theta", "d", "a", "alpha"))
            for key in order:
                m = motions[key]
                if m.param < 0:                 # held value: the joint's motion, then a constant
                    if m.joint >= 0:
                        factors.append(m)
                    factors.append(_constant(m.kind, getattr(row, key)))
                else:
                    factors.append(m)
            joint += row.kind != "fixed"
    else:
        for i, row in enumerate(table.rows):
            label = row.name or f"q{i + 1}"
            axis = row.axis / np.linalg.norm(row.axis)
            H = _frame_aligning(axis, np.zeros(3) if row.point is None else row.point)
            revolute = row.kind == "revolute"
            P = []
            if revolute:
                P += [_Motion("tx", param(f"{label}.shift_x", 0.0, False, free_table), -1),
                      _Motion("ty", param(f"{label}.shift_y", 0.0, False, free_table), -1)]
            P += [_Motion("rx", param(f"{label}.tilt_x", 0.0, True, free_table), -1),
                  _Motion("ry", param(f"{label}.tilt_y", 0.0, True, free_table), -1)]
            P = [m for m in P if m.param >= 0]
            motion = _Motion("rz" if revolute else "tz",
                             param(f"{label}.offset", 0.0, revolute, free_table), i)
            factors += [H, *P, motion, *[replace(m, sign=-1.0) for m in reversed(P)], invert(H)]
        factors.append(np.array(table.T_home))
    stop = len(factors)
    factors.append(np.array(table.T_tool))
    if "tool" in parts:
        factors += frame_params("T_tool", True)
    nominal_a, angular_a = np.array(nominal, dtype=float), np.array(angular, dtype=bool)
    kinds = ("rx", "ry", "rz", "tx", "ty", "tz")
    codes = np.array([(6, -1, -1) if isinstance(f, np.ndarray)
                      else (kinds.index(f.kind), f.param, f.joint) for f in factors],
                     dtype=np.int64).reshape(-1, 3)
    signs = np.array([1.0 if isinstance(f, np.ndarray) else f.sign for f in factors])
    constants = np.array([f if isinstance(f, np.ndarray) else np.eye(4) for f in factors],
                         dtype=float).reshape(-1, 4, 4)
    for a in (nominal_a, angular_a, codes, signs, constants):
        a.flags.writeable = False
    return ParametricModel(robot, tuple(names), nominal_a, angular_a, tuple(factors),
                           (start, stop), codes, signs, constants)


def _constant(kind: str, value: float) -> NDArray:
    return _elementary(kind, np.array([value]))[0]


def _elementary(kind: str, v: NDArray) -> NDArray:
    """Elementary transforms (m, 4, 4) for amounts v (m,)."""
    axis, rotation = _AXES[kind]
    E = np.zeros(v.shape + (4, 4))
    E[..., [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    if rotation:
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        c, s = np.cos(v), np.sin(v)
        E[..., i, i], E[..., j, j], E[..., i, j], E[..., j, i] = c, c, -s, s
    else:
        E[..., axis, 3] = v
    return E


def evaluate(model: ParametricModel, params: NDArray, Q: NDArray,
             jacobian: bool = True) -> tuple[NDArray, NDArray | None]:
    """Tool poses (m, 4, 4) at joint values Q (m, n), and the identification Jacobian.

    Returns
    -------
    T : ndarray, shape (m, 4, 4)
    J : ndarray, shape (m, 6, P) or None
        Rows 0-2: the tool position's derivative (m per parameter unit); rows 3-5: the tool
        rotation's, as an angular velocity in the base frame (rad per parameter unit).
    """
    Q = np.ascontiguousarray(Q, dtype=float)
    T, J = _evaluate_kernel(model.codes, model.signs, model.constants,
                            np.ascontiguousarray(params, dtype=float), Q, jacobian)
    return T, (J if jacobian else None)


@kernel(cache=True, nogil=True)
def _evaluate_kernel(codes, signs, constants, params, Q, jacobian):
    """`evaluate` compiled: per configuration, the product of the factors kept as its four
    columns C[0..3] (x, y, z, position; right-multiplying by an elementary motion changes one
    or two of them), with the axis and origin of every parametrised motion recorded for the
    Jacobian. Scalar loops only: array expressions would multiply the compile time."""
    m, F, P = Q.shape[0], codes.shape[0], params.shape[0]
    T = np.zeros((m, 4, 4))
    J = np.zeros((m if jacobian else 0, 6, P))
    records = np.zeros((F, 6))               # per factor: axis, origin after it
    C = np.zeros((4, 3))
    new = np.zeros((4, 3))
    for i in range(m):
        for c in range(4):
            for e in range(3):
                C[c, e] = 1.0 if c == e else 0.0
        for f in range(F):
            kind, k, joint = codes[f, 0], codes[f, 1], codes[f, 2]
            if kind == 6:
                for c in range(4):
                    for e in range(3):
                        v = constants[f, 0, c] * C[0, e] + constants[f, 1, c] * C[1, e] \
                            + constants[f, 2, c] * C[2, e]
                        if c == 3:
                            v += C[3, e]
                        new[c, e] = v
                for c in range(4):
                    for e in range(3):
                        C[c, e] = new[c, e]
                continue
            v = 0.0
            if joint >= 0:
                v += Q[i, joint]
            if k >= 0:
                v += params[k]
            v *= signs[f]
            a = kind % 3
            if kind < 3:
                p = (a + 1) % 3                  # the columns a rotation about a mixes
                q = (a + 2) % 3
                cv = np.cos(v)
                sv = np.sin(v)
                for e in range(3):
                    cp = C[p, e]
                    cq = C[q, e]
                    C[p, e] = cv * cp + sv * cq
                    C[q, e] = cv * cq - sv * cp
            else:
                for e in range(3):
                    C[3, e] += v * C[a, e]
            if jacobian and k >= 0:
                for e in range(3):
                    records[f, e] = C[a, e]
                    records[f, 3 + e] = C[3, e]
        for c in range(4):
            for e in range(3):
                T[i, e, c] = C[c, e]
        T[i, 3, 3] = 1.0
        if not jacobian:
            continue
        for f in range(F):
            k = codes[f, 1]
            if k < 0 or codes[f, 0] == 6:
                continue
            sg = signs[f]
            w0, w1, w2 = records[f, 0], records[f, 1], records[f, 2]
            if codes[f, 0] < 3:
                d0 = C[3, 0] - records[f, 3]
                d1 = C[3, 1] - records[f, 4]
                d2 = C[3, 2] - records[f, 5]
                J[i, 0, k] += sg * (w1 * d2 - w2 * d1)
                J[i, 1, k] += sg * (w2 * d0 - w0 * d2)
                J[i, 2, k] += sg * (w0 * d1 - w1 * d0)
                J[i, 3, k] += sg * w0
                J[i, 4, k] += sg * w1
                J[i, 5, k] += sg * w2
            else:
                J[i, 0, k] += sg * w0
                J[i, 1, k] += sg * w1
                J[i, 2, k] += sg * w2
    return T, J


# --- identifiability -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Identifiability:
    """Which parameters the data determines.

    Attributes
    ----------
    identifiable : ndarray of int
        Indices of the identifiable parameters (the QR pivots up to the numerical rank).
    unidentifiable : ndarray of int
    dependencies : dict
        For each unidentifiable parameter name: ``{other name: coefficient}``, the identifiable
        parameters whose change ``coefficient * delta`` has the same effect as its change
        delta; empty when it has no effect at all.
    """

    identifiable: NDArray
    unidentifiable: NDArray
    dependencies: dict


def identifiability(J: NDArray, names, rank_tol: float = 1e-7,
                    priority: NDArray | None = None) -> Identifiability:
    """QR with column pivoting of J (rows, P) with unit columns; `rank_tol` relative to the
    largest pivot.

    ``priority`` (P,), near 1, breaks ties between columns with the same effect: of two, the
    one with the larger priority is kept (by default, the table's own parameters before the
    base and tool frames')."""
    if priority is None:
        priority = np.array([0.98 if n.startswith(("T_base.", "T_tool.")) else 1.0
                             for n in names])
    norms = np.linalg.norm(J, axis=0)
    live = np.flatnonzero(norms > 1e-12 * max(norms.max(initial=0.0), 1e-300))
    dead = np.setdiff1d(np.arange(J.shape[1]), live)
    dependencies = {names[k]: {} for k in dead}
    if live.size == 0:
        return Identifiability(live, dead, dependencies)
    Js = J[:, live] * (priority[live] / norms[live])
    # A plain QR first shrinks the rows to P; the pivoted QR of that R has the same pivots and
    # diagonal (R0^T R0 = Js^T Js) at a fraction of the cost on thousands of rows.
    _, R, piv = scipy.linalg.qr(_r_factor(Js), pivoting=True)
    d = np.abs(np.diag(R))
    rank = int(np.sum(d > rank_tol * d[0]))
    kept, dropped = live[piv[:rank]], live[piv[rank:]]
    if dropped.size:
        coef = np.linalg.solve(R[:rank, :rank], R[:rank, rank:])
        for c, k in zip(coef.T, dropped):
            # back to the parameters' own units
            scale = (norms[k] / norms[kept]) * (priority[kept] / priority[k])
            dependencies[names[k]] = {names[i]: float(ci) for i, ci in
                                      zip(kept, c * scale) if abs(ci) > 1e-9}
    unidentifiable = np.sort(np.concatenate([dead, dropped]))
    ordered = {names[k]: dependencies[names[k]] for k in unidentifiable}
    return Identifiability(np.sort(kept), unidentifiable, ordered)


def _r_factor(A: NDArray, rows: int = 128) -> NDArray:
    """R of A's QR, block by block (R of [R_so_far; next rows]): the same R up to row signs,
    and on a busy machine many times faster than one LAPACK call on a tall matrix, which
    spends its time waiting for its threads."""
    R = np.linalg.qr(A[:rows], mode="r")
    for start in range(rows, len(A), rows):
        R = np.linalg.qr(np.vstack([R, A[start:start + rows]]), mode="r")
    return R


def dependency_text(name: str, combination: dict) -> str:
    """``lift.d: moves the tool as 1*base.d does`` (or ``has no effect on the measurements``)."""
    if not combination:
        return f"{name}: has no effect on the measurements"
    terms = " + ".join(f"{c:.6g}*{other}" for other, c in combination.items())
    return f"{name}: moves the tool as {terms.replace('+ -', '- ')} does"


# --- calibration ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class CalibrationResult:
    """Kinematic calibration outcome.

    Attributes
    ----------
    success : bool
    reason : str
    robot : Robot
        The identified robot (its table in the original convention and units).
    names : tuple of str
    nominal, identified : ndarray, shape (P,)
        Parameter values, SI (m, rad).
    std : ndarray, shape (P,)
        Standard deviations of the identified values (0 for those held at nominal).
    angular : ndarray of bool, shape (P,)
    identifiable : ndarray of bool, shape (P,)
    dependencies : dict
        For each parameter held at nominal, the combination of identified ones it acts as.
    residuals_before, residuals_after : ndarray, shape (m,)
        Position error per measurement (m), nominal and identified model.
    holdout_before, holdout_after : ndarray, shape (h,)
        The same on the hold-out set (empty without one).
    condition_number, o1 : float
        Of the scaled identification Jacobian (identifiable columns).
    iterations : int
    added : dict
        Parameters held at nominal by the analysis at the nominal values but identified at the
        fitted ones (the second pass), each with the significance of its effect there
        (standard deviations of the residual noise).
    """

    success: bool
    reason: str
    robot: Robot
    names: tuple[str, ...]
    nominal: NDArray
    identified: NDArray
    std: NDArray
    angular: NDArray
    identifiable: NDArray
    dependencies: dict
    residuals_before: NDArray
    residuals_after: NDArray
    holdout_before: NDArray
    holdout_after: NDArray
    condition_number: float
    o1: float
    iterations: int
    added: dict


def _measurements(robot: Robot, q: ArrayLike, measured: ArrayLike, name: str):
    Q = joint_array(robot, q, f"{name} q")
    if Q.ndim != 2:
        raise InputError(f"{name} q: expected shape (m, {robot.n}), found {Q.shape}")
    M = np.asarray(measured, dtype=float) if not isinstance(measured, np.ndarray) else measured
    if M.shape == (len(Q), 3):
        M = as_array(M, f"{name} positions", (3,))
    elif M.shape == (len(Q), 4, 4):
        M = as_transform(M, f"{name} poses")
    else:
        raise InputError(f"{name} measurements: expected shape ({len(Q)}, 3) positions or "
                         f"({len(Q)}, 4, 4) poses, found {M.shape}")
    return Q, M


def _residual(T: NDArray, M: NDArray, rotation_weight: float) -> NDArray:
    """Measured minus model: positions (m, 3), with poses also rotations (m, 3) * weight."""
    r = (M[:, :3, 3] if M.ndim == 3 else M) - T[:, :3, 3]
    if M.ndim == 3:
        rot = log_so3(M[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2))
        r = np.concatenate([r, rotation_weight * rot], axis=1)
    return r


def _rows(J: NDArray, M: NDArray, rotation_weight: float) -> NDArray:
    return (np.concatenate([J[:, :3], rotation_weight * J[:, 3:]], axis=1) if M.ndim == 3
            else J[:, :3])


def _position_errors(T: NDArray, M: NDArray) -> NDArray:
    return np.linalg.norm((M[:, :3, 3] if M.ndim == 3 else M) - T[:, :3, 3], axis=-1)


def calibrate(robot: Robot, q: ArrayLike, measured: ArrayLike, *,
              holdout: tuple[ArrayLike, ArrayLike] | None = None, parts=PARTS,
              rank_tol: float = 1e-7, rotation_weight: float = 0.1,
              iterations: int = 50, significance: float = 2.0) -> CalibrationResult:
    """Identify the robot's table, base and tool from measurements at joint values.

    The parameters identifiable at the nominal values are fitted first (Gauss-Newton). Some
    held ones only look unidentifiable at nominal, whose special geometry (a tool point on the
    last axis, exactly perpendicular or parallel axes) hides them; a second pass at the fitted
    values adds each held parameter whose effect there, beyond the fitted ones', is both
    numerically distinct (at least ``ADDED_TOL`` of its size) and significant against the
    residual noise (``significance`` standard deviations), then fits again.

    Parameters
    ----------
    robot : Robot
        Built from a DH, modified DH or screw table; its values are the nominal ones.
    q : array_like, shape (m, n)
        Joint values of the measurements (rad, m).
    measured : array_like, shape (m, 3) or (m, 4, 4)
        Measured tool positions (m) or poses, in the robot's base frame.
    holdout : (q, measured), optional
        Measurements kept out of the fit, on which the error before and after is reported.
    parts : sequence of {"table", "base", "tool"}
    rank_tol : float
        Relative size of a QR pivot below which parameters are taken as unidentifiable.
    rotation_weight : float
        m per rad: weight of pose measurements' rotation residuals against their positions.
    significance : float
        How many standard deviations of the residual noise a held parameter's effect at the
        fitted values must reach to be added; ``inf`` keeps the nominal analysis only.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InputError
        Shapes that do not match the robot, non-finite values, a robot without a table.
    """
    Q, M = _measurements(robot, q, measured, "measurements")
    if holdout is not None:
        Qh, Mh = _measurements(robot, holdout[0], holdout[1], "holdout")
    model = parametric_model(robot, parts)

    weights = np.array([1.0, 1.0, 1.0] + [rotation_weight if M.ndim == 3 else 0.0] * 3)

    def system(params):
        """Poses, residual, and the normal equations J^T J, J^T r of all the parameters."""
        T, J = evaluate(model, params, Q)
        r = _residual(T, M, rotation_weight)
        A = _rows(J, M, rotation_weight)                        # (m, rows per measurement, P)
        return T, r.ravel(), _gram_kernel(J, weights), np.einsum("mip,mi->p", A, r), A

    T, r, G, g, A = system(model.nominal)
    found = identifiability(A.reshape(-1, A.shape[-1]), model.names, rank_tol)
    free = found.identifiable
    before = _position_errors(T, M)
    state, done = _gauss_newton(system, model.nominal.copy(), free, (T, r, G, g), iterations)
    added: dict[str, float] = {}
    for _ in range(3):                       # each pass at the values the last fit reached
        params, T, r, G, g = state
        new = _significant_held(G, g, r @ r, len(r), free, significance)
        if not new:
            break
        added.update({model.names[k]: z for k, z in new.items()})
        free = np.sort(np.concatenate([free, list(new)]))
        state, more = _gauss_newton(system, params, free, (T, r, G, g), iterations)
        done += more
    params, T, r, G, g = state
    norms = np.sqrt(np.diag(G)[free])
    gram = G[np.ix_(free, free)] / np.outer(norms, norms)    # of the scaled Jacobian
    s = np.sqrt(np.clip(np.linalg.eigvalsh(gram), 0, None))[::-1]
    dof = max(len(r) - len(free), 1)
    cov = (r @ r) / dof * np.linalg.pinv(gram) / np.outer(norms, norms)
    std = np.zeros(len(params))
    std[free] = np.sqrt(np.clip(np.diag(cov), 0, None))
    condition = float(s[0] / s[-1]) if s.size and s[-1] > 0 else np.inf
    o1 = float(np.exp(np.mean(np.log(s))) / np.sqrt(len(Q))) if s.size and s[-1] > 0 else 0.0
    identified = identified_robot(model, params)
    if holdout is not None:
        hold_before = _position_errors(fk(robot, Qh), Mh)
        hold_after = _position_errors(evaluate(model, params, Qh, False)[0], Mh)
    else:
        hold_before = hold_after = np.zeros(0)
    after = _position_errors(T, M)
    success = bool(np.all(np.isfinite(params)))
    dependencies = {n: c for n, c in found.dependencies.items() if n not in added}
    return CalibrationResult(
        success, "ok" if success else "the solve diverged", identified, model.names,
        model.nominal, params, std, model.angular,
        np.isin(np.arange(len(params)), free), dependencies, before, after,
        hold_before, hold_after, condition, o1, done, added)


# A held parameter is added at the fitted values only when its effect there, beyond the fitted
# parameters', is at least this fraction of its own: below it, its whole effect on a
# measurement is under 1e-4 of the parameter's error times its lever (0.1 um per mm of error
# on a 1 m arm), and its estimate would swing by metres on noise (a length along one of two
# nearly parallel axes is such a parameter).
ADDED_TOL = 1e-4

# The residual's standard deviation is taken as at least this (m): below it, measurements and
# model agree to rounding and there is nothing left to explain.
_SIGMA_FLOOR = 1e-12

# Residuals (m) at which a fit has met the measurements to rounding.
_ROUNDING = 1e-14


def _significant_held(G: NDArray, g: NDArray, rr: float, rows: int, free: NDArray,
                      significance: float) -> dict[int, float]:
    """Held parameters to add at the fitted values, with their significance.

    From the normal equations G = J^T J, g = J^T r and rr = r^T r of all the parameters:
    greedily, the held parameter whose column beyond the span of the fitted ones explains the
    most of the residual, while that reaches `significance` standard deviations of the
    residual noise (a score test of the parameter at its nominal value) and its column beyond
    the fitted ones is at least ADDED_TOL of its length. The parts beyond come from the Schur
    complement of the fitted block in G with unit columns; their rounding error is about
    1e-16 times that block's condition number (the square of the one reported), far below
    ADDED_TOL ** 2 for any set the first pass accepts."""
    if not np.isfinite(significance):
        return {}
    d = np.sqrt(np.clip(np.diag(G), 0, None))
    held = np.setdiff1d(np.flatnonzero(d > 1e-12 * d.max()), free)
    if held.size == 0:
        return {}
    Gs, gs = G / np.outer(d, d).clip(1e-300), g / d.clip(1e-300)
    Gff = Gs[np.ix_(free, free)]
    X = np.linalg.solve(Gff, np.column_stack([Gs[np.ix_(free, held)], gs[free]]))
    S = Gs[np.ix_(held, held)] - Gs[np.ix_(free, held)].T @ X[:, :-1]  # Gram of the parts beyond
    s = gs[held] - Gs[np.ix_(free, held)].T @ X[:, -1]                 # and their scores
    rr = rr - gs[free] @ X[:, -1]
    dof = rows - len(free)
    chosen: dict[int, float] = {}
    while dof > 1:
        size2 = np.diag(S).copy()
        live = size2 > ADDED_TOL ** 2
        if not live.any():
            break
        sigma = max(np.sqrt(max(rr, 0.0) / dof), _SIGMA_FLOOR)
        z = np.where(live, np.abs(s) / np.sqrt(np.where(live, size2, 1.0)) / sigma, 0.0)
        best = int(np.argmax(z))
        if z[best] < significance:
            break
        chosen[int(held[best])] = float(z[best])
        column, score = S[:, best].copy(), s[best]
        rr -= score ** 2 / size2[best]
        s = s - column * score / size2[best]
        S = S - np.outer(column, column) / size2[best]
        S[best, :] = S[:, best] = 0.0
        dof -= 1
    return chosen


def _gauss_newton(system, params: NDArray, free: NDArray, current: tuple, iterations: int):
    """Gauss-Newton on the parameters `free` from `params`, whose (T, r, G, g) are `current`;
    a step that does not lower the cost is halved. It stops when the next step would move
    the parameters by less than 1 % of their standard deviations (its predicted decrease of
    the cost, step^T G step, below 1e-4 of the residual variance), when the residuals are at
    rounding or no step lowers the cost, or after `iterations`.
    Returns (params, T, r, G, g) at the end and the iterations done."""
    T, r, G, g = current
    cost, done = r @ r, 0
    for done in range(1, iterations + 1):
        if cost <= len(r) * _ROUNDING ** 2:
            break                            # the model meets the measurements to rounding
        step = _gauss_newton_step(G[np.ix_(free, free)], g[free])
        if step @ g[free] <= 1e-4 * cost / max(len(r) - len(free), 1):
            break
        for _ in range(10):                  # halve a step that does not lower the cost
            trial = params.copy()
            trial[free] += step
            new = system(trial)
            if new[1] @ new[1] <= cost:
                break
            step /= 2
        else:
            break                            # converged to rounding: no step lowers the cost
        params, (T, r, G, g, _) = trial, new
        cost = r @ r
        if np.abs(step).max() < 1e-14:
            break
    return (params, T, r, G, g), done


@kernel(cache=True, nogil=True)
def _gram_kernel(J, weights):
    """sum over measurements and rows k of (weights[k] J[i, k])^T (weights[k] J[i, k]): the
    normal matrix (P, P) of J (m, 6, P) on one thread (a BLAS product of this tall, thin
    matrix waits for its threads on a busy machine)."""
    m, rows, P = J.shape
    G = np.zeros((P, P))
    for i in range(m):
        for k in range(rows):
            w2 = weights[k] * weights[k]
            if w2 == 0.0:
                continue
            for a in range(P):
                x = J[i, k, a] * w2
                if x != 0.0:
                    for b in range(P):
                        G[a, b] += x * J[i, k, b]
    return G


def _gauss_newton_step(G: NDArray, g: NDArray) -> NDArray:
    """The least-squares step J^+ r from the normal equations G = J^T J, g = J^T r, solved
    with unit columns: the identifiable set is well conditioned (its scaled condition number
    is reported), and a P x P solve costs far less than a QR of thousands of rows."""
    norms = np.sqrt(np.diag(G))
    norms = np.where(norms > 0, norms, 1.0)
    return np.linalg.solve(G / np.outer(norms, norms), g / norms) / norms


def identified_robot(model: ParametricModel, params: NDArray) -> Robot:
    """The robot with `params` written into its own table (same convention, units, limits)."""
    robot, table = model.robot, model.robot.table
    value = dict(zip(model.names, params))
    T_base = _frame(table.T_base, value, "T_base")
    T_tool = _frame(table.T_tool, value, "T_tool")
    if isinstance(table, DHTable):
        rows = []
        for k, row in enumerate(table.rows):
            label = row.name or f"row{k + 1}"
            rows.append(replace(row, **{c: value.get(f"{label}.{c}", getattr(row, c))
                                        for c in ("alpha", "a", "d", "theta")}))
        new = DHTable(tuple(rows), table.modified, T_base, T_tool)
        chain = chain_from_dh(new)
    else:
        # Screws at q = 0 of the identified product: each joint's axis and a point on it in
        # the frame after the base, and the home pose M (Lynch and Park, ch. 4).
        rows, T = [], np.eye(4)
        for f in model.factors[model.inner[0]:model.inner[1]]:
            if isinstance(f, np.ndarray):
                T = T @ f
                continue
            amount = f.sign * (params[f.param] if f.param >= 0 else 0.0)
            if f.joint >= 0:
                old = table.rows[f.joint]
                point = T[:3, 3] if old.kind == "revolute" or old.point is not None else None
                rows.append(ScrewRow(old.kind, T[:3, 2].copy(), old.limits,
                                     None if point is None else point.copy(), old.name))
            T = T @ _elementary(f.kind, np.array([amount]))[0]
        new = ScrewTable(tuple(rows), T, T_base, T_tool)
        chain = chain_from_poe(new)
    return Robot(robot.name, chain, robot.units, robot.description, new)


def _frame(T: NDArray, value: dict, prefix: str) -> NDArray:
    out = np.array(T)
    for k in ("tx", "ty", "tz", "rx", "ry", "rz"):
        key = f"{prefix}.{k[1] if k[0] == 't' else k}"
        if key in value:
            out = out @ _elementary(k, np.array([value[key]]))[0]
    return out


def select_poses(robot: Robot, pool: ArrayLike, n: int, *, measure: str = "position",
                 parts=PARTS, rank_tol: float = 1e-7) -> NDArray:
    """The `n` configurations of a pool that make the identification best conditioned.

    Greedy D-optimal design: starting from none, add the candidate that most increases
    ``log det(J^T J)`` of the parameters identifiable from the whole pool (columns scaled to
    unit norm over the pool), by the matrix determinant lemma for every candidate at once.

    Parameters
    ----------
    pool : array_like, shape (K, n_joints)
        Candidate joint values (rad, m).
    n : int
        How many to choose, 1 .. K.
    measure : {"position", "pose"}
        What will be measured at each.

    Returns
    -------
    ndarray of int, shape (n,)
        Indices into the pool, in the order chosen.

    Raises
    ------
    InputError
        If n is not within 1 .. K, or the pool does not fit the robot.
    """
    Q = joint_array(robot, pool, "pool")
    if Q.ndim != 2:
        raise InputError(f"pool: expected shape (K, {robot.n}), found {Q.shape}")
    if measure not in ("position", "pose"):
        raise InputError(f"measure: expected position or pose, found {measure!r}")
    if not 1 <= n <= len(Q):
        raise InputError(f"n: expected 1 .. {len(Q)} (the pool's size), found {n}")
    model = parametric_model(robot, parts)
    _, J = evaluate(model, model.nominal, Q)
    J = J if measure == "pose" else J[:, :3]
    found = identifiability(J.reshape(-1, J.shape[-1]), model.names, rank_tol)
    J = J[:, :, found.identifiable]
    J = J / np.linalg.norm(J, axis=(0, 1))                # (K, rows, L), unit columns over the pool
    L = J.shape[-1]
    info = 1e-6 * np.eye(L)                                # a start that keeps it invertible
    chosen: list[int] = []
    available = np.ones(len(Q), dtype=bool)
    for _ in range(n):
        inv = np.linalg.inv(info)
        S = np.eye(J.shape[1]) + np.einsum("kal,lm,kbm->kab", J, inv, J)
        gain = np.linalg.slogdet(S)[1]
        gain[~available] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        available[best] = False
        info = info + J[best].T @ J[best]
    return np.array(chosen, dtype=int)
