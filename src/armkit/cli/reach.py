"""`armkit reach ROBOT`: the reachability map and its pictures; `armkit place ROBOT TASKS`:
where to stand the base so that every task pose is reached."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from armkit.cli.command import (
    EXIT_FAILED,
    JsonFlag,
    SiFlag,
    app,
    output_folder,
    print_json,
    stderr,
    stdout,
)
from armkit.cli.robots import RobotArg
from armkit.cli.values import COORDINATE, load_robot, number
from armkit.model import SI

METHODS = ("auto", "analytic", "lm", "newton")
REPORT_EVERY = 0.1      # fraction of the voxels between two progress lines without a terminal
QUIET_FOR = 5.0         # s: a shorter run prints no progress lines


class _Lines:
    """Progress for a log or a pipe, where a bar cannot redraw: once the run has taken
    QUIET_FOR seconds, a line every tenth of the voxels with the time left."""

    def __init__(self) -> None:
        self.started, self.first, self.next_report = time.perf_counter(), None, 0.0

    def __call__(self, done: int, total: int) -> None:
        if self.first is None:                  # chunks finished before: not this run's
            self.first, self.started = done, time.perf_counter()
        elapsed = time.perf_counter() - self.started
        if elapsed < QUIET_FOR or done <= self.first or done < self.next_report \
                or done >= total:
            return
        left = elapsed * (total - done) / max(done - self.first, 1)
        stderr.print(f"solved {done:,} of {total:,} voxels ({100 * done / total:.0f} %), "
                     f"about {left:.0f} s left", markup=False)
        self.next_report = done + REPORT_EVERY * total


@app.command()
def reach(robot: RobotArg,
          resolution: Annotated[float | None, typer.Option(
              help="Voxel edge, file units (default: 1/50 of the arm's span, rounded).",
              parser=number(0, COORDINATE, low_open=True))] = None,
          orientations: Annotated[int, typer.Option(
              help="Orientations per voxel: approach directions x rolls for six joints or "
                   "more; yaws or pitches for the closed forms of four-joint arms.",
              parser=number(1, 100_000, integer=True))] = 200,
          scene: Annotated[Path | None, typer.Option(
              help="Obstacles (a scene or planning .yaml, or MoveIt .scene) in the base "
                   "frame: only collision-free solutions count.")] = None,
          method: Annotated[str, typer.Option(
              help="IK: auto (the closed form where there is one), analytic, lm or "
                   "newton.")] = "auto",
          seed: Annotated[int, typer.Option(help="Seed of the samples and numeric restarts.",
                                            parser=number(0, 1e18, integer=True))] = 0,
          scheduler: Annotated[str | None, typer.Option(
              help="Dask scheduler address, e.g. tcp://127.0.0.1:8786 (default: this "
                   "process).")] = None,
          out: Annotated[Path, typer.Option(help="Folder for the map (.npz) and its "
                                                 "pictures.")] = Path("."),
          as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """The reachability map: per voxel, the share of tool orientations IK reaches.

    Writes ROBOT_reach.npz (the map), ROBOT_reach.png (sections) and ROBOT_reach.html (3-D,
    offline) into --out. Finished chunks are kept in --out while the map runs: the same
    command after an interruption resumes from them.
    """
    import armkit
    from armkit.errors import InputError
    from armkit.io.reach_maps import ChunkFolder, save_map
    from armkit.report.reach import save_map_figures

    model = load_robot(robot)
    units = SI if si else model.units
    if method not in METHODS:
        raise InputError(f"--method: expected one of {', '.join(METHODS)}, found {method!r}")
    obstacles = None
    if scene is not None:
        from armkit.io.scene import read_scene

        obstacles = read_scene(scene)
    out = output_folder(out)
    h = None if resolution is None else float(model.units.length_to_si(resolution))
    folder = ChunkFolder(out / f"{model.name}_reach.chunks")
    kwargs = dict(scene=obstacles, method=method, seed=seed, scheduler=scheduler,
                  checkpoint=folder)
    started = time.perf_counter()
    if stderr.is_terminal:
        with Progress(TextColumn("solving voxels"), BarColumn(), MofNCompleteColumn(),
                      TimeRemainingColumn(), console=stderr, transient=True) as bar:
            task = bar.add_task("voxels", total=None)
            m = armkit.reach_map(model, h, orientations, progress=lambda done, total:
                                 bar.update(task, completed=done, total=total), **kwargs)
    else:
        m = armkit.reach_map(model, h, orientations, progress=_Lines(), **kwargs)
    seconds = time.perf_counter() - started
    if folder.resumed:
        stderr.print(f"resumed: {folder.resumed} chunks were finished before", markup=False)
    path = save_map(m, out / f"{model.name}_reach.npz")
    folder.clear()
    figures = save_map_figures(m, out, units=units)
    length = units.length_from_si
    K, reached = len(m.orientations), m.count > 0
    problems = len(m.voxels) * K
    doc = {"robot": model.name, "units": {"length": units.length, "angle": units.angle},
           "resolution": length(m.resolution), "voxels": len(m.voxels),
           "orientations": K, "description": m.orientations.description,
           "task": m.orientations.task, "method": m.settings["method"],
           "ik_problems": problems, "seconds": seconds,
           "obstacles": m.settings["obstacles"],
           "reachable_voxels": int(reached.sum()),
           "reachable_volume": float(length(length(length(m.volume)))),
           "full_voxels": int((m.count == K).sum()),
           "mean_index": float(m.index[reached].mean()) if reached.any() else 0.0,
           "best_manipulability": float(m.manipulability.max()),
           "map": str(path), "figures": [str(p) for p in figures]}
    if as_json:
        return print_json(doc)
    u = units.length
    stdout.print(f"[bold]{model.name}[/bold]: {doc['voxels']:,} voxels of "
                 f"{doc['resolution']:g} {u} x {K} orientations ({doc['description']}; task "
                 f"{doc['task']}): {problems:,} IK problems ({doc['method']}) in "
                 f"{seconds:.3g} s")
    in_m3 = f" ({m.volume:.4g} m\u00b3)" if u != "m" else ""
    stdout.print(f"reachable: {doc['reachable_voxels']:,} voxels, "
                 f"{doc['reachable_volume']:.4g} {u}\u00b3{in_m3}; every orientation in "
                 f"{doc['full_voxels']:,}; mean index where reachable "
                 f"{doc['mean_index']:.3f}")
    stdout.print(f"map: {path}")
    stdout.print("figures:  " + ", ".join(str(p) for p in figures))


@app.command()
def place(robot: RobotArg,
          tasks: Annotated[Path, typer.Argument(
              help="Task-pose file (.yaml): the poses in the world and the floor or rail "
                   "the base may stand on.", metavar="TASKS")],
          map_file: Annotated[Path | None, typer.Option(
              "--map", help="The robot's reachability map (.npz from `armkit reach`): "
                            "scores poses by its index and skips bases it rules out.")] = None,
          out: Annotated[Path | None, typer.Option(
              help="Folder for the picture of the placement.")] = None,
          as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """Where to stand the base so that IK reaches every task pose; exit 1 with the reason
    when no base of the file's floor or rail does."""
    import armkit
    from armkit.io.reach_maps import read_map
    from armkit.io.task_poses import read_task_poses

    model = load_robot(robot)
    units = SI if si else model.units
    if out is not None:
        out = output_folder(out)
    task = read_task_poses(tasks)
    reach_map = None if map_file is None else read_map(map_file, model)
    placement = armkit.base_placement(model, task.poses, task.grid, reach_map=reach_map,
                                      criterion=task.criterion, mask=task.mask,
                                      names=task.names)
    figure = None
    if out is not None:
        from armkit.report.reach import save_placement_figure

        figure = str(save_placement_figure(placement, out / f"{model.name}_placement.png",
                                           units))
    length, angle = units.length_from_si, units.angle_from_si
    doc = {"robot": model.name, "units": {"length": units.length, "angle": units.angle},
           "success": placement.success, "reason": placement.reason,
           "criterion": placement.criterion, "task": placement.mask,
           "bases": len(placement.grid), "feasible": int(placement.feasible.sum()),
           "figure": figure}
    if placement.best is not None:
        best = placement.best
        to_file = (lambda q: q) if si else model.q_from_si
        doc.update(position=length(placement.T_world_base[:3, 3]),
                   yaw=float(angle(placement.grid.yaws[best])),
                   score=float(placement.score[best]),
                   margin=float(length(placement.margin[best])),
                   yaw_margin=float(angle(placement.yaw_margin)),
                   poses=[{"name": name, "reachability": float(r), "q": q}
                          for name, r, q in zip(task.names, placement.reachability[best],
                                                to_file(placement.q))])
    if as_json:
        print_json(doc)
    else:
        _show_placement(doc, model, units)
    if not placement.success:
        raise typer.Exit(EXIT_FAILED)


