"""Bad command lines, run as users run them (a subprocess each): exit 2 with one line on stderr
naming the option or argument, user text shown as typed (no console markup, no emoji), nothing
on stdout, no traceback, no hang. The default run makes a sample of the calls; ``pytest -m
slow`` makes all of them (over 300)."""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.fuzz.seeds import EXAMPLES

CLOUD = str(EXAMPLES / "perception" / "inlet_scan.pcd")
PLAN = str(EXAMPLES / "shelf.scene.yaml")
CASE = str(EXAMPLES / "tool_changer_table1.yaml")
POSES = str(EXAMPLES / "calibration" / "handeye_poses.yaml")
MEAS = str(EXAMPLES / "calibration" / "water_supply_measurements.csv")
POOL = str(EXAMPLES / "calibration" / "water_supply_pool.csv")
ACC = str(EXAMPLES / "calibration" / "inspection_6dof_accuracy.csv")
TASK = str(EXAMPLES / "tasks" / "water_supply.task.yaml")

MARKUP = ["[bold]x[/bold]", "[/]", ":x:", "ws$\\frac{$"]
TEXT = ["", "x", "a" * 5000, "a" * 100_000, "😀"] + MARKUP
NUMBER = ["nan", "inf", "-inf", "1e309", "0x10", "1,5", "--", "1e", "²"] + TEXT[:4] + MARKUP
POSITIVE = NUMBER + ["-1", "0", "1e300"]
WHOLE = NUMBER + ["-1", "1.5", "1e30"]


def files(tmp: Path) -> list[str]:
    """Paths that are not a readable file of the kind asked for."""
    fifo = tmp / "fifo.pcd"
    if not fifo.exists():
        os.mkfifo(fifo)
    (tmp / "empty.yaml").write_text("")
    (tmp / "empty.pcd").write_bytes(b"")
    (tmp / "dir.yaml").mkdir(exist_ok=True)
    return [str(tmp / "missing.yaml"), str(tmp / "dir.yaml"), "/dev/zero", str(fifo),
            str(tmp / "empty.yaml"), str(tmp / "empty.pcd"), "x" * 300, str(tmp / "[bold].pcd"),
            str(tmp / ":x:.yaml"), ""]


def outs(tmp: Path, kind: str) -> list[str]:
    """--out values that cannot be written: folder or file (`kind`) as the command needs."""
    (tmp / "a_file").write_text("x")
    (tmp / "a_dir.png").mkdir(exist_ok=True)
    (tmp / "a_dir.yaml").mkdir(exist_ok=True)
    (tmp / "a_dir.html").mkdir(exist_ok=True)
    common = ["/dev/null/x", "/proc/armkit", "x" * 300]       # ("" is the current folder)
    if kind == "folder":
        return common + [str(tmp / "a_file")]
    return common + [str(tmp / "a_dir.png"), str(tmp / "a_dir.yaml"), str(tmp / "a_dir.html"),
                     str(tmp / "x.txt"), str(tmp / "no" / "such" / "x.png")]


def calls(tmp: Path) -> list[list[str]]:
    """Every bad call: a valid base call with one argument or option made bad."""
    out = []
    for v in POSITIVE:
        out += [["detect", CLOUD, "--radius", v], ["detect", CLOUD, "--eps", v],
                ["accuracy", ACC, "--tolerance", v]]
    for v in NUMBER + ["-1", "1e300"]:             # 0 s is a time limit: "no path" at once
        out += [["plan", PLAN, "--time-limit", v]]
    for v in TEXT:
        out += [["detect", CLOUD, "--kind", v], ["detect", CLOUD, "--units", v],
                ["detect", CLOUD, "--choose", v], ["detect", CLOUD, "--nonfinite", v],
                ["plan", PLAN, "--planner", v], ["handeye", POSES, "--method", v]]
    for v in WHOLE:
        out += [["plan", PLAN, "--waypoints", v], ["plan", PLAN, "--seed", v],
                ["calibrate", "water_supply", MEAS, "--select", v],
                ["calibrate", "water_supply", MEAS, "--holdout", v]]
    out += [["plan", PLAN, "--waypoints", "200000000"], ["detect", CLOUD, "--radius", "2e6"]]
    for f in files(tmp):
        out += [["detect", f], ["plan", f], ["traj", f], ["handeye", f], ["run", f],
                ["calibrate", "water_supply", f], ["accuracy", f],
                ["detect", CLOUD, "--sensor-to-base", f]]
    for o in outs(tmp, "folder"):
        out += [["detect", CLOUD, "--out", o], ["plan", PLAN, "--out", o],
                ["traj", CASE, "--out", o], ["workspace", "ur5", "-n", "1000", "--out", o],
                ["run", TASK, "--out", o]]
    for o in outs(tmp, "file"):
        out += [["view", "ur5", "--out", o], ["handeye", POSES, "--out", o],
                ["calibrate", "water_supply", MEAS, "--out", o], ["accuracy", ACC, "--out", o]]
    for name in TEXT[1:] + ["x" * 300]:
        out += [["show", name], ["fk", name, "0"], ["view", name]]
    return out


def call(args: list[str], folder: Path) -> dict:
    """Run ``armkit ARGS`` in `folder` (where a call that should have been refused would
    write)."""
    env = {**os.environ, "COLUMNS": "200"}
    try:
        run = subprocess.run([sys.executable, "-m", "armkit", *args], capture_output=True,
                             text=True, timeout=120, cwd=folder, env=env, errors="replace")
    except subprocess.TimeoutExpired:
        return {"args": args, "hang": True}
    return {"args": args, "hang": False, "code": run.returncode, "out": run.stdout,
            "err": run.stderr}


def judge(result: dict) -> str | None:
    shown = [a[:60] for a in result["args"]]
    if result["hang"]:
        return f"{shown}: no exit within 120 s"
    lines = result["err"].splitlines()
    if "Traceback" in result["err"]:
        return f"{shown}: a traceback: {result['err'][-300:]}"
    if result["code"] != 2:
        return f"{shown}: exit {result['code']}, not 2: {result['err'][:200]}"
    if len(lines) != 1 or not lines[0].startswith("armkit: ") or len(lines[0]) > 1000:
        return f"{shown}: not one line: {result['err'][:300]!r}"
    if result["out"]:
        return f"{shown}: something on stdout: {result['out'][:100]!r}"
    if "❌" in result["err"]:
        return f"{shown}: :x: shown as an emoji"
    return None


def run_calls(todo: list[list[str]], folder: Path) -> list[str]:
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(lambda args: call(args, folder), todo))
    failures = [why for why in map(judge, results) if why]
    written = [p.name for p in folder.iterdir() if p.is_file() and p.suffix in
               (".png", ".html", ".json", ".js", ".yaml")
               and p.name not in ("empty.yaml",)]
    return failures + ([f"a refused call wrote {written}"] if written else [])


def test_a_sample_of_bad_calls(tmp_path):
    todo = calls(tmp_path)
    sample = todo[::max(len(todo) // 12, 1)][:12]
    assert run_calls(sample, tmp_path) == []


@pytest.mark.slow
def test_over_three_hundred_bad_calls(tmp_path):
    todo = calls(tmp_path)
    assert len(todo) >= 300
    failures = run_calls(todo, tmp_path)
    assert failures == [], "\n".join(failures[:30])


def test_user_text_reaches_the_console_as_typed(tmp_path):
    result = call(["detect", CLOUD, "--kind", "[bold]pipe[/bold] :x:"], tmp_path)
    assert result["code"] == 2
    assert "[bold]pipe[/bold] :x:" in result["err"] and "❌" not in result["err"]
