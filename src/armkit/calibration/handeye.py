"""Hand-eye calibration: the camera's mount X from robot poses and camera-to-target poses.

Eye-in-hand (camera on the gripper): the target is fixed in the base frame, so for every pose i

    G_i @ X @ C_i = W,   G_i = T_base_gripper,  X = T_gripper_camera,  C_i = T_camera_target,

and W = T_base_target. Two poses give ``A X = X B`` with ``A = G_j^-1 G_i``, ``B = C_j C_i^-1``.
Eye-to-hand (camera fixed, target on the gripper): ``G_i^-1 @ X @ C_i = W`` with
X = T_base_camera and W = T_gripper_target, the same equations with G_i inverted (the
water-filling paper's ``B X A`` form).

Methods: the closed forms of Tsai and Lenz (1989), Park and Martin (1994) and Horaud and
Dornaika (1995) on every pair of poses; ``"pairs"`` refines X over the pairs (Gauss-Newton);
``"joint"`` (the default) refines X and W together on the absolute poses, which uses each
measurement once rather than in every pair it belongs to.

Only two things are refused (``success`` False, X filled with NaN), each saying which:
degenerate motion (repeated poses, no rotation change, rotations about one axis: the scaled
refinement Jacobian has a near-zero singular value), and poses that fit far better inverted
(the convention mistake: `CONVENTION_RATIO` times or more, for the robot poses, the camera
poses or both). Noisy data is answered: with its residuals per pose pair, X's covariance, and a
warning when the residuals exceed what a calibrated camera gives (`WARN_ROTATION`,
`WARN_TRANSLATION`), so that a user sees how far to trust X.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.spatial import as_array, invert, log_so3, rotation_angle, skew

Mode = Literal["eye_in_hand", "eye_to_hand"]
METHODS = ("tsai", "park", "horaud", "pairs", "joint")
MODES = ("eye_in_hand", "eye_to_hand")

# Thresholds of the refusals, with where they come from.
ORTHONORMAL_TOL = 1e-6        # |R R^T - I| of a rotation read from a file with 7+ digits
REPEATED_ROTATION = 1e-6      # rad: two robot poses this close are the same pose
REPEATED_TRANSLATION = 1e-7   # m
MIN_ROTATION_CHANGE = np.deg2rad(0.5)  # below this, every motion is a near-pure translation
# Smallest singular value of the column-normalised joint-refinement Jacobian: about 0 for
# rotations about one axis, 0.2-0.8 for poses that turn about two axes or more.
MIN_SCALED_SINGULAR_VALUE = 0.02
# The poses fit this many times better (rotation residual) with the robot poses inverted:
# the base-to-gripper / gripper-to-base mistake gives 20-100x, noise alone about 1x.
CONVENTION_RATIO = 5.0
# Residuals (rms over the pose pairs) above which the answer carries a warning: a calibrated
# camera seeing a printed target gives a few tenths of a degree and a few millimetres; fiducial
# tags seen from afar give degrees and centimetres.
WARN_ROTATION = np.deg2rad(0.5)
WARN_TRANSLATION = 0.005      # m

_E = skew(np.eye(3))          # (3, 3, 3): _E[k] = [e_k]x


@dataclass(frozen=True)
class HandEyeResult:
    """A hand-eye solution or its refusal.

    Attributes
    ----------
    success : bool
    reason : str
        "ok", or why the data cannot determine X.
    X : ndarray, shape (4, 4)
        T_gripper_camera (eye-in-hand) or T_base_camera (eye-to-hand); NaN when refused.
    W : ndarray, shape (4, 4)
        The target's pose: T_base_target (eye-in-hand) or T_gripper_target (eye-to-hand).
    method, mode : str
    rotation_residuals, translation_residuals : ndarray, shape (N,)
        Per pose pair i: angle (rad) and distance (m) between ``G_i X C_i`` and W.
    covariance : ndarray, shape (6, 6)
        Of X's small rotation (rad, about X's own axes) then translation (m), from the
        refinement's Jacobian scaled by the residuals.
    scaled_singular_value : float
        Smallest singular value of the column-normalised refinement Jacobian (near 0: X is not
        determined by the data).
    warning : str
        "" or, for residuals above `WARN_ROTATION` or `WARN_TRANSLATION`, what they are and
        how far they leave X uncertain.
    """

    success: bool
    reason: str
    X: NDArray
    W: NDArray
    method: str
    mode: str
    rotation_residuals: NDArray
    translation_residuals: NDArray
    covariance: NDArray
    scaled_singular_value: float
    warning: str = ""

    @property
    def rotation_std(self) -> NDArray:
        """Standard deviation (3,) of X's rotation about its own axes, rad."""
        return np.sqrt(np.diag(self.covariance)[:3])

    @property
    def translation_std(self) -> NDArray:
        """Standard deviation (3,) of X's translation, m."""
        return np.sqrt(np.diag(self.covariance)[3:])

    @property
    def rotation_rms(self) -> float:
        """Rms of the rotation residuals, rad."""
        return float(np.sqrt(np.mean(self.rotation_residuals ** 2)))

    @property
    def translation_rms(self) -> float:
        """Rms of the translation residuals, m."""
        return float(np.sqrt(np.mean(self.translation_residuals ** 2)))


