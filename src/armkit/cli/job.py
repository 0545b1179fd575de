"""`armkit run TASK.yaml`, `armkit demo` and `armkit view ROBOT [Q...]`: the end-to-end job, its
built-in task, and the 3-D view of any robot."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.text import Text

from armkit.cli.command import (EXIT_FAILED, NUMBERS, JsonFlag, app, output_folder,
                                print_json, stdout)
from armkit.cli.robots import RobotArg
from armkit.cli.values import load_robot, number, output_path

STEP_NAMES = {"target": "target to the base frame", "drive": "the arm's joints from the drive",
              "ik": "inverse kinematics", "plan": "collision-free path",
              "trajectory": "smooth motion within the limits", "send": "waypoints to the drive",
              "arrival": "the drive's arrival", "check": "final position"}

OutOption = Annotated[Path | None, typer.Option(
    "--out", help="Folder for the report (default: the task's `report`, else ./armkit-report).")]


def _job(task, out: Path, as_json: bool) -> None:
    """Run a task with a progress display (or quietly with --json), write its report, print
    where it is; exit 1 if the job stopped short."""
    from armkit.report.job import summary, write_report
    from armkit.task import run_task

    out = output_folder(out)
    started = time.perf_counter()
    if as_json:
        result = run_task(task)
    else:
        stdout.rule(f"armkit run: {task.name} ({task.robot.name}, {task.robot.n} joints)")
        with stdout.status("starting") as status:
            def on_step(step: str, detail: str) -> None:
                if detail:
                    stdout.print(Text.assemble(("  done", "green"),
                                               f" {STEP_NAMES[step]}: {detail}"))
                else:
                    status.update(f"{STEP_NAMES[step]} ...")
            result = run_task(task, on_step)
    write_report(result, out)
    if as_json:
        print_json({**summary(result), "report": str(out / "report.html")})
    else:
        u = task.units
        if result.success:
            stdout.print(Text.assemble(
                ("done", "bold green"), f" in {time.perf_counter() - started:.1f} "
                f"s: the tool is {u.length_from_si(result.position_error):.4f} "
                f"{u.length} from the target (the drive's resolution allows "
                f"{u.length_from_si(result.resolution):.4f} {u.length})"))
        else:
            step = STEP_NAMES.get(result.stopped_at, result.stopped_at)
            stdout.print(Text.assemble(("stopped", "bold red"), f" at {step}: {result.reason}"))
        stdout.print(f"report: {out / 'report.html'}")
    if not result.success:
        raise typer.Exit(EXIT_FAILED)


@app.command()
def run(task: Annotated[Path, typer.Argument(help="Task file (YAML).")],
        out: OutOption = None, as_json: JsonFlag = False) -> None:
    """Run the end-to-end job of a task file: target, IK, path, motion, drive, report."""
    from armkit.io.tasks import load_task

    job = load_task(task)
    _job(job, out or job.report or Path("armkit-report"), as_json)


@app.command()
def demo(out: Annotated[Path, typer.Option("--out", help="Folder for the report.")] = Path(
             "armkit-demo"), as_json: JsonFlag = False) -> None:
    """Run the built-in water-supply task (paper 1) against the simulated drive."""
    from armkit.task import demo_task

    _job(demo_task(), out, as_json)


@app.command(context_settings=NUMBERS)
def view(robot: RobotArg,
         q: Annotated[list[float] | None, typer.Argument(
             help="Joint values in the robot file's units (default: zero, or the nearest limit).",
             metavar="[Q...]", parser=number())] = None,
         out: Annotated[Path, typer.Option("--out", help="The HTML file to write.")] = Path(
             "armkit-view.html")) -> None:
    """Write an offline interactive 3-D view of a robot: links as collision capsules, frames."""
    import numpy as np

    from armkit.errors import InputError
    from armkit.report.view import robot_view, write_view

    model = load_robot(robot)
    if q and len(q) != model.n:
        raise InputError(f"Q: expected {model.n} joint values for {model.name}, found {len(q)}")
    output_path(out, "--out", folder=False, formats=(".html", ".htm"))
    q_si = model.q_to_si(q) if q else np.clip(0.0, model.lower, model.upper)
    write_view(robot_view(model, q_si, title=f"{model.name} at q = "
                          f"{np.round(model.q_from_si(q_si), 3).tolist()}"), out)
    stdout.print(f"view: {out}")
