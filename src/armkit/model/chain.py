"""The canonical serial chain that every robot description compiles into.

A chain of n joints maps joint positions q (rad for revolute, m for prismatic joints) to the
tool pose

    T_base_tool(q) = T_base @ prod_i [ T_before_i @ M_i(q_i + offset_i) @ T_after_i ] @ T_tool

where ``M_i`` rotates about (revolute) or translates along (prismatic) the unit ``axis_i``,
expressed in the joint frame ``T_before_i`` places. Link frame i is the frame after
``T_after_i``: standard DH puts its fixed part there (``Rz Tz | Tx Rx``), modified DH and URDF
put theirs before the motion, so each front-end keeps its own link frames.

At construction the chain is also compiled into the form the kernels use: every axis turned
onto z, and the fixed transforms between two motions multiplied out (``pre``, ``links``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError

JointKind = Literal["revolute", "prismatic"]
KINDS: tuple[str, ...] = ("revolute", "prismatic")


def frozen_array(a: ArrayLike, dtype=float) -> NDArray:
    """A read-only copy of `a` as an array of `dtype`: the arrays of armkit's immutable values."""
    a = np.array(a, dtype=dtype)
    a.setflags(write=False)
    return a


def freeze(record, *names: str) -> None:
    """Make the named array fields of a frozen dataclass read-only float copies (None stays)."""
    for name in names:
        value = getattr(record, name)
        if value is not None:
            object.__setattr__(record, name, frozen_array(value))


JERK_PER_ACCELERATION = 10.0
"""1/s: a joint without a jerk limit of its own gets this many times its acceleration limit,
so that it reaches full acceleration from rest in 0.1 s."""


@dataclass(frozen=True)
class Limits:
    """Limits of one joint, SI: position (rad or m), velocity (/s), acceleration (/s^2),
    jerk (/s^3), torque (N m, or N for a prismatic joint).

    Velocity, acceleration and torque are ``inf`` where none is given; jerk, where none is
    given, is `JERK_PER_ACCELERATION` times the acceleration limit.
    """

    lower: float
    upper: float
    velocity: float = np.inf
    acceleration: float = np.inf
    jerk: float | None = None
    torque: float = np.inf

    def __post_init__(self):
        if not self.lower < self.upper:
            raise InputError(f"limits: expected lower < upper, found {self.lower} and {self.upper}")
        if self.jerk is None:
            object.__setattr__(self, "jerk", JERK_PER_ACCELERATION * self.acceleration)
        if not (self.velocity > 0 and self.acceleration > 0 and self.jerk > 0):
            raise InputError(f"limits: expected positive velocity, acceleration and jerk "
                             f"limits, found {self.velocity}, {self.acceleration} and "
                             f"{self.jerk}")
        if not self.torque > 0:
            raise InputError(f"limits: expected a positive torque limit, found {self.torque}")


@dataclass(frozen=True, eq=False)
class Joint:
    """One moving joint: ``T_before @ M(q + offset) @ T_after``.

    Parameters
    ----------
    name : str
    kind : {"revolute", "prismatic"}
    axis : array_like, shape (3,)
        Direction of the motion in the joint frame (normalised here).
    limits : Limits
        On the joint value q (before the offset is added).
    T_before, T_after : array_like, shape (4, 4)
        Fixed transforms before and after the motion; identity if omitted.
    offset : float
        Added to q before the motion (rad or m): the joint's value at q = 0.
    leader : str, optional
        The joint this one mimics (URDF ``<mimic>``): it has no value of its own, its q is
        ``multiplier * q_leader + mimic_offset``; None for an independent joint.
    multiplier, mimic_offset : float
        The coupling to the leader (mimic_offset in rad or m).
    """

    name: str
    kind: JointKind
    axis: NDArray
    limits: Limits
    T_before: NDArray = field(default_factory=lambda: np.eye(4))
    T_after: NDArray = field(default_factory=lambda: np.eye(4))
    offset: float = 0.0
    leader: str | None = None
    multiplier: float = 1.0
    mimic_offset: float = 0.0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise InputError(f"joint {self.name}: expected kind revolute or prismatic, "
                             f"found {self.kind!r}")
        axis = np.asarray(self.axis, dtype=float)
        norm = np.linalg.norm(axis) if axis.shape == (3,) else 0.0
        if not norm > 1e-9:
            raise InputError(f"joint {self.name}: expected a non-zero 3-vector axis, found {axis}")
        object.__setattr__(self, "axis", frozen_array(axis / norm))
        object.__setattr__(self, "T_before", frozen_array(self.T_before))
        object.__setattr__(self, "T_after", frozen_array(self.T_after))
        object.__setattr__(self, "offset", float(self.offset))
        object.__setattr__(self, "multiplier", float(self.multiplier))
        object.__setattr__(self, "mimic_offset", float(self.mimic_offset))