# --- input -------------------------------------------------------------------------------------

def _poses(T: ArrayLike, name: str) -> NDArray:
    T = as_array(T, name, (4, 4))
    if T.ndim != 3:
        raise InputError(f"{name}: expected shape (N, 4, 4), found {T.shape}")
    R = T[:, :3, :3]
    off = np.abs(R @ np.swapaxes(R, -1, -2) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(R)
    bad = np.flatnonzero((off > ORTHONORMAL_TOL) | (det < 0))
    if bad.size:
        i = int(bad[0])
        what = "a reflection (det -1)" if det[i] < 0 else f"one off by {off[i]:.3g}"
        raise InputError(f"{name}[{i}]: expected a rotation part that is orthonormal with det "
                         f"+1, found {what}")
    if np.abs(T[:, 3, :] - (0.0, 0.0, 0.0, 1.0)).max() > ORTHONORMAL_TOL:
        raise InputError(f"{name}: expected last rows (0, 0, 0, 1), found another")
    return T


def _checked(G: ArrayLike, C: ArrayLike, mode: str, method: str) -> tuple[NDArray, NDArray]:
    if mode not in MODES:
        raise InputError(f"mode: expected one of {', '.join(MODES)}, found {mode!r}")
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, found {method!r}")
    G, C = _poses(G, "robot_poses"), _poses(C, "camera_poses")
    if len(G) != len(C):
        raise InputError(f"camera_poses: expected one per robot pose ({len(G)}), found {len(C)}")
    if len(G) < 3:
        raise InputError(f"robot_poses: expected at least 3 pose pairs (two motions about "
                         f"different axes), found {len(G)}")
    return (invert(G) if mode == "eye_to_hand" else G), C


# --- closed forms --------------------------------------------------------------------------------

def _motions(G: NDArray, C: NDArray) -> tuple[NDArray, NDArray]:
    """Relative motions A (k, 4, 4) and B over every pair i < j, with ``A X = X B``."""
    i, j = np.triu_indices(len(G), 1)
    return invert(G[j]) @ G[i], C[j] @ invert(C[i])


def _translation(A: NDArray, B: NDArray, R: NDArray) -> NDArray:
    """p_X from ``(R_A - I) p_X = R_X p_B - p_A`` over every motion, least squares."""
    M = (A[:, :3, :3] - np.eye(3)).reshape(-1, 3)
    rhs = (B[:, :3, 3] @ R.T - A[:, :3, 3]).reshape(-1)
    return np.linalg.lstsq(M, rhs, rcond=None)[0]


def _rotation_tsai(A: NDArray, B: NDArray) -> NDArray:
    """Tsai and Lenz (1989): modified Rodrigues vectors ``2 sin(theta/2) n``."""
    def rodrigues(R):
        v = log_so3(R)
        angle = np.linalg.norm(v, axis=-1, keepdims=True)
        return 2 * np.sin(angle / 2) * np.divide(v, angle, out=np.zeros_like(v),
                                                 where=angle > 0)
    Pa, Pb = rodrigues(A[:, :3, :3]), rodrigues(B[:, :3, :3])
    M = skew(Pa + Pb).reshape(-1, 3)
    P_ = np.linalg.lstsq(M, (Pb - Pa).reshape(-1), rcond=None)[0]
    P = 2 * P_ / np.sqrt(1 + P_ @ P_)
    n2 = P @ P
    return ((1 - n2 / 2) * np.eye(3) + 0.5 * (np.outer(P, P) + np.sqrt(4 - n2) * skew(P)))


def _project(M: NDArray) -> NDArray:
    """The rotation nearest to M (3, 3) in the Frobenius norm."""
    U, _, Vt = np.linalg.svd(M)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    return U @ D @ Vt


def _rotation_park(A: NDArray, B: NDArray) -> NDArray:
    """Park and Martin (1994): ``log R_A = R_X log R_B``, solved as an orthogonal Procrustes
    problem (the polar factor of ``sum alpha beta^T``, kept a proper rotation)."""
    alpha, beta = log_so3(A[:, :3, :3]), log_so3(B[:, :3, :3])
    return _project(alpha.T @ beta)


def _quat(R: NDArray) -> NDArray:
    """Quaternions (k, 4) ``(w, x, y, z)`` with w >= 0."""
    v = log_so3(R)
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    axis = np.divide(v, angle, out=np.zeros_like(v), where=angle > 0)
    return np.concatenate([np.cos(angle / 2), np.sin(angle / 2) * axis], axis=-1)


def _rotation_horaud(A: NDArray, B: NDArray) -> NDArray:
    """Horaud and Dornaika (1995): ``q_A q_X = q_X q_B`` is linear in q_X; the unit q_X
    minimising its squared residual is the eigenvector of the smallest eigenvalue."""
    qa, qb = _quat(A[:, :3, :3]), _quat(B[:, :3, :3])
    w, x, y, z = qa.T
    L = np.stack([np.stack([w, -x, -y, -z], -1), np.stack([x, w, -z, y], -1),
                  np.stack([y, z, w, -x], -1), np.stack([z, -y, x, w], -1)], -2)
    w, x, y, z = qb.T
    Rm = np.stack([np.stack([w, -x, -y, -z], -1), np.stack([x, w, z, -y], -1),
                   np.stack([y, -z, w, x], -1), np.stack([z, y, -x, w], -1)], -2)
    D = L - Rm
    _, vectors = np.linalg.eigh(np.einsum("kij,kil->jl", D, D))
    w, x, y, z = vectors[:, 0]
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


_CLOSED = {"tsai": _rotation_tsai, "park": _rotation_park, "horaud": _rotation_horaud}


def _closed_form(G: NDArray, C: NDArray, method: str) -> NDArray:
    A, B = _motions(G, C)
    R = _CLOSED[method](A, B)
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, _translation(A, B, R)
    return X


def _target(G: NDArray, X: NDArray, C: NDArray) -> NDArray:
    """W as the mean of ``G_i X C_i``: chordal mean of the rotations, mean of the positions."""
    T = G @ X @ C
    W = np.eye(4)
    W[:3, :3], W[:3, 3] = _project(T[:, :3, :3].sum(0)), T[:, :3, 3].mean(0)
    return W


# --- refinements ---------------------------------------------------------------------------------
# Rotation residuals are chordal, (R_1 - R_2) / sqrt(2), whose norm is the angle between them to
# first order and whose Jacobian is exact; translation residuals are in m times `weight` (1/m),
# the ratio of the rotation to the translation noise, estimated from the residuals.

def _joint_residual(G, C, X, W, weight):
    RG, RC, RX, RW = G[:, :3, :3], C[:, :3, :3], X[:3, :3], W[:3, :3]
    rot = (RG @ RX @ RC - RW) / np.sqrt(2)
    trans = RG @ (RX @ C[:, :3, 3:] + X[:3, 3:]) + G[:, :3, 3:] - W[:3, 3:]
    return np.concatenate([rot.reshape(-1, 9), weight * trans[..., 0]], axis=1)


def _joint_jacobian(G, C, X, W, weight):
    """d residual / d (rot X, p X, rot W, p W), shape (N * 12, 12); X and W move on the right."""
    N = len(G)
    RG, RC, RX, RW = G[:, :3, :3], C[:, :3, :3], X[:3, :3], W[:3, :3]
    RGX = RG @ RX
    J = np.zeros((N, 12, 12))
    # d(R_G R_X exp([d]) R_C)/dd_k = R_G R_X [e_k] R_C, (N, k, 3, 3) -> rows of 9, column k
    J[:, :9, 0:3] = np.moveaxis((RGX[:, None] @ _E[None] @ RC[:, None]).reshape(N, 3, 9),
                                1, 2) / np.sqrt(2)
    J[:, :9, 6:9] = -np.moveaxis((RW @ _E).reshape(3, 9), 0, 1) / np.sqrt(2)
    J[:, 9:, 0:3] = weight * RGX @ skew(-C[:, :3, 3])     # R_G R_X (e_k x p_C) = -R_G R_X [p_C]
    J[:, 9:, 3:6] = weight * RG
    J[:, 9:, 9:12] = -weight * np.eye(3)
    return J.reshape(N * 12, 12)


def _pairs_residual(A, B, X, weight):
    RA, RB, RX = A[:, :3, :3], B[:, :3, :3], X[:3, :3]
    rot = (RA @ RX - RX @ RB) / np.sqrt(2)
    trans = RA @ X[:3, 3] + A[:, :3, 3] - B[:, :3, 3] @ RX.T - X[:3, 3]
    return np.concatenate([rot.reshape(-1, 9), weight * trans], axis=1)


def _pairs_jacobian(A, B, X, weight):
    k = len(A)
    RA, RB, RX = A[:, :3, :3], B[:, :3, :3], X[:3, :3]
    J = np.zeros((k, 12, 6))
    D = (RA @ RX)[:, None] @ _E[None] - (RX @ _E)[None] @ RB[:, None]      # (k, 3, 3, 3)
    J[:, :9, :3] = np.moveaxis(D.reshape(k, 3, 9), 1, 2) / np.sqrt(2)
    J[:, 9:, :3] = weight * RX @ skew(B[:, :3, 3])        # -R_X (e_k x p_B) = R_X [p_B]
    J[:, 9:, 3:] = weight * (RA - np.eye(3))
    return J.reshape(k * 12, 6)


def _rodrigues(v: NDArray) -> NDArray:
    """exp([v]) for one rotation vector (3,), without scipy's per-call overhead."""
    angle = float(np.sqrt(v @ v))
    K = skew(v)
    if angle < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return (np.eye(3) + np.sin(angle) / angle * K
            + (1 - np.cos(angle)) / angle ** 2 * K @ K)


def _step(T: NDArray, d_rot: NDArray, d_p: NDArray) -> NDArray:
    out = T.copy()
    out[:3, :3] = T[:3, :3] @ _rodrigues(d_rot)
    out[:3, 3] = T[:3, 3] + d_p
    return out


def _gauss_newton(residual, jacobian, update, state, iterations=50):
    """Gauss-Newton with step halving: returns the state with the least squared residual."""
    r = residual(state)
    cost = r @ r
    for _ in range(iterations):
        J = jacobian(state)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        for _ in range(10):
            trial = update(state, step)
            r_trial = residual(trial)
            if r_trial @ r_trial <= cost:
                break
            step = step / 2
        else:
            break
        improvement = cost - r_trial @ r_trial
        state, r, cost = trial, r_trial, r_trial @ r_trial
        if improvement <= 1e-12 * cost or np.abs(step).max() < 1e-13:
            break
    return state


def _noise_weight(rot: NDArray, trans: NDArray, default: float) -> float:
    """Rotation over translation noise (1/m) from residuals (rows of 9 and 3 unweighted)."""
    sigma_r = np.sqrt(np.mean(np.sum(rot ** 2, axis=-1)) / 3)
    sigma_t = np.sqrt(np.mean(np.sum(trans ** 2, axis=-1)) / 3)
    if sigma_r < 1e-12 or sigma_t < 1e-15:     # noise-free data: any weight fits exactly
        return default
    return float(np.clip(sigma_r / sigma_t, default / 1e4, default * 1e4))


def _refine_joint(G, C, X, W, weight):
    for _ in range(3):                     # re-weighted as the residuals tell the noise ratio
        def residual(s, w=weight):
            return _joint_residual(G, C, s[0], s[1], w).ravel()

        def jacobian(s, w=weight):
            return _joint_jacobian(G, C, s[0], s[1], w)

        def update(s, d):
            return _step(s[0], d[0:3], d[3:6]), _step(s[1], d[6:9], d[9:12])

        X, W = _gauss_newton(residual, jacobian, update, (X, W))
        r = _joint_residual(G, C, X, W, 1.0)
        new = _noise_weight(r[:, :9], r[:, 9:], weight)
        if abs(np.log(new / weight)) < 0.05:
            break
        weight = new
    return X, W, weight


def _refine_pairs(A, B, X, weight):
    for _ in range(3):
        def residual(s, w=weight):
            return _pairs_residual(A, B, s, w).ravel()

        def jacobian(s, w=weight):
            return _pairs_jacobian(A, B, s, w)

        X = _gauss_newton(residual, jacobian, lambda s, d: _step(s, d[:3], d[3:]), X)
        r = _pairs_residual(A, B, X, 1.0)
        new = _noise_weight(r[:, :9], r[:, 9:], weight)
        if abs(np.log(new / weight)) < 0.05:
            break
        weight = new
    return X, weight


# --- checks ------------------------------------------------------------------------------------

def _repeated(G: NDArray) -> str | None:
    i, j = np.triu_indices(len(G), 1)
    D = invert(G[j]) @ G[i]
    same = (rotation_angle(D[:, :3, :3]) < REPEATED_ROTATION) & (
        np.linalg.norm(D[:, :3, 3], axis=-1) < REPEATED_TRANSLATION)
    if same.any():
        k = int(np.flatnonzero(same)[0])
        return (f"repeated poses: robot poses {i[k]} and {j[k]} are the same pose, which adds "
                f"no motion; measure distinct poses")
    return None


def _rotation_change(G: NDArray) -> str | None:
    R = G[:, :3, :3]
    i, j = np.triu_indices(len(G), 1)
    largest = rotation_angle(np.swapaxes(R[j], -1, -2) @ R[i]).max()
    if largest < MIN_ROTATION_CHANGE:
        return (f"no rotation change: the robot poses differ by at most "
                f"{np.rad2deg(largest):.2g} deg in rotation, so X's position is not determined; "
                f"turn the gripper about two different axes")
    return None


def _convention(G: NDArray, C: NDArray) -> str | None:
    """Does the rotation data fit far better with the robot or camera poses inverted?"""
    # The rotation residual of a motion pair: angle between R_A R_X and R_X R_B.
    def fit(G, C):
        A, B = _motions(G, C)
        R = _rotation_park(A, B)
        E = A[:, :3, :3] @ R @ np.swapaxes(R @ B[:, :3, :3], -1, -2)
        return float(np.sqrt(np.mean(rotation_angle(E) ** 2)))

    given = fit(G, C)
    alternatives = {"the robot poses inverted (base-to-gripper given as gripper-to-base?)":
                    fit(invert(G), C),
                    "the camera poses inverted (camera-in-target given as target-in-camera?)":
                    fit(G, invert(C)),
                    "both robot and camera poses inverted": fit(invert(G), invert(C))}
    best = min(alternatives.values())
    # Inverting the robot poses and inverting the camera poses can fit equally well (the
    # motions are then conjugate through W instead of X): name every one that fits as well.
    what = " or ".join(w for w, fit_ in sorted(alternatives.items(), key=lambda item: item[1])
                       if fit_ <= 2 * best + 1e-12)
    if given > 1e-9 and given > CONVENTION_RATIO * best:
        return (f"the poses as given fit {given / max(best, 1e-300):.3g}x worse than with "
                f"{what} (rotation residuals of {np.rad2deg(given):.3g} deg rms against "
                f"{np.rad2deg(best):.3g}); check the pose convention")
    return None


def _scaled_singular(J: NDArray) -> float:
    """Smallest singular value of J with unit columns (0 if a column is zero)."""
    norms = np.linalg.norm(J, axis=0)
    if not norms.all():
        return 0.0
    # Through the 12 x 12 Gram matrix: an SVD of the tall J costs more in threads than maths.
    gram = np.einsum("ij,ik->jk", J, J) / np.outer(norms, norms)
    return float(np.sqrt(max(np.linalg.eigvalsh(gram)[0], 0.0)))


# --- the solver ----------------------------------------------------------------------------------

def handeye(robot_poses: ArrayLike, camera_poses: ArrayLike, mode: Mode = "eye_in_hand",
            method: str = "joint") -> HandEyeResult:
    """Solve ``G_i X C_i = W`` (eye-in-hand) or ``G_i^-1 X C_i = W`` (eye-to-hand) for X.

    Parameters
    ----------
    robot_poses : array_like, shape (N, 4, 4)
        ``T_base_gripper`` at each measurement (OpenCV's gripper2base), m.
    camera_poses : array_like, shape (N, 4, 4)
        ``T_camera_target`` at each measurement (OpenCV's target2cam), m.
    mode : {"eye_in_hand", "eye_to_hand"}
    method : {"joint", "pairs", "tsai", "park", "horaud"}
        ``joint`` refines X and the target pose W on the absolute poses; ``pairs`` refines X on
        the relative motions; the others are the closed forms alone.

    Returns
    -------
    HandEyeResult
        ``success`` False with a ``reason`` for degenerate data (X then NaN).

    Raises
    ------
    InputError
        Fewer than 3 pose pairs, mismatched counts, NaN or inf, a rotation part that is not
        orthonormal with det +1, an unknown mode or method.

    Example
    -------
    A camera on the gripper (X = T_gripper_camera) sees a fixed target (W = T_base_target) from
    eight poses, so that G_i X C_i = W:

    >>> from armkit.spatial import invert, pose_from_xyz_rpy
    >>> rng = np.random.default_rng(0)
    >>> X = pose_from_xyz_rpy([0.05, 0.0, 0.1], [0.1, 0.2, 0.3])
    >>> W = pose_from_xyz_rpy([1.0, 0.2, 0.0], [0.0, 0.0, 1.0])
    >>> G = pose_from_xyz_rpy(rng.uniform(-0.5, 0.5, (8, 3)), rng.uniform(-1, 1, (8, 3)))
    >>> C = invert(X) @ invert(G) @ W
    >>> result = handeye(G, C)
    >>> result.success, bool(np.allclose(result.X, X, atol=1e-9))
    (True, True)
    """
    G, C = _checked(robot_poses, camera_poses, mode, method)
    N = len(G)
    nan = np.full((4, 4), np.nan)

    def refused(reason: str, residuals=None, s=np.nan):
        rot, trans = residuals if residuals is not None else (np.full(N, np.nan),) * 2
        return HandEyeResult(False, reason, nan.copy(), nan.copy(), method, mode, rot, trans,
                             np.full((6, 6), np.nan), float(s))

    reason = _repeated(G) or _rotation_change(G) or _convention(G, C)
    if reason:
        return refused(reason)
    A, B = _motions(G, C)
    length = max(float(np.sqrt(np.mean(np.sum(C[:, :3, 3] ** 2, axis=-1)))), 1e-3)
    weight = 1.0 / length          # a rotation error at the camera moves the target by ~ length
    if method in _CLOSED:
        X = _closed_form(G, C, method)
        W = _target(G, X, C)
    else:
        starts = [_closed_form(G, C, m) for m in _CLOSED]
        costs = [np.sum(_pairs_residual(A, B, X0, weight) ** 2) for X0 in starts]
        X = starts[int(np.argmin(costs))]
        if method == "pairs":
            X, weight = _refine_pairs(A, B, X, weight)
            W = _target(G, X, C)
        else:
            X, W, weight = _refine_joint(G, C, X, _target(G, X, C), weight)
    # Uncertainty and observability from the joint problem's Jacobian at the answer.
    J = _joint_jacobian(G, C, X, W, weight)
    r = _joint_residual(G, C, X, W, weight)
    E = invert(W) @ G @ X @ C
    residuals = (rotation_angle(E[:, :3, :3]), np.linalg.norm(E[:, :3, 3], axis=-1))
    smallest = _scaled_singular(J)
    if not smallest >= MIN_SCALED_SINGULAR_VALUE:
        return refused(
            f"rotations about one axis (or nearly): the refinement's scaled Jacobian has a "
            f"singular value of {smallest:.2g} (healthy data: 0.2 or more), so X is not "
            f"determined along it; turn the gripper about two non-parallel axes",
            residuals=residuals, s=smallest)
    dof = max(r.size - 12, 1)
    sigma2 = float(r.ravel() @ r.ravel()) / dof
    # Residuals in rad (translations times weight, 1/m), parameters in rad and m: the
    # covariance comes out in rad^2 and m^2.
    cov = sigma2 * np.linalg.pinv(J.T @ J)[:6, :6]
    rot_rms = float(np.sqrt(np.mean(residuals[0] ** 2)))
    trans_rms = float(np.sqrt(np.mean(residuals[1] ** 2)))
    warning = ""
    if rot_rms > WARN_ROTATION or trans_rms > WARN_TRANSLATION:
        std = np.sqrt(np.diag(cov))
        warning = (f"noisy data: residuals of {np.rad2deg(rot_rms):.3g} deg and "
                   f"{trans_rms * 1e3:.3g} mm rms per pose pair (a calibrated camera gives under "
                   f"{np.rad2deg(WARN_ROTATION):.2g} deg and {WARN_TRANSLATION * 1e3:.2g} mm); X "
                   f"is uncertain by {np.rad2deg(np.linalg.norm(std[:3])):.3g} deg and "
                   f"{np.linalg.norm(std[3:]) * 1e3:.3g} mm (one standard deviation)")
    return HandEyeResult(True, "ok", X, W, method, mode, residuals[0], residuals[1], cov,
                         smallest, warning)

