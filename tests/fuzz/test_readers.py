"""Mutated files through every reader: an ArmkitError of one line naming the file, or a result;
never a traceback, a hang, an invalid file accepted or a content silently changed (see
harness.py). The default run reads a sample of each reader; ``pytest -m slow`` reads 2,000
mutants of each (the issue's figure), and ``python -m tests.fuzz.harness`` prints the table."""

from __future__ import annotations

import os

import pytest

from tests.fuzz.harness import judge, run
from tests.fuzz.mutate import Case
from tests.fuzz.seeds import READERS

SAMPLE = int(os.environ.get("ARMKIT_FUZZ_SAMPLE", "12"))
SEED = int(os.environ.get("ARMKIT_FUZZ_SEED", "7"))


def check(readers: list[str], count: int) -> None:
    report = run(readers, count, SEED)
    print(report.table())
    assert not report.failures, "\n".join(report.failures[:20])
    for reader in readers:
        counts = report.rows[reader]
        assert counts["cases"] == count
        assert counts["refused"] + counts["read"] == count


def test_a_sample_of_mutants_of_every_reader():
    check(list(READERS), SAMPLE)                   # one worker process for all


@pytest.mark.slow
@pytest.mark.parametrize("reader", list(READERS))
def test_two_thousand_mutants(reader):
    check([reader], 2000)


def test_the_judge_counts_what_breaks_the_rules():
    refuse = Case("task", "/f.yaml", "refuse", "bool for a number")
    good = {"outcome": "refused", "message": "/f.yaml: x: expected a valid number, found True"}
    assert judge(refuse, good) is None
    assert judge(refuse, None) == "hang"
    assert judge(refuse, {"outcome": "crashed", "message": "TypeError: x"}) == "traceback"
    assert judge(refuse, {**good, "message": "x: expected"}) == "traceback"        # no file
    assert judge(refuse, {**good, "message": good["message"] + "\nmore"}) == "traceback"
    assert judge(refuse, {**good, "message": "/f.yaml: " + "x" * 400}) == "traceback"
    assert judge(refuse, {"outcome": "read", "same": None}) == "silent"
    same = Case("pcd_binary", "/c.pcd", "same", "rewritten")
    assert judge(same, {"outcome": "read", "same": False}) == "silent"
    assert judge(same, {"outcome": "read", "same": True}) is None
    either = Case("ply_ascii", "/c.ply", "either", "bytes flipped")
    assert judge(either, {"outcome": "read", "same": None}) is None
