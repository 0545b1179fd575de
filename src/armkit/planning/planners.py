"""The planners `plan` knows, in one table: name -> compiled loop, Python planner, budget.

The compiled loop runs with armkit's own `CollisionChecker` (every state and edge checked
inside the kernel); the Python planner with any other validity (a `ValidityFunction`, or a
user's object with the same methods). A name the table does not hold is an error, never a
substitute.
"""

from __future__ import annotations

from dataclasses import dataclass

from armkit.errors import InputError
from armkit.jit import Kernel
from armkit.planning.compiled import grow_connect, grow_rrt, grow_star
from armkit.planning.rrt import rrt, rrt_connect, rrt_star


@dataclass(frozen=True)
class Planner:
    """One planner of the table.

    Attributes
    ----------
    name : str
    kernel : Kernel
        The compiled loop (`armkit.planning.compiled`), for a `CollisionChecker`.
    python : callable
        The planner of `armkit.planning.rrt`, for any other validity.
    iterations : int
        The default iteration budget.
    trees : int
        1: one tree from the start; 2: one from the start and one from the goals.
    rewires : bool
        Whether it keeps improving its tree (RRT*: it uses its whole budget).
    """

    name: str
    kernel: Kernel
    python: object
    iterations: int
    trees: int = 1
    rewires: bool = False


PLANNERS = {p.name: p for p in (
    Planner("rrtconnect", grow_connect, rrt_connect, 100_000, trees=2),
    Planner("rrt", grow_rrt, rrt, 100_000),
    Planner("rrtstar", grow_star, rrt_star, 2_000, rewires=True),
)}


def planner_named(name: str) -> Planner:
    """The table's planner of this name.

    Raises
    ------
    InputError
        If the table has none of that name (the message lists the names).
    """
    found = PLANNERS.get(name) if isinstance(name, str) else None
    if found is None:
        raise InputError(f"planner: expected one of {', '.join(PLANNERS)}, found {name!r}")
    return found
