"""`armkit workspace ROBOT`: Monte Carlo workspace, its numbers and its pictures."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

import armkit
from armkit.cli.app import JsonFlag, SiFlag, app, output_folder, print_json, stderr, stdout
from armkit.cli.robots import RobotArg
from armkit.errors import InputError
from armkit.model import SI

PROGRESS_FROM = 2_000_000       # samples; shorter runs end before a bar would help
CONVERGED = 0.01                # volume growth over the last doubling below which we say so


def _count(text: str) -> int:
    """-n as people write it: 1000000, 1_000_000 or 1e6."""
    try:
        value = float(text.replace("_", ""))
    except ValueError:
        raise InputError(f"N: expected a whole number such as 1000000 or 1e6, "
                         f"found {text!r}") from None
    if not (math.isfinite(value) and value == int(value)):
        raise InputError(f"N: expected a whole number such as 1000000 or 1e6, found {text!r}")
    return int(value)


@app.command()
def workspace(robot: RobotArg,
              n: Annotated[str, typer.Option("-n", metavar="N",
                                             help="Samples (joint vectors), e.g. 1e6.")] = "1e6",
              seed: Annotated[int, typer.Option(help="Seed of the joint samples.")] = 0,
              resolution: Annotated[float | None, typer.Option(
                  help="Voxel edge, file units (default: 1/50 of the arm's span, rounded).")]
              = None,
              height: Annotated[float | None, typer.Option(
                  help="Height of the horizontal section, file units (default: mid-height).")]
              = None,
              azimuth: Annotated[float, typer.Option(
                  help="Azimuth of the vertical section through the z axis, file units.")]
              = 0.0,
              out: Annotated[Path, typer.Option(help="Folder for the figures.")] = Path("."),
              scheduler: Annotated[str | None, typer.Option(
                  help="Dask scheduler address, e.g. tcp://127.0.0.1:8786 (default: "
                       "this process).")] = None,
              as_json: JsonFlag = False, si: SiFlag = False) -> None:
    """Bounds, reach, volume and sections of the tool's workspace, and its pictures."""
    # Here, not at the top: matplotlib would slow down every other command's start.
    from armkit.report.workspace import default_height, save_workspace_figures

    model = armkit.robot(robot)
    units = SI if si else model.units
    samples = _count(n)
    out = output_folder(out)
    kwargs = dict(seed=seed, scheduler=scheduler)
    if resolution is not None:
        if not (math.isfinite(resolution) and resolution > 0):
            raise InputError(f"--resolution: expected a positive voxel edge in "
                             f"{model.units.length}, found {resolution:g}")
        kwargs["resolution"] = float(model.units.length_to_si(resolution))
    with Progress(TextColumn("sampling"), BarColumn(), MofNCompleteColumn(),
                  TimeRemainingColumn(), console=stderr, transient=True,
                  disable=samples < PROGRESS_FROM) as bar:
        task = bar.add_task("samples", total=samples)
        ws = armkit.workspace(model, samples,
                              progress=lambda done, _: bar.update(task, completed=done), **kwargs)
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
    stdout.print(f"[bold]{model.name}[/bold]: {ws.samples:,} samples, seed {ws.seed}, "
                 f"voxels of {length(ws.resolution):g} {u}")
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
