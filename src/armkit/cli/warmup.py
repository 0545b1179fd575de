"""`armkit warm-up`: compile the kernels of armkit's common calls now (`armkit.warm_up`)."""

from __future__ import annotations

import time
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

from armkit.cli.command import app, stderr, stdout
from armkit.errors import InputError
from armkit.warmup import CAPABILITIES, warm_up, warm_up_steps


@app.command("warm-up")
def warm_up_command(
        only: Annotated[str | None, typer.Option(
            help=f"Comma-separated capabilities: some of {', '.join(CAPABILITIES)}.")] = None,
) -> None:
    """Compile every kernel of the common calls now (from numba's cache if it holds them), so
    that a program's first calls run compiled."""
    chosen = CAPABILITIES if only is None else tuple(c.strip() for c in only.split(","))
    if not chosen or not set(chosen) <= set(CAPABILITIES):
        raise InputError(f"--only: expected some of {', '.join(CAPABILITIES)} (commas between), "
                         f"found {only!r}")
    total = len(warm_up_steps(chosen))
    start = time.perf_counter()
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                  console=stderr, transient=True) as bar:
        task = bar.add_task("warming up", total=total)

        def show(step):
            bar.update(task, description=f"{step.capability}: {step.name}", advance=1)

        count = warm_up(chosen, progress=show)
    stdout.print(f"{count} calls of {', '.join(chosen)} compiled in "
                 f"{time.perf_counter() - start:.1f} s", markup=False, highlight=False)
