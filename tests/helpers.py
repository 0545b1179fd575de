"""Helpers shared by the tests."""

from __future__ import annotations

import numpy as np

import armkit


def random_q(robot: armkit.Robot, size, seed: int = 0) -> np.ndarray:
    """Joint vectors uniform inside the limits, shape size + (n,)."""
    size = (size,) if isinstance(size, int) else tuple(size)
    return np.random.default_rng(seed).uniform(robot.lower, robot.upper, size + (robot.n,))
