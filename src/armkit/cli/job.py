"""`armkit run TASK.yaml`, `armkit demo` and `armkit view ROBOT [Q...]`: the end-to-end job,
its built-in task, and the 3-D view of any robot with joint sliders.

Exit status of `run` and `demo`: 0 done, 1 the job stopped short (its report says why), 2 bad
input (nothing sent), 3 the motion is done but its record could not be written in full
(summary.json first, then the figures, then the page).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.text import Text

from armkit.cli.command import (EXIT_FAILED, NUMBERS, JsonFlag, app, print_json, stderr,
                                stdout)
from armkit.cli.robots import RobotArg
from armkit.cli.values import load_robot, number, output_path
from armkit.errors import InputError

# The job, its report and the views import numba, scipy, matplotlib and plotly: each command
# imports them when it runs, so that `armkit --help` and the other commands start fast.

EXIT_RECORD_INCOMPLETE = 3
STEP_NAMES = {"target": "target to the base frame", "drive": "the arm's joints from the drive",
              "ik": "inverse kinematics", "plan": "collision-free path",
              "motion": "jerk-limited motion within the limits",
              "checks": "checks before sending", "send": "waypoints to the drive",
              "arrival": "the drive's arrival", "final": "final position"}

OutOption = Annotated[Path | None, typer.Option(
    "--out", help="Folder for the report (default: the task's `report`, else ./armkit-report).")]


def _say(text: str) -> None:
    """A line with text from files in it: printed as it is (no console markup, no emoji)."""
    stdout.print(text, markup=False, emoji=False)


def _job(task, out: Path, as_json: bool) -> None:
    """Check the report can be written, run the task with a progress display (or quietly with
    --json), write its report, say where it is; exit 1 if the job stopped short, 3 if the
    report could not be written after the arm moved."""
    from armkit.job import run_job
    from armkit.report.job import FILES, check_report, summary, write_report

    out = check_report(task, out)
    started = time.perf_counter()
    if as_json:
        result = run_job(task)
    else:
        stdout.rule(Text(f"armkit run: {task.name} ({task.robot.name}, {task.robot.n} "
                         f"joints)"), characters="-")
        with stdout.status("starting") as status:
            def on_step(step: str, detail: str) -> None:
                if detail:
                    _say(f"  done {STEP_NAMES[step]}: {detail}")
                else:
                    status.update(f"{STEP_NAMES[step]} ...")
            result = run_job(task, on_step)
    try:
        write_report(result, out)
    except Exception as err:        # anything at all: the arm has moved, say so and stop
        moved = result.sent is not None and result.sent.waypoints > 0
        written = [name for name in FILES if (out / name).is_file()]
        why = f"{err.strerror} ({err.filename})" if isinstance(err, OSError) else str(err)
        stderr.print(f"{'the motion is done' if moved else 'the job ended'} "
                     f"({result.reason or 'ok'}), but its record is incomplete: {why}; "
                     f"written: {', '.join(written) or 'nothing'}", markup=False, emoji=False)
        raise typer.Exit(EXIT_RECORD_INCOMPLETE) from None
    if as_json:
        print_json({**summary(result), "report": str(out / "report.html")})
    else:
        u = task.units
        if result.success:
            final = result.final
            _say(f"done in {time.perf_counter() - started:.1f} s: the tool is "
                 f"{u.length_from_si(final.position_error):.4f} {u.length} from the target "
                 f"(the drive's resolution allows {u.length_from_si(final.resolution):.4f} "
                 f"{u.length})")
        else:
            step = STEP_NAMES.get(result.stopped_at, result.stopped_at)
            _say(f"stopped at {step}: {result.reason}")
        _say(f"report: {out / 'report.html'}")
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
    from armkit.io.tasks import demo_task

    _job(demo_task(), out, as_json)


@app.command(context_settings=NUMBERS)
def view(robot: RobotArg,
         q: Annotated[list[float] | None, typer.Argument(
             help="Joint values in the robot file's units (default: zero, or the nearest limit).",
             metavar="[Q...]", parser=number())] = None,
         out: Annotated[Path, typer.Option("--out", help="The HTML file to write.")] = Path(
             "armkit-view.html"),
         tip: Annotated[str | None, typer.Option(
             "--tip", help="URDF only: the link the chain ends at, where the tree has several."
         )] = None) -> None:
    """Write an offline 3-D view of a robot, with a slider per joint that moves it (a URDF's
    visual meshes where it has them and trimesh is installed)."""
    import numpy as np

    from armkit.io.robot_files import load_robot as load_urdf
    from armkit.io.visuals import read_visuals
    from armkit.planning import arm_geometry
    from armkit.report.view import view_page, visual_bodies, write_page

    model = load_robot(robot) if tip is None else load_urdf(robot, tip)
    if q and len(q) != model.n:
        raise InputError(f"Q: expected {model.n} joint values for {model.name}, found {len(q)}")
    output_path(out, "--out", folder=False, formats=(".html", ".htm"))
    q_si = model.q_to_si(q) if q else np.clip(0.0, model.lower, model.upper)
    outside = (q_si < model.lower - 1e-12) | (q_si > model.upper + 1e-12)
    if outside.any():
        j = int(np.argmax(outside))
        lo, hi = model.q_from_si(model.lower)[j], model.q_from_si(model.upper)[j]
        raise InputError(f"Q: expected {model.joint_names[j]} within {lo:g}..{hi:g} "
                         f"{model.joint_units[j]}, found {q[j]:g}")
    bodies = None
    try:
        visuals = read_visuals(model)
    except ImportError:
        _say("the URDF's visual meshes need trimesh (pip install \"armkit[mesh]\"): "
             "drawing the collision capsules")
        visuals = None
    if visuals is not None:
        bodies = visual_bodies(visuals, arm_geometry(model))
        for note in visuals.notes[:5]:
            _say(f"not drawn: {note}")
    page = view_page(model, q_si, bodies=bodies, title=f"{model.name} at q = "
                     f"{np.round(model.q_from_si(q_si), 3).tolist()}")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"--out: expected a folder armkit can write, found {out.parent} "
                         f"({err.strerror or err})") from None
    try:
        write_page(page, out)
    except OSError as err:
        raise InputError(f"--out: expected a file armkit can write, found {out} "
                         f"({err.strerror or err})") from None
    _say(f"view: {out}")
