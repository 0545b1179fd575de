"""`armkit workspace ROBOT`: Monte Carlo workspace, its numbers and its pictures."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.text import Text

import armkit
from armkit.cli.command import JsonFlag, SiFlag, app, output_folder, print_json, stderr, stdout
from armkit.cli.robots import RobotArg
from armkit.cli.values import COORDINATE, check_number, load_robot, number
from armkit.model import SI

PROGRESS_FROM = 2_000_000       # samples; shorter runs end before a bar would help
CONVERGED = 0.01                # volume growth over the last doubling below which we say so
# Samples one command takes: in this process about an hour at a few million samples a
# second on one core; on a Dask cluster a hundred times that. More cannot finish in a sitting.
MOST_SAMPLES = 10**10
MOST_SAMPLES_DASK = 10**12
ESTIMATE_FROM = 5.0             # s: runs expected to take longer say so before they go on
REPORT_EVERY = 0.1              # fraction of the samples between two lines without a terminal


def _count(text: str, most: int, where: str) -> int:
    """-n as people write it: 1000000, 1_000_000 or 1e6, at most `most`."""
    return int(check_number("-n", text, 1, most, integer=True,
                            unit=f"samples {where}"))


class _Lines:
    """Progress for a log or a pipe, where a bar cannot redraw: after the first chunk, an
    estimate of the time left if the run is long, then a line every tenth of the samples."""

    def __init__(self, samples: int) -> None:
        self.samples, self.started, self.next_report = samples, time.perf_counter(), None

    def __call__(self, done: int, total: int) -> None:
        elapsed = time.perf_counter() - self.started
        if self.next_report is None:
            left = elapsed * (total - done) / max(done, 1)
            if left < ESTIMATE_FROM:
                self.next_report = total + 1        # short: nothing to say
                return
            stderr.print(f"sampling {total:,} joint vectors: about {_duration(left)} left "
                         f"({done / elapsed:,.0f} samples/s so far)", markup=False)
            self.next_report = done + REPORT_EVERY * total
        elif done >= self.next_report and done < total:
            left = elapsed * (total - done) / done
            stderr.print(f"sampled {done:,} of {total:,} ({100 * done / total:.0f} %), about "
                         f"{_duration(left)} left", markup=False)
            self.next_report = done + REPORT_EVERY * total


def _duration(seconds: float) -> str:
    for size, unit in ((86400, "days"), (3600, "h"), (60, "min")):
        if seconds >= 2 * size:
            return f"{seconds / size:.0f} {unit}"
    return f"{seconds:.0f} s"


@app.command()
def workspace(robot: RobotArg,
              n: Annotated[str, typer.Option("-n", metavar="N",
                                             help="Samples (joint vectors), e.g. 1e6; at most "
                                                  "1e10 in this process, 1e12 on Dask.")]
              = "1e6",
              seed: Annotated[int, typer.Option(help="Seed of the joint samples.",
                                                parser=number(0, 1e18, integer=True))]
              = 0,
              resolution: Annotated[float | None, typer.Option(
                  help="Voxel edge, file units (default: 1/50 of the arm's span, rounded).",
                  parser=number(0, COORDINATE, low_open=True))]
              = None,
              height: Annotated[float | None, typer.Option(
                  help="Height of the horizontal section, file units (default: mid-height).",
                  parser=number())]
              = None,
              azimuth: Annotated[float, typer.Option(
                  help="Azimuth of the vertical section through the z axis, file units.",
                  parser=number(-1e6, 1e6))]
              = 0.0,
              out: Annotated[Path, typer.Option(help="Folder for the figures.")] = Path("."),
              scheduler: Annotated[str | None, typer.Option(
                  help="Dask scheduler address, e.g. tcp://127.0.0.1:8786 (default: "
                       "this process).")] = None,
              as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """Bounds, reach, volume and sections of the tool's workspace, and its pictures."""
    # Here, not at the top: matplotlib would slow down every other command's start.
    from armkit.report.workspace import default_height, save_workspace_figures

    model = load_robot(robot)
    units = SI if si else model.units
    samples = (_count(n, MOST_SAMPLES, "in this process (--scheduler for more)")
               if scheduler is None else _count(n, MOST_SAMPLES_DASK, "on Dask"))
    out = output_folder(out, files=(f"{model.name}_workspace.png", f"{model.name}_sections.png"))
    kwargs = dict(seed=seed, scheduler=scheduler)
    if resolution is not None:
        kwargs["resolution"] = float(model.units.length_to_si(resolution))
    if samples < PROGRESS_FROM:
        ws = armkit.workspace(model, samples, **kwargs)
    elif stderr.is_terminal:
        with Progress(TextColumn("sampling"), BarColumn(), MofNCompleteColumn(),
                      TimeRemainingColumn(), console=stderr, transient=True) as bar:
            task = bar.add_task("samples", total=samples)
            ws = armkit.workspace(model, samples,
                                  progress=lambda done, _: bar.update(task, completed=done),
                                  **kwargs)
    else:
        ws = armkit.workspace(model, samples, progress=_Lines(samples), **kwargs)
    z = default_height(ws) if height is None else float(model.units.length_to_si(height))
    phi = float(model.units.angle_to_si(azimuth))
    figures = save_workspace_figures(ws, out, z, phi, units)
    length = units.length_from_si
    area = lambda a: float(length(length(a)))  # noqa: E731
    volume = lambda v: float(length(length(length(v))))  # noqa: E731
    sections = [{"plane": "horizontal", "height": length(z),
                 "area": area(ws.horizontal_section(z).area)},
                {"plane": "vertical", "azimuth": units.angle_from_si(phi),
                 "area": area(ws.vertical_section(phi).area)}]
    if as_json:
        return print_json({
            "robot": model.name, "units": {"length": units.length, "angle": units.angle},
            "samples": ws.samples, "seed": ws.seed, "chunk": ws.chunk,
            "resolution": length(ws.resolution),
            "bounds": {"lower": length(ws.lower), "upper": length(ws.upper)},
            "reach": length(ws.reach), "radial_reach": length(ws.radial_reach),
            "volume": volume(ws.volume), "volume_change": ws.volume_change,
            "volume_history": [[int(m), volume(v)] for m, v in ws.volume_history],
            "sections": sections, "figures": [str(p) for p in figures]})
    u = units.length
    stdout.print(Text.assemble((model.name, "bold"), f": {ws.samples:,} samples, seed "
                               f"{ws.seed}, voxels of {length(ws.resolution):g} {u}"))
    stdout.print(f"bounds ({u}):  " + "   ".join(
        f"{axis} {lo:.6g} .. {hi:.6g}"
        for axis, lo, hi in zip("xyz", length(ws.lower), length(ws.upper))))
    stdout.print(f"reach ({u}):  {length(ws.reach):.6g} from the base origin, "
                 f"{length(ws.radial_reach):.6g} from the base z axis")
    half = int(ws.volume_history[-2, 0]) if len(ws.volume_history) > 1 else 0
    growth = (f"; grew {100 * ws.volume_change:.2g} % from {half:,} to {ws.samples:,} samples"
              if half else "")
    in_m3 = f" ({ws.volume:.4g} m\u00b3)" if u != "m" else ""
    stdout.print(f"volume ({u}\u00b3):  {volume(ws.volume):.4g}{in_m3}{growth}")
    if not ws.volume_change < CONVERGED:
        stdout.print("note: the volume has not converged at this resolution; more samples "
                     "(-n) or larger voxels (--resolution) settle it")
    stdout.print(f"sections ({u}\u00b2):  z = {sections[0]['height']:.6g}: "
                 f"{sections[0]['area']:.4g};  vertical through the z axis at azimuth "
                 f"{sections[1]['azimuth']:g} {units.angle}: {sections[1]['area']:.4g}")
    stdout.print("figures:  " + ", ".join(str(p) for p in figures))
