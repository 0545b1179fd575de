"""Denavit-Hartenberg tables, standard and modified (Craig), compiled into a chain.

Standard DH, row i:   ``A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``
Modified DH, row i:   ``A_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``
(a modified row holds alpha_{i-1} and a_{i-1} as its ``alpha`` and ``a``).

The joint variable adds to ``theta`` (revolute) or ``d`` (prismatic); the table's value of that
column is the joint's offset, its value at q = 0. A ``fixed`` row moves nothing: it is folded
into the transform of the moving joint before it (or after it, for rows before the first).
Link frame i is the DH frame i, ``A_1 ... A_i``, in both conventions.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.model.chain import Chain, Joint, Limits, freeze
from armkit.spatial import rotx, rotz, transform

_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class DHRow:
    """One row of a DH table, SI (rad, m).

    ``limits`` is required for moving rows and must be None for fixed ones.
    """

    kind: Literal["revolute", "prismatic", "fixed"]
    alpha: float
    a: float
    d: float
    theta: float
    name: str = ""
    limits: Limits | None = None


@dataclass(frozen=True)
class DHTable:
    """A whole DH description: rows, convention, base and tool transforms (4, 4)."""

    rows: tuple[DHRow, ...]
    modified: bool = False
    T_base: NDArray = field(default_factory=lambda: np.eye(4))
    T_tool: NDArray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        object.__setattr__(self, "rows", tuple(self.rows))
        freeze(self, "T_base", "T_tool")


def _tz(d: float) -> NDArray:
    return transform(p=[0.0, 0.0, d])


def _tx(a: float) -> NDArray:
    return transform(p=[a, 0.0, 0.0])


def _rx(alpha: float) -> NDArray:
    return transform(rotx(alpha))


def _rz(theta: float) -> NDArray:
    return transform(rotz(theta))


def dh_transform(row: DHRow, modified: bool = False) -> NDArray:
    """The row's transform ``A`` (4, 4) at its table values (the joint at q = 0)."""
    if modified:
        return _rx(row.alpha) @ _tx(row.a) @ _rz(row.theta) @ _tz(row.d)
    return _rz(row.theta) @ _tz(row.d) @ _tx(row.a) @ _rx(row.alpha)


def _moving_parts(row: DHRow, modified: bool) -> tuple[NDArray, NDArray, float]:
    """(T_before, T_after, offset) of a moving row, its motion about / along local z.

    The offset column (theta or d) moves into the joint value; the other z column commutes
    with the motion, so it may sit on either side of it.
    """
    revolute = row.kind == "revolute"
    offset = row.theta if revolute else row.d
    along_z = _tz(row.d) if revolute else _rz(row.theta)
    if modified:
        return _rx(row.alpha) @ _tx(row.a) @ along_z, np.eye(4), offset
    return np.eye(4), along_z @ _tx(row.a) @ _rx(row.alpha), offset


def chain_from_dh(table: DHTable) -> Chain:
    """Compile a DH or modified-DH table into a chain.

    Raises
    ------
    InputError
        If the table has no moving row, or a moving row has no limits.
    """
    joints: list[Joint] = []
    pending = np.eye(4)                      # fixed rows not yet attached to a joint
    for i, row in enumerate(table.rows):
        if row.kind == "fixed":
            if joints:                       # after a joint: part of that joint's link
                joints[-1] = replace(joints[-1], T_after=joints[-1].T_after
                                     @ dh_transform(row, table.modified))
            else:
                pending = pending @ dh_transform(row, table.modified)
            continue
        if row.limits is None:
            raise InputError(f"rows[{i}].limits: expected [lower, upper] for a {row.kind} "
                             f"joint, found none")
        before, after, offset = _moving_parts(row, table.modified)
        joints.append(Joint(row.name or f"q{len(joints) + 1}", row.kind, _Z, row.limits,
                            pending @ before, after, offset))
        pending = np.eye(4)
    if not joints:
        raise InputError("rows: expected at least one revolute or prismatic row, found none")
    return Chain(joints, table.T_base, table.T_tool)
