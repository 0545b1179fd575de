"""The tool orientations a reachability map tries at every voxel, and the IK task they ask for.

An orientation set is K rotations and a task mask (`armkit.kinematics.ik.masks`):

- `Orientations.sphere`: approach directions (the tool's z axis) evenly spread on the sphere,
  times rolls about each: full poses, for arms of six joints or more;
- `Orientations.axis`: directions of one tool axis on the sphere, roll about it free (the
  pointing task of a five-joint arm, or of a welding torch);
- `Orientations.about`: turns about one tool axis from its home orientation (position + yaw
  for a lift-and-swing arm such as the water-supply robot);
- `Orientations.pitch`: one tool axis turned in the vertical plane through the base axis and
  the voxel (a base yaw and pitch joints, the modular 4-DOF arm, can point nowhere else);
- `Orientations.given`: a task's own rotations.

Rotations are in the base frame, except for ``frame="radial"`` (`pitch`), where they are in the
voxel's radial frame: x from the first joint's axis towards the voxel, z along that axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.ik.analytic import family_of
from armkit.kinematics.ik.masks import MASK_FORMS, as_mask, mask_name
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot

GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))     # rad: Fibonacci points on the sphere
MOST = 100_000                                      # orientations per voxel, at most
AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True, eq=False)
class Orientations:
    """K tool orientations and the task that judges them.

    Attributes
    ----------
    rotations : ndarray, shape (K, 3, 3)
        Target rotations: in the base frame, or in the voxel's radial frame (`frame`).
    mask : ndarray of bool, shape (6,)
        The IK task (x, y, z, rx, ry, rz), rotations about the tool's own axes.
    frame : {"base", "radial"}
        Where the rotations are given.
    kind : str
        How they were made: "sphere", "axis", "about", "pitch" or "given".
    description : str
        In words, e.g. "25 approach directions x 8 rolls".
    """

    rotations: NDArray
    mask: NDArray
    frame: str
    kind: str
    description: str

    def __len__(self) -> int:
        return len(self.rotations)

    @property
    def task(self) -> str:
        """The mask's name (`armkit.kinematics.ik.masks.mask_name`)."""
        return mask_name(self.mask)

    def in_base(self, centers: NDArray, robot: Robot) -> NDArray:
        """The rotations at voxel centers (V, 3) in the base frame, (V, K, 3, 3)."""
        R = np.broadcast_to(self.rotations, (len(centers),) + self.rotations.shape)
        if self.frame == "base":
            return R
        return np.einsum("vij,kjl->vkil", radial_frames(robot, centers), self.rotations)

    def nearest(self, R: NDArray, centers: NDArray, robot: Robot) -> NDArray:
        """Index (...,) of the orientation nearest each rotation R (..., 3, 3), at positions
        centers (..., 3), under the mask: the whole rotation (largest trace of
        ``R_k^T R``), the free axis's direction, or the turn about the one constrained axis."""
        lead = R.shape[:-2]
        R = R.reshape(-1, 3, 3)
        if self.frame == "radial":
            F = radial_frames(robot, centers.reshape(-1, 3))
            R = np.einsum("nji,njk->nik", F, R)
        flags = self.mask[3:]
        count = int(flags.sum())
        if count == 3:
            score = np.einsum("kij,nij->nk", self.rotations, R)
        elif count == 2:
            f = int(np.flatnonzero(~flags)[0])
            score = R[:, :, f] @ self.rotations[:, :, f].T
        elif count == 1:
            k = int(np.flatnonzero(flags)[0])
            o = (k + 1) % 3
            # The other axis projected on the plane normal to the tool's axis k: its angle to
            # each orientation's, about k.
            axis = R[:, :, k]
            a = R[:, :, o] - np.sum(R[:, :, o] * axis, -1, keepdims=True) * axis
            b = self.rotations[:, :, o]
            score = a @ b.T
        else:
            score = np.zeros((len(R), len(self)))
        return np.argmax(score, axis=-1).reshape(lead)

    # --- sets ----------------------------------------------------------------------------------

    @classmethod
    def sphere(cls, count: int = 200, rolls: int | None = None) -> Orientations:
        """Approach directions (tool z) evenly spread on the sphere, times rolls about them.

        Parameters
        ----------
        count : int
            About this many orientations in all (the product of directions and rolls).
        rolls : int, optional
            Rolls per direction, evenly over one turn. Default: near ``(pi count)^(1/3)``,
            which spaces rolls as far apart as neighbouring directions, and dividing the count
            where one of the nearest does (8 rolls of 45 deg and 25 directions about 41 deg
            apart for 200).
        """
        count = _count("orientations", count)
        if rolls is None:
            # As many rolls as keep them as far apart as neighbouring directions; among the
            # five nearest that number, one that divides the count, so that it is met.
            ideal = (math.pi * count) ** (1 / 3)
            near = sorted(range(max(1, round(ideal) - 2), round(ideal) + 3),
                          key=lambda r: (count % r != 0, abs(r - ideal)))
            rolls = min(near[0], count)
        rolls = _count("rolls", rolls, count)
        directions = max(1, round(count / rolls))
        R = rolled(fibonacci_sphere(directions), rolls, axis=2)
        return cls(frozen_array(R), frozen_array(MASK_FORMS[(1,) * 6].flags, bool), "base",
                   "sphere", f"{directions} approach directions x {rolls} rolls")

    @classmethod
    def axis(cls, count: int = 200, axis: str = "z") -> Orientations:
        """Directions of one tool axis evenly spread on the sphere; the roll about it free.

        Parameters
        ----------
        count : int
            Directions.
        axis : {"x", "y", "z"}
            The tool axis that points.
        """
        count = _count("orientations", count)
        k = _axis(axis)
        R = rolled(fibonacci_sphere(count), 1, axis=k)
        mask = np.ones(6, dtype=bool)
        mask[3 + k] = False
        return cls(frozen_array(R), frozen_array(mask, bool), "base", "axis",
                   f"{count} directions of the tool {axis} axis, roll free")

    @classmethod
    def about(cls, robot: Robot, count: int = 36, axis: str = "z") -> Orientations:
        """Turns about one tool axis from the tool's home orientation, evenly over one turn;
        the other two rotations are the home pose's (the task "position + yaw" for
        ``axis="z"``).

        Parameters
        ----------
        robot : Robot
            Its tool orientation at q = 0 is turned.
        count : int
            Turns.
        axis : {"x", "y", "z"}
            The tool axis turned about; it keeps its home direction.
        """
        count = _count("orientations", count)
        k = _axis(axis)
        R0 = robot.chain.T_home[:3, :3]
        w = R0[:, k]
        angle = 2.0 * math.pi * np.arange(count) / count
        R = axis_rotations(w, angle) @ R0
        mask = np.zeros(6, dtype=bool)
        mask[:3] = True
        mask[3 + k] = True
        return cls(frozen_array(R), frozen_array(mask, bool), "base", "about",
                   f"{count} turns about the tool {axis} axis")

    @classmethod
    def pitch(cls, count: int = 36, axis: str = "x") -> Orientations:
        """One tool axis turned in the vertical plane through the first joint's axis and the
        voxel, evenly over one turn (outwards at 0, up at 90 deg); the roll about it free.

        Parameters
        ----------
        count : int
            Directions in the plane.
        axis : {"x", "y", "z"}
            The tool axis that points.
        """
        count = _count("orientations", count)
        k = _axis(axis)
        angle = 2.0 * math.pi * np.arange(count) / count
        directions = np.column_stack([np.cos(angle), np.zeros(count), np.sin(angle)])
        R = rolled(directions, 1, axis=k)
        mask = np.ones(6, dtype=bool)
        mask[3 + k] = False
        return cls(frozen_array(R), frozen_array(mask, bool), "radial", "pitch",
                   f"{count} pitches of the tool {axis} axis in the vertical plane through "
                   f"the voxel, roll free")

    @classmethod
    def given(cls, rotations: ArrayLike, mask: str | ArrayLike = "pose") -> Orientations:
        """A task's own rotations (K, 3, 3) in the base frame, under a mask (default: pose)."""
        R = np.asarray(rotations, dtype=float)
        if R.ndim == 2:
            R = R[None]
        if R.ndim != 3 or R.shape[1:] != (3, 3) or not 1 <= len(R) <= MOST:
            raise InputError(f"rotations: expected shape (K, 3, 3) with 1 <= K <= {MOST}, "
                             f"found {R.shape}")
        if not np.isfinite(R).all():
            raise InputError("rotations: expected finite numbers, found NaN or inf")
        off = np.abs(np.einsum("kji,kjl->kil", R, R) - np.eye(3)).max()
        if off > 1e-6 or (np.linalg.det(R) <= 0).any():
            raise InputError(f"rotations: expected rotation matrices, found one {off:.3g} off "
                             f"orthonormal or a reflection")
        return cls(frozen_array(R), frozen_array(as_mask(mask), bool), "base", "given",
                   f"{len(R)} given orientations, task {mask_name(as_mask(mask))}")


