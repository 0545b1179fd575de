"""Mutated robot files and URDFs: an ArmkitError naming the file (and the field, where the
mutation knows it) in bounded time, or a model that passes a sanity check; never a hang, another
exception type, an invalid file accepted or a model silently changed (see fuzz_files.py).

ARMKIT_FUZZ_FILES sets the number of files of each kind (300 by default; the closing figures
were run with ``python -m tests.io.fuzz_files --count 2000 --seed 14``).
"""

from __future__ import annotations

import os

import pytest

from tests.io.fuzz_files import Case, judge, run

COUNT = int(os.environ.get("ARMKIT_FUZZ_FILES", "300"))
SEED = int(os.environ.get("ARMKIT_FUZZ_SEED", "14"))


@pytest.mark.parametrize("kind", ["yaml", "urdf"])
def test_mutated_files(kind):
    report = run(COUNT, SEED, (kind,))
    print("\n".join(report.lines()))
    assert not report.failures, "\n".join(report.failures[:20])
    counts = {(e, o): v for (k, e, o), v in report.counts.items()}
    assert sum(counts.values()) == COUNT
    # Every class was exercised, and the loads that must succeed did.
    assert counts.get(("refuse", "refused"), 0) > COUNT * 0.4
    assert counts.get(("same", "loaded"), 0) > COUNT * 0.1
    assert counts.get(("either", "loaded"), 0) + counts.get(("either", "refused"), 0) > 0


def test_the_judge_counts_what_breaks_the_rules():
    case = Case("yaml", "/f.yaml", "refuse", "bool for a number", field="joints[1].a")
    good = {"outcome": "refused", "message": "/f.yaml: joints[1].a: expected a valid number, found True"}
    assert judge(case, good) is None
    assert "hang" in judge(case, None)
    assert "not an ArmkitError" in judge(case, {"outcome": "crashed", "message": "TypeError: x"})
    assert "accepted" in judge(case, {"outcome": "loaded", "finite": True, "same": None})
    assert "does not name 'joints[1].a'" in judge(case, {**good, "message": "/f.yaml: other"})
    assert "does not name the file" in judge(case, {**good, "message": "joints[1].a: x"})
    assert "not one line" in judge(case, {**good, "message": good["message"] + "\nmore"})
    same = Case("urdf", "/g.urdf", "same", "meshes")
    assert "different model" in judge(same, {"outcome": "loaded", "finite": True, "same": False})
    either = Case("urdf", "/g.urdf", "either", "bytes damaged")
    assert "not finite" in judge(either, {"outcome": "loaded", "finite": False, "same": None})