def _rotation_onto_z(axis: NDArray) -> NDArray:
    """A 4x4 rotation R with ``R @ e_z = axis`` (for a unit axis); identity for e_z itself.

    Built from the axis and the basis vector least aligned with it (cross products), which
    stays orthonormal to rounding for every axis, -z and its neighbours included.
    """
    R = np.eye(4)
    if np.array_equal(axis, [0.0, 0.0, 1.0]):
        return R
    x = np.cross(np.eye(3)[np.argmin(np.abs(axis))], axis)
    x /= np.linalg.norm(x)
    R[:3, :3] = np.column_stack([x, np.cross(axis, x), axis])
    return R


def _motion_along_z(kind: str, value: float) -> NDArray:
    M = np.eye(4)
    if kind == "revolute":
        c, s = np.cos(value), np.sin(value)
        M[:2, :2] = [[c, -s], [s, c]]
    else:
        M[2, 3] = value
    return M


@dataclass(frozen=True, eq=False)
class Chain:
    """A serial chain of moving joints between a base and a tool transform.

    The chain's joint values q are those of its independent joints; a joint that mimics
    another (`Joint.leader`) moves with it and has no value of its own. A leader off the chain
    (a gripper's driven finger, when the chain ends at the other finger) moves nothing but its
    mimic joints, and has a value in q all the same: the one a drive commands.

    Parameters
    ----------
    joints : sequence of Joint
        Every moving joint, base to tool.
    T_base : array_like, shape (4, 4)
        The first joint's parent frame in the world (robot base) frame.
    T_tool : array_like, shape (4, 4)
        The tool frame in the last link's frame.
    leaders : sequence of Joint
        Independent joints off the chain that joints of the chain mimic (only their name,
        kind and limits matter).

    Attributes
    ----------
    variables : tuple of Joint
        The joints whose values q (n,) holds: the chain's independent joints, and each leader
        off the chain where its first mimic joint is.
    lower, upper : ndarray, shape (n,)
        Position limits (rad or m); a leader's are narrowed to keep its followers in theirs.
    velocity_limits, acceleration_limits, jerk_limits : ndarray, shape (n,)
        Per joint (/s, /s^2, /s^3); inf where none is given (jerk: see `Limits`); narrowed
        for leaders as the positions.
    torque_limits : ndarray, shape (n,)
        Per joint value (N m, N); inf where none is given; a leader's own.
    revolute : ndarray of bool, shape (n,)
    coupling : ndarray, shape (n_joints, n)
        d(q of each moving joint)/dq: the identity without mimic joints.
    screws : ndarray, shape (n_joints, 6)
        Each moving joint's space-frame screw ``(v, w)`` at q = 0 (product-of-exponentials
        form: ``T(q) = exp([S_1] q_1) ... exp([S_n] q_n) @ T_home``); a prismatic screw is
        ``(w, 0)``.
    points : ndarray, shape (n_joints, 3)
        A point on each moving joint's axis at q = 0 (base frame).
    T_home : ndarray, shape (4, 4)
        The tool pose at q = 0.
    kernel : KernelChain
        The compiled form the kinematics kernels take.
    """

    joints: tuple[Joint, ...]
    T_base: NDArray = field(default_factory=lambda: np.eye(4))
    T_tool: NDArray = field(default_factory=lambda: np.eye(4))
    leaders: tuple[Joint, ...] = ()
    variables: tuple[Joint, ...] = field(init=False, repr=False)
    lower: NDArray = field(init=False, repr=False)
    upper: NDArray = field(init=False, repr=False)
    velocity_limits: NDArray = field(init=False, repr=False)
    acceleration_limits: NDArray = field(init=False, repr=False)
    jerk_limits: NDArray = field(init=False, repr=False)
    torque_limits: NDArray = field(init=False, repr=False)
    revolute: NDArray = field(init=False, repr=False)
    coupling: NDArray = field(init=False, repr=False)
    screws: NDArray = field(init=False, repr=False)
    points: NDArray = field(init=False, repr=False)
    T_home: NDArray = field(init=False, repr=False)
    kernel: KernelChain = field(init=False, repr=False)

    def __post_init__(self):
        joints = tuple(self.joints)
        if not joints:
            raise InputError("chain: expected at least one moving joint, found none")
        def set_(name, value):
            object.__setattr__(self, name, value)

        set_("joints", joints)
        set_("T_base", frozen_array(self.T_base))
        set_("T_tool", frozen_array(self.T_tool))
        set_("leaders", tuple(self.leaders))
        variables = _variables(joints, self.leaders)
        set_("variables", variables)
        source, scale, shift = _couplings(joints, variables)
        limits = []
        for v in variables:
            followers = [j for j in joints if j.leader == v.name]
            narrowed = leader_limits(v.limits, [(j.multiplier, j.mimic_offset, j.limits)
                                                for j in followers])
            if narrowed is None:
                raise InputError(f"joint {v.name}: expected a range of motion that keeps its "
                                 f"mimic joints ({', '.join(j.name for j in followers)}) within "
                                 f"their limits, found none")
            limits.append(narrowed)
        set_("lower", frozen_array([x.lower for x in limits]))
        set_("upper", frozen_array([x.upper for x in limits]))
        set_("velocity_limits", frozen_array([x.velocity for x in limits]))
        set_("acceleration_limits", frozen_array([x.acceleration for x in limits]))
        set_("jerk_limits", frozen_array([x.jerk for x in limits]))
        set_("torque_limits", frozen_array([x.torque for x in limits]))
        revolute = np.array([j.kind == "revolute" for j in variables])
        revolute.setflags(write=False)
        set_("revolute", revolute)
        coupling = np.zeros((len(joints), len(variables)))
        coupling[np.arange(len(joints)), source] = scale
        set_("coupling", frozen_array(coupling))
        # Kernel form: joint i rotates about / slides along z of frame pre @ ... @ links[i-1].
        align = [_rotation_onto_z(j.axis) for j in joints]
        after = [R.T @ j.T_after for R, j in zip(align, joints)]
        links = [after[i] @ joints[i + 1].T_before @ align[i + 1]
                 for i in range(len(joints) - 1)] + [after[-1] @ self.T_tool]
        kinds = frozen_array([0 if j.kind == "revolute" else 1 for j in joints], np.int64)
        set_("kernel", KernelChain(
            kinds=kinds, offsets=frozen_array(np.array([j.offset for j in joints]) + shift),
            pre=frozen_array(self.T_base @ joints[0].T_before @ align[0]),
            links=frozen_array(links), after=frozen_array(np.reshape(after[:-1], (-1, 4, 4))),
            source=frozen_array(source, np.int64), scale=frozen_array(scale)))
        # Screws at home: walk the kernel form at q = 0 (each joint at its offset).
        T, screws, points = self.kernel.pre, [], []
        for j, offset, link in zip(joints, self.kernel.offsets, self.kernel.links):
            T = T @ _motion_along_z(j.kind, offset)
            w, r = T[:3, 2], T[:3, 3]
            screws.append(np.r_[-np.cross(w, r), w] if j.kind == "revolute" else np.r_[w, 0, 0, 0])
            points.append(r)
            T = T @ link
        set_("screws", frozen_array(screws))
        set_("points", frozen_array(points))
        set_("T_home", frozen_array(T))

    @property
    def n(self) -> int:
        """Number of joint values: the independent moving joints."""
        return len(self.variables)

    @property
    def n_joints(self) -> int:
        """Number of moving joints, mimic joints included: the link frames are n_joints + 1."""
        return len(self.joints)

    @property
    def coupled(self) -> bool:
        """Whether some joint mimics another."""
        return any(j.leader is not None for j in self.joints)

    @property
    def names(self) -> tuple[str, ...]:
        """The names of the joint values, in chain order."""
        return tuple(j.name for j in self.variables)

    @cached_property
    def wraps(self) -> NDArray:
        """(n,) bool: the revolute joint values whose range spans a full turn, where q and
        q + 2 pi are the same pose (their mimic joints, if any, move by whole turns too)."""
        whole = np.ones(self.n, dtype=bool)
        for j, source, scale in zip(self.joints, self.kernel.source, self.kernel.scale):
            whole[source] &= j.leader is None or (j.kind == "revolute" and scale == round(scale))
        return frozen_array(self.revolute & whole & (self.upper - self.lower >= 2 * np.pi - 1e-12),
                            bool)

    @cached_property
    def sampling_limits(self) -> tuple[NDArray, NDArray]:
        """Ranges to draw joint values from, (n,) each: the limits, where they are finite.

        A revolute joint without finite limits (a URDF continuous joint) spans one turn from
        its lower limit (or -pi): every pose it can take. A prismatic joint without them
        spans -1 .. 1 m.
        """
        endless = ~(np.isfinite(self.lower) & np.isfinite(self.upper))
        lower = np.where(np.isfinite(self.lower), self.lower,
                         np.where(self.revolute, -np.pi, -1.0))
        upper = np.where(endless, lower + np.where(self.revolute, 2 * np.pi, 2.0), self.upper)
        return frozen_array(lower), frozen_array(upper)

    @cached_property
    def reach(self) -> float:
        """An upper bound (m) on the distance from joint 1's axis point (``points[0]``) to the
        tool point, over every joint value within the limits.

        Consecutive axis points are fixed in the link between them, so the tool can be no
        farther than the sum of those distances, plus the longest stroke of each prismatic
        joint (mimic ones too, from its value at q = 0). A target farther than this is out of
        reach, whatever the solver. Computed on first use and kept, as the chain is immutable.
        """
        k = self.kernel
        points = np.vstack([self.points, self.T_home[:3, 3]])
        strokes = np.abs(k.motion_ends(self.lower, self.upper) - k.offsets).max(axis=0)
        return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))
                     + strokes[k.kinds == 1].sum())

    @cached_property
    def kernel_limits(self) -> NDArray:
        """(5, n): the joint limits as the numeric IK kernels take them, read-only. Rows: lower
        (-pi for a wrapping joint without a finite lower limit), upper, `wraps` (1.0 or 0.0),
        then `sampling_limits` (lower, upper). Computed on first use and kept."""
        lower = np.where(self.wraps & ~np.isfinite(self.lower), -np.pi, self.lower)
        return frozen_array([lower, self.upper, self.wraps, *self.sampling_limits])


