"""Every kernel of armkit's common calls compiled up front: `warm_up`.

A program that makes light calls never waits for numba (`armkit.jit`): they run as Python until
a background thread has compiled their kernels. A program that wants compiled speed from its
first call, such as a control loop, calls `warm_up` once before it starts: it runs each common
call once with its kernels compiled in the foreground (from numba's cache on disk when the
kernels were compiled before, about 2 s; compiled anew on a fresh install, a minute or two).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from armkit import jit
from armkit.errors import InputError

ROBOTS = ("ur5", "puma560", "water_supply", "modular_4dof", "panda")
"""The built-in robots a warm-up runs on: one per closed-form family, and one solved
numerically (a kernel is compiled per argument types, not per robot, so these serve every
robot)."""

CAPABILITIES = ("kinematics", "ik", "trajectory", "planning", "workspace")


@dataclass(frozen=True)
class WarmUpStep:
    """One call of the warm-up: its capability and what it runs."""

    capability: str
    name: str
    run: Callable[[], object]


def warm_up_steps(capabilities: Iterable[str] = CAPABILITIES) -> list[WarmUpStep]:
    """The calls a warm-up makes, in order, for the given capabilities.

    Raises
    ------
    InputError
        If a capability is not one of `CAPABILITIES`.
    """
    from armkit.io.robot_files import robot as built_in
    from armkit.kinematics.forward import fk, fk_frames
    from armkit.kinematics.ik import IKSolver
    from armkit.kinematics.jacobian import jacobian
    from armkit.planning import Box, CollisionChecker, Scene, plan
    from armkit.sampled_workspace import workspace
    from armkit.trajectory import jerk_limited, quintic, retime, spline, trapezoidal

    chosen = tuple(capabilities)
    unknown = [c for c in chosen if c not in CAPABILITIES]
    if unknown:
        raise InputError(f"capabilities: expected some of {', '.join(CAPABILITIES)}, found "
                         f"{', '.join(map(repr, unknown))}")
    rng = np.random.default_rng(0)
    steps: list[WarmUpStep] = []

    def add(capability, name, run):
        if capability in chosen:
            steps.append(WarmUpStep(capability, name, run))

    for name in ROBOTS:
        robot = built_in(name)
        Q = rng.uniform(*robot.chain.sampling_limits, (20_000, robot.n))
        q = Q[0]
        T = fk(robot, Q[:64])
        solver = IKSolver(robot)
        add("kinematics", f"{name}: one pose, frames and Jacobian",
            lambda robot=robot, q=q: (fk(robot, q), fk_frames(robot, q),
                                      jacobian(robot, q)))
        add("kinematics", f"{name}: a batch of poses and Jacobians",
            lambda robot=robot, Q=Q: (fk(robot, Q), jacobian(robot, Q)))
        add("ik", f"{name}: one target, from a start and alone",
            lambda solver=solver, T=T, q=Q[1]: (solver.solve(T[0], q), solver.solve(T[1])))
        add("ik", f"{name}: a batch of targets",
            lambda solver=solver, T=T: solver.solve(T))
        if solver.family is not None:
            add("ik", f"{name}: every closed-form solution",
                lambda solver=solver, T=T: (solver.solutions(T[0]), solver.solutions(T)))
    ur5 = built_in("ur5")
    q0, q1 = np.zeros(6), np.full(6, 0.5)
    vmax, amax = np.full(6, 1.0), np.full(6, 2.0)
    waypoints = rng.uniform(-1.0, 1.0, (8, 6))
    add("trajectory", "point to point profiles",
        lambda: (jerk_limited(q0, q1, vmax, amax, 10 * amax).sample(
                     np.linspace(0.0, 1.0, 100)),
                 trapezoidal(q0, q1, vmax, amax), quintic(q0, q1, 2.0)))
    add("trajectory", "splines and retiming",
        lambda: (spline(np.arange(8.0), waypoints, "5-5-5-5-5-5-5").sample(
                     np.linspace(0.0, 7.0, 5000)),
                 retime(waypoints, vmax, amax)))
    shelf = Scene([Box.from_bounds([0.3, -0.5, 0.2], [0.6, 0.5, 0.24])])
    add("planning", "collision checks and a plan",
        lambda: plan(CollisionChecker(ur5, shelf), np.array([0.0, -1.0, 1.0, 0.0, 0.5, 0.0]),
                     np.array([1.0, -1.2, 1.2, 0.3, 0.5, 0.2]), seed=0, waypoints=10))
    add("workspace", "a Monte Carlo workspace",
        lambda: workspace(ur5, 200_000, seed=0))
    return steps


def warm_up(capabilities: Iterable[str] = CAPABILITIES, *,
            progress: Callable[[WarmUpStep], None] | None = None) -> int:
    """Compile the kernels of armkit's common calls now, so that later calls run compiled.

    Each step of `warm_up_steps` runs once with every kernel compiled in the foreground (loaded
    from numba's cache when it holds them). Kernels already compiled, or queued for the
    background thread, are done too.

    Parameters
    ----------
    capabilities : iterable of str
        Some of `CAPABILITIES`; all by default.
    progress : callable, optional
        Called with each step before it runs.

    Returns
    -------
    int
        The number of steps run.

    Example
    -------
    >>> import armkit
    >>> armkit.warm_up(["kinematics"])        # doctest: +SKIP
    10
    """
    steps = warm_up_steps(capabilities)
    before = jit.mode
    jit.set_mode("compiled")
    try:
        for step in steps:
            if progress is not None:
                progress(step)
            step.run()
    finally:
        jit.mode = before
    jit.wait_for_background()
    return len(steps)
