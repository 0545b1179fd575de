"""The end-to-end job: `armkit demo` as a user runs it, in fresh processes.

    python benchmarks/job.py              # 3 rounds
    python benchmarks/job.py --rounds 5

Each round runs the README's first command, ``python -m armkit demo --json``, twice in fresh
processes: once with an empty numba cache (``NUMBA_CACHE_DIR`` a new temporary directory, as on
a fresh install) and once again on that directory (warm, as every later run). It prints the
wall time of the whole command, the job's own time per step (from its summary), and, as the
reference measured in the same run, the motion's own duration: the drive moves in real time, so
the job can take no less than that. Figures are min-median-max over the rounds, with the load
average.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from common import Spread, load


def demo(cache: str, out: str) -> tuple[float, dict]:
    """Wall time (s) of one `armkit demo --json` in a fresh process, and its summary."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "armkit", "demo", "--json", "--out", out],
                          capture_output=True, text=True, env=env, timeout=600)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"armkit demo failed: {done.stderr.strip() or done.stdout[-500:]}")
    return wall, json.loads(done.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    rounds = parser.parse_args().rounds
    walls: dict[str, list[float]] = {"empty cache": [], "warm cache": []}
    steps: dict[str, list[float]] = {}
    motion, error, resolution = [], [], []
    print(f"armkit demo, {rounds} rounds; {load()}")
    for _ in range(rounds):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
            for kind in walls:
                wall, doc = demo(cache, out)
                walls[kind].append(wall)
                if kind == "warm cache":
                    for step, seconds in doc["timings_s"].items():
                        steps.setdefault(step, []).append(seconds)
                    motion.append(doc["motion"]["duration_s"])
                    error.append(doc["position_error"]["mm"])
                    resolution.append(doc["position_error"]["drive_resolution_m"] * 1e3)
    floor = Spread(tuple(motion))
    print(f"{'':28s} {'median [min-max] s':>24s}   x the motion's own duration")
    for kind, values in walls.items():
        s = Spread(tuple(values))
        print(f"{'armkit demo, ' + kind:28s} {s.text('s'):>24s}   {s.median / floor.median:.1f}x")
    print(f"{'the motion itself':28s} {floor.text('s'):>24s}")
    print("steps of the job (warm cache), s:")
    for step, values in steps.items():
        print(f"  {step:12s} {Spread(tuple(values)).text('s')}")
    print(f"final tool error: {max(error):.4f} mm (the drive's resolution there: "
          f"{min(resolution):.4f} mm); {load()}")


if __name__ == "__main__":
    main()