def _variables(joints: tuple[Joint, ...], leaders: tuple[Joint, ...]) -> tuple[Joint, ...]:
    """The joints q holds values of: independent ones in chain order, a leader off the chain
    where its first mimic joint is."""
    off_chain = {j.name: j for j in leaders}
    variables, placed = [], set()
    for j in joints:
        joint = j if j.leader is None else off_chain.get(j.leader)
        if joint is not None and joint.name not in placed:
            variables.append(joint)
            placed.add(joint.name)
    unused = [name for name in off_chain if name not in placed]
    if unused or any(j.leader is not None for j in leaders):
        raise InputError(f"chain leaders: expected independent joints that joints of the chain "
                         f"mimic, found {', '.join(j.name for j in leaders)}")
    return tuple(variables)


def _couplings(joints: tuple[Joint, ...], variables: tuple[Joint, ...]):
    """For each moving joint, the index of the value that drives it, the factor and the
    constant: its q is ``scale * q[source] + shift``."""
    index = {j.name: i for i, j in enumerate(variables)}
    names = [j.name for j in joints] + [j.name for j in variables if j not in joints]
    if len(set(names)) != len(names):
        raise InputError(f"chain: expected unique joint names, found {names}")
    source, scale, shift = [], [], []
    for j in joints:
        if j.leader is None:
            source.append(index[j.name]), scale.append(1.0), shift.append(0.0)
            continue
        if j.leader not in index:
            what = "a mimic joint itself" if j.leader in names else "neither on the chain nor a leader"
            raise InputError(f"joint {j.name}: expected to mimic an independent joint "
                             f"({', '.join(index)}), found {j.leader!r} ({what})")
        leader = variables[index[j.leader]]
        if leader.kind != j.kind:
            raise InputError(f"joint {j.name}: expected a leader of its own kind ({j.kind}), "
                             f"found {j.leader!r}, {leader.kind}")
        if not (math.isfinite(j.multiplier) and math.isfinite(j.mimic_offset)):
            raise InputError(f"joint {j.name}: expected a finite mimic multiplier and offset, "
                             f"found {j.multiplier} and {j.mimic_offset}")
        source.append(index[j.leader]), scale.append(j.multiplier), shift.append(j.mimic_offset)
    return np.array(source), np.array(scale), np.array(shift)


