"""`armkit traj`: a point-to-point or via-point trajectory case, its peaks and its figures.

A case comes from a YAML file or from options (options override the file); joint values and
limits are in the robot file's units (deg, mm, per second...). Via points (paper 4, Table 1)::

    robot: tool_changer_6dof
    joints: [2, 3, 5]              # the columns of points: 1-based numbers or joint names
    times: [0, 2, 4, 5]            # s
    points: [[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]]
    patterns: [3-3-3, 4-5-5, 5-5-5]
    hold: [0, 0, 0, 0, 0, 0]       # optional: where the other joints stay (default 0)

Point to point::

    robot: inspection_6dof
    start: [0, 0, 0, 0, 0, 0]
    goal: [30, -45, 60, 0, 90, 0]
    profiles: [quintic, jerk-limited]   # cubic | quintic | trapezoidal | jerk-limited
    duration: 10                        # s, for cubic and quintic (default: shortest in limits)
    jerk: 400                           # deg/s^3 (robot files carry no jerk limit)

``velocity``, ``acceleration`` and ``jerk`` (one value or one per joint) replace the robot
file's limits; ``sync: phase`` makes profiles straight lines in joint space.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import typer
from pydantic import Field, ValidationError, model_validator
from rich.table import Table

import armkit
from armkit import trajectory as tj
from armkit.cli.app import NUMBERS, JsonFlag, SiFlag, app, output_folder, print_json, stdout
from armkit.errors import InputError
from armkit.model import SI, Robot
from armkit.io.documents import StrictModel, read_yaml, validation_error

Profile = Literal["cubic", "quintic", "trapezoidal", "jerk-limited"]
Limit = float | list[float] | None


class CaseFile(StrictModel):
    """A trajectory case as its file (or the command's options) gives it, in file units."""

    robot: str
    start: list[float] | None = None
    goal: list[float] | None = None
    profiles: list[Profile] = ["quintic"]
    duration: float | None = Field(None, gt=0)
    joints: list[int | str] | None = None
    times: list[float] | None = None
    points: list[list[float]] | None = None
    hold: list[float] | None = None
    patterns: list[str | int] | None = None
    velocity: Limit = None
    acceleration: Limit = None
    jerk: Limit = None
    sync: Literal["time", "phase"] = "time"

    @model_validator(mode="after")
    def _one_kind(self):
        p2p, via = self.start is not None or self.goal is not None, self.times is not None
        if p2p == via or (p2p and (self.start is None or self.goal is None)) or \
                (via and self.points is None):
            raise ValueError("expected start and goal (point to point) or times and points "
                             "(via points), found " + (
                                 "both" if p2p and via else "an incomplete case"))
        return self


def _numbers(name: str, text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        return [float(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise InputError(f"--{name}: expected numbers separated by commas, found {text!r}") \
            from None


def _case_document(source: str) -> dict | None:
    """The document of a case file, or None if the source names a robot (a built-in name or
    a robot file: a YAML file without a ``robot`` field)."""
    if not source.endswith((".yaml", ".yml")):
        return None
    if not Path(source).is_file():
        raise InputError(f"case: expected a case file or a robot, found no file {source}")
    document = read_yaml(source)
    return document if isinstance(document, dict) and "robot" in document else None


def load_case(source: str, overrides: dict[str, Any]) -> tuple[CaseFile, bool]:
    """The case from a file (or a robot) with the given options laid over it, and whether it
    came from a case file."""
    document = _case_document(source)
    from_file = document is not None
    where = source if from_file else "command line"
    document = {**document} if from_file else {"robot": source}
    document.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return CaseFile.model_validate(document), from_file
    except ValidationError as err:
        raise validation_error(where, err, CaseFile) from None


def _per_joint(robot: Robot, name: str, value: Limit, default: np.ndarray) -> np.ndarray:
    """A limit per joint in SI from file units (one value for all, or one per joint)."""
    if value is None:
        return default
    v = np.asarray(value, dtype=float).ravel()
    if v.shape not in ((1,), (robot.n,)):
        raise InputError(f"{name}: expected one value or {robot.n} (one per joint), "
                         f"found {v.size}")
    if not (v > 0).all():
        raise InputError(f"{name}: expected positive limits, found {v.tolist()}")
    return robot.q_to_si(np.broadcast_to(v, (robot.n,)))


def _joint_index(robot: Robot, joint: int | str) -> int:
    if isinstance(joint, int) and 1 <= joint <= robot.n:
        return joint - 1
    if isinstance(joint, str) and joint in robot.joint_names:
        return robot.joint_names.index(joint)
    if isinstance(joint, str) and joint.isdigit():
        return _joint_index(robot, int(joint))
    raise InputError(f"joints: expected joint numbers 1..{robot.n} or names "
                     f"({', '.join(robot.joint_names)}), found {joint!r}")


def build(case: CaseFile, robot: Robot) -> tuple[dict[str, tj.Trajectory], list[int]]:
    """The case's trajectories by label (SI) and the joints that move (0-based)."""
    vmax = _per_joint(robot, "velocity", case.velocity, robot.chain.velocity_limits)
    amax = _per_joint(robot, "acceleration", case.acceleration, robot.chain.acceleration_limits)
    jmax = _per_joint(robot, "jerk", case.jerk, np.full(robot.n, np.inf))
    if case.times is None:
        q0, qf = (robot.q_to_si(_joint_vector(robot, name, v))
                  for name, v in (("start", case.start), ("goal", case.goal)))
        out = {}
        for name in dict.fromkeys(case.profiles):
            if name in ("cubic", "quintic"):
                law = tj.cubic if name == "cubic" else tj.quintic
                out[name] = law(q0, qf, case.duration, vmax=vmax, amax=amax, jmax=jmax)
            elif name == "trapezoidal":
                out[name] = tj.trapezoidal(q0, qf, vmax, amax, sync=case.sync)
            else:
                if not np.isfinite(jmax).all():
                    raise InputError("jerk: expected a jerk limit for jerk-limited profiles "
                                     "(robot files carry none), found none")
                out[name] = tj.jerk_limited(q0, qf, vmax, amax, jmax, sync=case.sync)
        return out, [j for j in range(robot.n) if q0[j] != qf[j]]
    joints = [_joint_index(robot, j) for j in (case.joints or range(1, robot.n + 1))]
    if any(len(p) != len(joints) for p in case.points):
        raise InputError(f"points: expected rows of {len(joints)} values (one per joint in "
                         f"joints), found rows of {[len(p) for p in case.points]}")
    points = np.asarray(case.points, dtype=float)
    hold = (robot.q_to_si(_joint_vector(robot, "hold", case.hold)) if case.hold is not None
            else np.clip(0.0, robot.lower, robot.upper))
    q = np.tile(hold, (len(points), 1))
    q[:, joints] = robot.q_to_si(_full(robot, joints, points))[:, joints]
    patterns = case.patterns or (list(tj.PAPER_PATTERNS) if len(points) == 4 else [3, 5])
    return tj.patterns(case.times, q, patterns), joints


def _joint_vector(robot: Robot, name: str, values: list[float]) -> np.ndarray:
    if len(values) != robot.n:
        raise InputError(f"{name}: expected {robot.n} joint values for {robot.name}, "
                         f"found {len(values)}")
    return np.asarray(values, dtype=float)


def _full(robot: Robot, joints: list[int], points: np.ndarray) -> np.ndarray:
    """Points of some joints placed in rows of all joints (file units), so units convert."""
    full = np.zeros((len(points), robot.n))
    full[:, joints] = points
    return full


def _rows(robot: Robot, tr: tj.Trajectory, s: tj.Stats, joints: list[int], units) -> list[dict]:
    """Peaks per joint in `units` (the file's, or SI), with the acceleration steps at the ends."""
    scale = robot.q_from_si(np.ones(robot.n)) if units is not SI else np.ones(robot.n)
    steps = tj.knot_jumps(tr).jump[[0, -1], 2]
    # Rounding leaves steps of 1e-15 where the conditions make them zero.
    steps = np.where(np.abs(steps) > 1e-9 * (1.0 + s.peak_acceleration), steps, 0.0) * scale
    return [{"joint": robot.joint_names[j], "number": j + 1,
             "unit": units.of_joint(robot.chain.revolute[j]),
             "peak_velocity": s.peak_velocity[j] * scale[j],
             "peak_acceleration": s.peak_acceleration[j] * scale[j],
             "peak_jerk": s.peak_jerk[j] * scale[j],
             "squared_jerk": s.squared_jerk[j] * scale[j] ** 2,
             "acceleration_step_at_start": steps[0, j],
             "acceleration_step_at_end": steps[1, j]} for j in joints]


def _fmt(x: float) -> str:
    return f"{x:.4g}"


@app.command(context_settings=NUMBERS)
def traj(
    case: Annotated[str, typer.Argument(help="A trajectory case file (.yaml, see the README), or "
                                             "a robot (built-in name or robot file) with the "
                                             "case given by options.")],
    start: Annotated[str | None, typer.Option(help="Start, all joints, file units, e.g. "
                                                   "--start=0,-90,0,0,0,0.")] = None,
    goal: Annotated[str | None, typer.Option(help="Goal, all joints, file units.")] = None,
    profile: Annotated[list[str] | None, typer.Option(
        help="cubic, quintic, trapezoidal or jerk-limited; repeat to compare "
             "(default quintic).")] = None,
    duration: Annotated[float | None, typer.Option(help="s, for cubic and quintic "
                                                        "(default: shortest in limits).")] = None,
    times: Annotated[str | None, typer.Option(help="Knot times (s), e.g. 0,2,4,5.")] = None,
    point: Annotated[list[str] | None, typer.Option(
        help="Via point (values of --joints, file units); repeat once per knot.")] = None,
    joints: Annotated[str | None, typer.Option(
        help="The joints --point gives, 1-based numbers or names (default all).")] = None,
    hold: Annotated[str | None, typer.Option(help="Where the other joints stay "
                                                  "(all joints, file units; default 0).")] = None,
    pattern: Annotated[list[str] | None, typer.Option(
        help="Degrees per segment, e.g. 4-5-5; repeat to compare (default 3-3-3, 4-5-5, "
             "5-5-5 for three segments).")] = None,
    velocity: Annotated[str | None, typer.Option(help="Velocity limit(s), file units/s.")] = None,
    acceleration: Annotated[str | None, typer.Option(help="Acceleration limit(s), "
                                                          "file units/s^2.")] = None,
    jerk: Annotated[str | None, typer.Option(help="Jerk limit(s), file units/s^3 (needed for "
                                                  "jerk-limited).")] = None,
    sync: Annotated[str | None, typer.Option(help="time (default) or phase (a straight "
                                                  "line in joint space).")] = None,
    out: Annotated[Path, typer.Option(help="Directory for the figures.")] = Path("."),
    as_json: JsonFlag = False,
    si: SiFlag = False,
) -> None:
    """Point-to-point or via-point trajectories: the table of peaks, and their figures."""
    overrides = {"start": _numbers("start", start), "goal": _numbers("goal", goal),
                 "profiles": profile, "duration": duration, "times": _numbers("times", times),
                 "points": [_numbers("point", p) for p in point] if point else None,
                 "joints": joints.replace(",", " ").split() if joints else None,
                 "hold": _numbers("hold", hold), "patterns": pattern, "sync": sync,
                 "velocity": _numbers("velocity", velocity),
                 "acceleration": _numbers("acceleration", acceleration),
                 "jerk": _numbers("jerk", jerk)}
    spec, from_file = load_case(case, overrides)
    out = output_folder(out)
    robot = armkit.robot(spec.robot)
    trajectories, moving = build(spec, robot)
    table = tj.compare(trajectories)
    units = SI if si else robot.units
    stem = Path(case).stem if from_file else f"{robot.name}_traj"
    figures = _figures(robot, trajectories, moving, out, stem, via=spec.times is not None)
    results = [{"label": label, "duration": s.duration, "knots": trajectories[label].knots,
                "joints": _rows(robot, trajectories[label], s, moving, units)}
               for label, s in table.items()]
    if as_json:
        return print_json({"robot": robot.name, "units": {"length": units.length,
                                                          "angle": units.angle},
                           "case": "via points" if spec.times is not None else "point to point",
                           "trajectories": results, "figures": [str(f) for f in figures]})
    _print(robot, results, figures)


def _figures(robot: Robot, trajectories: dict, moving: list[int], out: Path, stem: str,
             via: bool) -> list[Path]:
    # Here, not at the top: matplotlib would slow down every other command's start.
    from armkit.report.trajectory import patterns_figure, tool_figure

    shown = moving or list(range(robot.n))
    title = (f"{robot.name}: joint{'s' if len(shown) > 1 else ''} "
             + ", ".join(str(j + 1) for j in shown) +
             (" through via points at t = " + ", ".join(
                 f"{t:g}" for t in next(iter(trajectories.values())).knots) + " s" if via
              else ", point to point"))
    joints = patterns_figure(robot, trajectories, shown, rows=3 if via else 4, title=title)
    tool = tool_figure(robot, {k: tj.tool_motion(robot, v) for k, v in trajectories.items()})
    paths = [out / f"{stem}_joints.png", out / f"{stem}_tool.png"]
    for fig, path in zip((joints, tool), paths):
        fig.savefig(path, dpi=100)
    return paths


def _print(robot: Robot, results: list[dict], figures: list[Path]) -> None:
    table = Table("trajectory", "joint", "peak |v|", "peak |a|", "peak |j|", "∫j²dt",
                  "a step at ends", box=None, title=f"{robot.name}: peaks per joint",
                  title_justify="left")
    for r in results:
        for i, row in enumerate(r["joints"]):
            table.add_row(f"{r['label']} {_fmt(r['duration'])} s" if i == 0 else "",
                          f"{row['number']} {row['joint']} ({row['unit']})",
                          *(_fmt(row[k]) for k in ("peak_velocity", "peak_acceleration",
                                                   "peak_jerk", "squared_jerk")),
                          f"{_fmt(row['acceleration_step_at_start'])}, "
                          f"{_fmt(row['acceleration_step_at_end'])}")
    stdout.print(table)
    stdout.print("per unit of each joint: v /s, a /s², j /s³, ∫j²dt unit²/s⁵ (steps not "
                 "included)")
    stdout.print("figures: " + ", ".join(str(f) for f in figures))