def default_orientations(robot: Robot, count: int = 200) -> Orientations:
    """The orientation set that fits the robot's IK task (`IKSolver.default_mask`).

    Full poses (six joints or more): `Orientations.sphere`. A closed form's own task: turns
    about the tool axis it keeps (lift-and-swing), or pitches of the axis it points
    (yaw-and-pitch). Any other arm of fewer than six joints: positions only (one orientation,
    task "position").
    """
    family = family_of(robot.chain)
    if family is not None and family.mask[3:].count(1) == 1:
        return Orientations.about(robot, count, "xyz"[family.mask[3:].index(1)])
    if family is not None and family.mask[3:].count(1) == 2:
        return Orientations.pitch(count, "xyz"[family.mask[3:].index(0)])
    if robot.n >= 6:
        return Orientations.sphere(count)
    return Orientations(frozen_array(np.eye(3)[None]), frozen_array(as_mask("position"), bool),
                        "base", "given", "position only")


# --- geometry ---------------------------------------------------------------------------------

def fibonacci_sphere(count: int) -> NDArray:
    """`count` unit vectors (count, 3) spread evenly on the sphere (a Fibonacci lattice: equal
    areas in z, successive points a golden angle apart in azimuth)."""
    i = np.arange(count)
    z = 1.0 - (2.0 * i + 1.0) / count
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = GOLDEN_ANGLE * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def rolled(directions: NDArray, rolls: int, axis: int) -> NDArray:
    """Rotations (D rolls, 3, 3) whose column `axis` is each direction (D, 3), turned about it
    by `rolls` angles evenly over one turn; the next column starts along the direction's part
    normal to the base axis that is least parallel to it."""
    d = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    reference = np.eye(3)[np.argmin(np.abs(d), axis=1)]
    u = np.cross(d, reference)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(d, u)
    angle = 2.0 * math.pi * np.arange(rolls) / rolls
    c, s = np.cos(angle)[None, :, None], np.sin(angle)[None, :, None]
    a = c * u[:, None] + s * v[:, None]             # (D, rolls, 3): the next axis
    b = np.cross(d[:, None], a)                     # and the one after it
    R = np.empty((len(d), rolls, 3, 3))
    R[..., axis] = d[:, None]
    R[..., (axis + 1) % 3] = a
    R[..., (axis + 2) % 3] = b
    return R.reshape(-1, 3, 3)