def leader_limits(limits: Limits, couplings) -> Limits | None:
    """A leader's limits narrowed so that each of its mimic joints stays within its own.

    Parameters
    ----------
    limits : Limits
        The leader's own.
    couplings : iterable of (multiplier, offset, Limits)
        Each mimic joint's coupling (its value is ``multiplier * leader + offset``) and limits.

    Returns
    -------
    Limits, or None if no leader value keeps every mimic joint within its limits.
    """
    lower, upper = limits.lower, limits.upper
    velocity, acceleration, jerk = limits.velocity, limits.acceleration, limits.jerk
    for m, b, own in couplings:
        if m == 0.0:
            if not own.lower <= b <= own.upper:
                return None
            continue
        ends = sorted(((own.lower - b) / m, (own.upper - b) / m))
        lower, upper = max(lower, ends[0]), min(upper, ends[1])
        velocity = min(velocity, own.velocity / abs(m))
        acceleration = min(acceleration, own.acceleration / abs(m))
        jerk = min(jerk, own.jerk / abs(m))
    return (Limits(lower, upper, velocity, acceleration, jerk, limits.torque) if lower < upper
            else None)


@dataclass(frozen=True, eq=False)
class KernelChain:
    """The chain as the numba kernels take it (all axes on z).

    Per moving joint i (n_joints of them, mimic joints included): kinds (n_joints,) int,
    0 revolute, 1 prismatic; the joint moves by ``scale[i] * q[source[i]] + offsets[i]``
    (source int, scale and offsets float, (n_joints,) each); pre (4, 4): base up to joint 1's
    motion; links (n_joints, 4, 4): from joint i's motion to joint i+1's (the last ends at the
    tool); after (n_joints - 1, 4, 4): from joint i's motion to link frame i (the last link
    frame is the tool).

    The kernels take the same chain packed in two arrays, `floats` and `ints` (two arrays
    cross numba's dispatcher in a fraction of the time of six, which is most of the cost of
    one configuration's pose): ints (2 n_joints,) is kinds then source; floats
    (2 n_joints + 12 + 12 n_joints,) is offsets, scale, the top three rows of pre (3, 4)
    row by row, then those of each link (n_joints, 3, 4) (the last row of a rigid transform is
    always 0 0 0 1); `armkit.kinematics.core` reads them through named accessors. `floats`
    and `ints` are read-only; `F` and `I` are the same arrays as the kernels are called with,
    writable only because numba's dispatcher takes a writable array about 80 ns faster: never
    write them.
    """

    kinds: NDArray
    offsets: NDArray
    pre: NDArray
    links: NDArray
    after: NDArray
    source: NDArray
    scale: NDArray
    floats: NDArray = field(init=False, repr=False)
    ints: NDArray = field(init=False, repr=False)
    F: NDArray = field(init=False, repr=False)
    I: NDArray = field(init=False, repr=False)    # noqa: E741 (the kernels' name)
    independent: bool = field(init=False, repr=False)
    """No mimic joint: moving joint i is value i of q, with scale 1."""

    def __post_init__(self):
        floats = np.concatenate([self.offsets, self.scale, np.reshape(self.pre[:3], -1),
                                 np.reshape(self.links[:, :3], -1)]).astype(float)
        ints = np.concatenate([self.kinds, self.source]).astype(np.int64)
        object.__setattr__(self, "F", floats)
        object.__setattr__(self, "I", ints)
        object.__setattr__(self, "floats", floats.view())
        object.__setattr__(self, "ints", ints.view())
        self.floats.setflags(write=False)
        self.ints.setflags(write=False)
        object.__setattr__(self, "independent",
                           bool(np.array_equal(self.source, np.arange(len(self.source)))
                                and (self.scale == 1.0).all()))

    def motion_ends(self, lower: ArrayLike, upper: ArrayLike) -> NDArray:
        """(2, n_joints): each moving joint's motion ``scale * q[source] + offset`` at the
        joint values `lower` and `upper` (n,) (not sorted: a negative scale swaps them)."""
        ends = np.stack([np.asarray(lower, float), np.asarray(upper, float)])
        return self.scale * ends[:, self.source] + self.offsets