def _show_placement(doc: dict, model, units) -> None:
    u, a = units.length, units.angle
    if not doc["success"]:
        stdout.print(f"no placement: {doc['reason']} ({doc['bases']:,} bases tried)")
        return
    x, y, z = doc["position"]
    stdout.print(f"best base: x {x:.6g}  y {y:.6g}  z {z:.6g} {u},  yaw {doc['yaw']:.6g} {a}")
    stdout.print(f"score: {doc['score']:.4g} (the worst pose's {doc['criterion']});  margin: "
                 f"{doc['margin']:.4g} {u} to a base that fails, {doc['yaw_margin']:.4g} {a} "
                 f"of yaw;  {doc['feasible']:,} of {doc['bases']:,} bases reach every pose")
    joint_units = [units.of_joint(r) for r in model.chain.revolute]
    table = Table("pose", "index", *[f"{n} ({j})" for n, j in zip(model.joint_names,
                                                                     joint_units)],
                  box=None, title=f"joint values from the best base (task {doc['task']})",
                  title_justify="left")
    for pose in doc["poses"]:
        index = "-" if pose["reachability"] != pose["reachability"] else \
            f"{pose['reachability']:.3f}"
        table.add_row(pose["name"], index, *[f"{v:.6g}" for v in pose["q"]])
    stdout.print(table)
    if doc["figure"]:
        stdout.print(f"figure: {doc['figure']}")
