"""The fuzz runner: mutated files read in a worker process under a time guard, each judged.

For every reader it counts the cases, and the three ways to fail: a traceback (an exception
that is not an ArmkitError, or a message on more than one line or not naming the file), a hang
(no answer within the time-out: the worker is killed and restarted) and a silent accept (a
file invalid by construction read without complaint), with a silent change (a file that must
read as its seed reading otherwise) counted with the silent accepts.

Run more than the tests do::

    python -m tests.fuzz.harness --count 2000 --seed 7
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from tests.fuzz.mutate import Case, generate
from tests.io.fuzz_files import Worker
from tests.fuzz.seeds import READERS, close, digest, load


@functools.lru_cache(maxsize=None)
def _reference(reader: str, path: str):
    """The seed's digest, read once per worker."""
    return digest(load(reader, path))


def _check(case: dict) -> dict:
    """Read one case in this process; what happened."""
    import armkit

    start = time.perf_counter()
    try:
        value = load(case["reader"], case["path"])
    except armkit.ArmkitError as err:
        return {"outcome": "refused", "message": str(err)[:2000],
                "seconds": time.perf_counter() - start}
    except BaseException as err:                  # noqa: BLE001 - the failure being counted
        return {"outcome": "crashed", "message": f"{type(err).__name__}: {str(err)[:300]}",
                "seconds": time.perf_counter() - start}
    seconds = time.perf_counter() - start
    same = None
    if case["expect"] == "same":
        # A cloud rewritten in another layout keeps its float32 numbers (to 1 part in 1e7).
        rtol = 2e-7 if case["reader"].startswith(("pcd", "ply", "cloud")) else 1e-12
        same = close(digest(value), _reference(case["reader"], case["reference"]), rtol)
    return {"outcome": "read", "same": same, "seconds": seconds}


def serve() -> None:
    """Answer one JSON case per stdin line with one JSON result line on stdout."""
    for line in sys.stdin:
        sys.stdout.write(json.dumps(_check(json.loads(line))) + "\n")
        sys.stdout.flush()


def judge(case: Case, result: dict | None) -> str | None:
    """The kind of failure ("traceback", "hang", "silent") this result is, or None."""
    if result is None:
        return "hang"
    if result["outcome"] == "crashed":
        return "traceback"
    if result["outcome"] == "refused":
        message = result["message"]
        if "\n" in message or not message.startswith(case.path[:60]) or len(message) > 300:
            return "traceback"               # not one line naming the file
        return "silent" if case.expect == "same" else None
    if case.expect == "refuse" or (case.expect == "same" and not result["same"]):
        return "silent"
    return None


@dataclass
class Report:
    rows: dict = field(default_factory=dict)        # reader -> Counter
    failures: list = field(default_factory=list)

    def table(self) -> str:
        head = "| reader | cases | refused | read | tracebacks | hangs | silent accepts |"
        lines = [head, "|---|---|---|---|---|---|---|"]
        for reader, c in self.rows.items():
            lines.append(f"| {reader} | {c['cases']} | {c['refused']} | {c['read']} | "
                         f"{c['traceback']} | {c['hang']} | {c['silent']} |")
        return "\n".join(lines)


def run(readers, count: int, seed: int, timeout: float = 30.0) -> Report:
    """Generate and read `count` mutants of each reader; the report."""
    report = Report()
    worker = Worker("tests.fuzz.harness")
    try:
        with tempfile.TemporaryDirectory() as scratch:
            for reader in readers:
                counts = Counter()
                for case in generate(reader, count, seed, Path(scratch)):
                    result = worker.ask(case, timeout)
                    counts["cases"] += 1
                    if result is not None:
                        counts[result["outcome"] if result["outcome"] != "crashed"
                               else "traceback-outcome"] += 1
                    failure = judge(case, result)
                    if failure:
                        counts[failure] += 1
                        report.failures.append(f"{reader} {failure}: {case.mutation} "
                                               f"({case.expect}) -> "
                                               f"{(result or {}).get('message', '')[:200]}")
                    Path(case.path).unlink(missing_ok=True)
                report.rows[reader] = counts
    finally:
        worker.stop()
    return report


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=2000, help="mutants of each reader")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--reader", choices=list(READERS), action="append")
    args = parser.parse_args(argv)
    start = time.monotonic()
    report = run(args.reader or list(READERS), args.count, args.seed)
    print(f"seed {args.seed}, {args.count} mutants of each reader, "
          f"{time.monotonic() - start:.0f} s")
    print(report.table())
    for failure in report.failures[:60]:
        print("  FAIL", failure)
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main())
