"""Product of exponentials: space-frame screw axes and a home pose, compiled into a chain.

``T_base_tool(q) = T_base @ exp([S_1] q_1) ... exp([S_n] q_n) @ T_home @ T_tool``
with ``S_i = (-w_i x p_i, w_i)`` for a revolute joint about the unit axis w_i through the
point p_i, and ``S_i = (v_i, 0)`` for a prismatic joint along v_i (Lynch & Park, ch. 4).

Compilation: joint i gets the frame H_i at p_i with the space frame's orientation, so that
``exp([S_i] q) = H_i @ M_i(q) @ H_i^-1`` with M_i the motion about the axis through H_i's origin.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.model.chain import Chain, Joint, Limits, freeze
from armkit.spatial import invert, translation


@dataclass(frozen=True)
class ScrewRow:
    """One joint as a screw in the space frame at the home configuration, SI.

    ``point`` is a point on a revolute joint's axis; a prismatic joint has no line, and its
    optional point only places its link frame (by default, at the previous joint's point).
    """

    kind: Literal["revolute", "prismatic"]
    axis: NDArray
    limits: Limits
    point: NDArray | None = None
    name: str = ""

    def __post_init__(self):
        freeze(self, "axis", "point")


@dataclass(frozen=True)
class ScrewTable:
    """Screws, home tool pose ``T_home`` (M), base and tool transforms, each (4, 4)."""

    rows: tuple[ScrewRow, ...]
    T_home: NDArray
    T_base: NDArray = field(default_factory=lambda: np.eye(4))
    T_tool: NDArray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        object.__setattr__(self, "rows", tuple(self.rows))
        freeze(self, "T_home", "T_base", "T_tool")


def chain_from_poe(table: ScrewTable) -> Chain:
    """Compile screws and a home pose into a chain.

    Raises
    ------
    InputError
        If a revolute row has no point, or an axis is zero.
    """
    joints, previous = [], translation(np.zeros(3))
    for i, row in enumerate(table.rows):
        if row.point is None and row.kind == "revolute":
            raise InputError(f"rows[{i}].point: expected a point on the revolute axis, found none")
        H = previous if row.point is None else translation(row.point)
        joints.append(Joint(row.name or f"q{i + 1}", row.kind, row.axis, row.limits,
                            T_before=invert(previous) @ H))
        previous = H
    return Chain(joints, table.T_base, invert(previous) @ table.T_home @ table.T_tool)
