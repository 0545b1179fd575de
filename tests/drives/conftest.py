"""Fixtures for the drive tests: register maps and simulated drives on loopback ports.

Every wait is bounded: client time-outs of a fraction of a second, server threads joined with
a time-out, so a broken drive fails a test instead of hanging it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from armkit.drives import SimDrive
from armkit.io.register_maps import load_register_map, parse_register_map

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "drives"
INSPECTION = EXAMPLES / "inspection_6dof.map.yaml"
WATER = EXAMPLES / "water_supply.map.yaml"
TIMEOUT = 0.3   # s, the clients' response time-out in these tests


def float32_map():
    """The inspection map with float32 targets in degrees."""
    doc = yaml.safe_load(INSPECTION.read_text())
    for joint in doc["joints"]:
        joint.update(type="float32", scale=1.0)
    return parse_register_map(doc, "float32 map")


def locked_map(**out_of_limits):
    """The inspection map with a lock register (29) and a fault reset (30); `out_of_limits`
    as the file's section of that name."""
    doc = yaml.safe_load(INSPECTION.read_text())
    doc["command"].update(lock=29, reset=30)
    if out_of_limits:
        doc["out_of_limits"] = out_of_limits
    return parse_register_map(doc, "locked map")


def drive_took(sim: SimDrive, register_map, q) -> int | None:
    """The last waypoint of `q` (N, n) whose targets the drive took, from the drive's own
    record (its index register aside); None if it took none of them."""
    m = register_map
    keep = [i for i in range(m.block_count) if m.waypoint - m.block_start != i]
    sent = m.encode(q)[:, keep]
    taken = {tuple(np.array(block)[keep]) for block in list(sim.taken)}
    found = [k for k in range(len(q)) if tuple(sent[k]) in taken]
    return max(found) if found else None


def assert_report_true(err, took: int | None) -> None:
    """A DriveError tells the truth: its last accepted waypoint is the last the drive took,
    or, when it says the failed waypoint's outcome is unknown, that one may be taken too."""
    if err.outcome_unknown:
        assert took in (err.last_accepted, err.waypoint), (str(err), took)
    else:
        assert took == err.last_accepted, (str(err), took)


MAPS = {"int32": lambda: load_register_map(INSPECTION), "float32": float32_map,
        "water_supply": lambda: load_register_map(WATER)}


@pytest.fixture(params=sorted(MAPS))
def any_map(request):
    return MAPS[request.param]()


@pytest.fixture
def inspection_map():
    return load_register_map(INSPECTION)


@pytest.fixture
def sim(inspection_map):
    with SimDrive(inspection_map) as drive:
        yield drive


def waypoints(register_map, count: int = 10, seed: int = 0) -> np.ndarray:
    """`count` waypoints uniform within the limits, (count, n), SI."""
    robot = register_map.robot
    return np.random.default_rng(seed).uniform(robot.lower, robot.upper, (count, robot.n))