def axis_rotations(w: NDArray, angle: NDArray) -> NDArray:
    """Rotations (k, 3, 3) by angles (k,) about the unit axis w (3,) (Rodrigues)."""
    W = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * W + (1.0 - c) * (W @ W)


def radial_frames(robot: Robot, centers: NDArray) -> NDArray:
    """Frames (V, 3, 3) at points (V, 3): x from the first joint's axis towards the point
    (normal to the axis), z along the axis, y = z x x. A point on the axis takes the x of the
    axis's own normal (the first of the base's x and y axes that is not along it)."""
    chain = robot.chain
    w = chain.screws[0, 3:] if chain.revolute[0] else chain.screws[0, :3]
    w = w / np.linalg.norm(w)
    d = centers - chain.points[0]
    x = d - np.outer(d @ w, w)
    norm = np.linalg.norm(x, axis=1, keepdims=True)
    fallback = np.eye(3)[0] if abs(w[0]) < 0.9 else np.eye(3)[1]
    fallback = fallback - (fallback @ w) * w
    fallback /= np.linalg.norm(fallback)
    x = np.where(norm > 1e-12, x / np.maximum(norm, 1e-300), fallback)
    F = np.empty((len(centers), 3, 3))
    F[..., 0] = x
    F[..., 2] = w
    F[..., 1] = np.cross(w, x)
    return F


def _count(name: str, value, high: int = MOST) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
            or not 1 <= value <= high:
        raise InputError(f"{name}: expected a whole number 1 .. {high}, found {value!r}")
    return int(value)


def _axis(axis: str) -> int:
    if axis not in AXES:
        raise InputError(f"axis: expected one of x, y, z, found {axis!r}")
    return AXES[axis]
