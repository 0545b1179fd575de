"""`armkit handeye POSES.yaml`, `armkit calibrate ROBOT MEASUREMENTS.csv`,
`armkit accuracy FILE`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import numpy as np
import typer

import armkit
from armkit.calibration.handeye import METHODS, handeye
from armkit.cli.command import EXIT_FAILED, JsonFlag, app, print_json, stdout
from armkit.cli.robots import RobotArg
from armkit.cli.values import COORDINATE, FIGURE_FORMATS, number, output_path, shown
from armkit.errors import InputError
from armkit.io.handeye import pose_document, read_handeye_poses, write_handeye_result
from armkit.io.measurements import read_accuracy, read_measurements, read_pool
from armkit.io.robot_files import save_robot
from armkit.model import Units


YAML = (".yaml", ".yml")


def _stats(d: np.ndarray, length) -> dict:
    if d.size == 0:
        return {"count": 0, "mean": None, "rms": None, "max": None}
    d = length(d)
    return {"count": int(d.size), "mean": float(d.mean()), "rms": float(np.sqrt(np.mean(d ** 2))),
            "max": float(d.max())}


# --- handeye -------------------------------------------------------------------------------------

@app.command(name="handeye")
def handeye_command(
    poses: Annotated[Path, typer.Argument(help="Hand-eye poses file (YAML).")],
    method: Annotated[str, typer.Option(help=f"One of {', '.join(METHODS)}.")] = "joint",
    out: Annotated[Optional[Path], typer.Option(
        help="Write the result file (YAML) here, for a task file or `frames`.")] = None,
    as_json: JsonFlag = False) -> None:
    """Hand-eye calibration (AX = XB): the camera's mount from pose pairs; exit 1 with the
    reason when the poses cannot determine it."""
    if method not in METHODS:
        raise InputError(f"--method: expected one of {', '.join(METHODS)}, found "
                         f"{shown(method)}")
    if out is not None:
        out = output_path(out, folder=False, formats=YAML)
    data = read_handeye_poses(poses)
    result = handeye(data.robot_poses, data.camera_poses, data.mode, method)
    u = data.units
    deg, length = u.angle_from_si, u.length_from_si
    doc = {"file": str(poses), "units": {"length": u.length, "angle": u.angle},
           "mode": result.mode, "method": result.method, "success": result.success,
           "reason": result.reason, "warning": result.warning,
           "poses": len(data.robot_poses)}
    if result.success:
        frames = ("T_gripper_camera", "T_base_target") if result.mode == "eye_in_hand" else (
            "T_base_camera", "T_gripper_target")
        doc.update({
            "X": {"frame": frames[0], **pose_document(result.X, u)},
            "target": {"frame": frames[1], **pose_document(result.W, u)},
            "std": {"rotation": deg(result.rotation_std),
                    "translation": length(result.translation_std)},
            "residuals": {"rotation": deg(result.rotation_residuals),
                          "translation": length(result.translation_residuals),
                          "rotation_rms": deg(result.rotation_rms),
                          "translation_rms": length(result.translation_rms)},
            "scaled_singular_value": result.scaled_singular_value})
        if out is not None:
            write_handeye_result(result, out, u)
            doc["out"] = str(out)
    if as_json:
        print_json(doc)
    elif not result.success:
        stdout.print(f"refused: {result.reason}")
    else:
        _show_handeye(doc)
    if not result.success:
        raise typer.Exit(EXIT_FAILED)


def _show_handeye(doc: dict) -> None:
    L, A = doc["units"]["length"], doc["units"]["angle"]

    def fmt(values) -> str:
        return " ".join(f"{x:.6g}" for x in values)

    stdout.print(f"hand-eye {doc['mode']} ({doc['method']}), {doc['poses']} pose pairs")
    for key in ("X", "target"):
        stdout.print(f"{doc[key]['frame']}: xyz ({L}) {fmt(doc[key]['xyz'])}   rpy ({A}) "
                     f"{fmt(doc[key]['rpy'])}")
    stdout.print(f"std of X: rotation ({A}) {fmt(doc['std']['rotation'])}   translation ({L}) "
                 f"{fmt(doc['std']['translation'])}")
    r = doc["residuals"]
    stdout.print(f"residuals per pose pair: rotation rms {r['rotation_rms']:.3g} {A}, max "
                 f"{max(r['rotation']):.3g}; translation rms {r['translation_rms']:.3g} {L}, "
                 f"max {max(r['translation']):.3g}")
    stdout.print(f"smallest scaled singular value {doc['scaled_singular_value']:.3g}")
    if doc["warning"]:
        stdout.print(f"warning: {doc['warning']}")
    if "out" in doc:
        stdout.print(f"result written to {doc['out']}")


# --- calibrate -----------------------------------------------------------------------------------

def _file_factor(angular: np.ndarray, u: Units) -> np.ndarray:
    """Per parameter, SI -> file units multiplier (deg per rad, mm per m)."""
    return np.where(angular, float(u.angle_from_si(1.0)), float(u.length_from_si(1.0)))


@app.command(name="calibrate")
def calibrate_command(
    robot: RobotArg,
    measurements: Annotated[Path, typer.Argument(help="Measurements file (CSV): joint values "
                                                      "and measured tool positions.")],
    select: Annotated[Optional[int], typer.Option(
        "--select", metavar="N", help="Choose N configurations (D-optimal): from --pool, or "
                                      "else from the measurements (the rest is held out).")]
    = None,
    pool: Annotated[Optional[Path], typer.Option(
        help="Candidate configurations (CSV) for --select: the plan of what to measure.")] = None,
    holdout: Annotated[Optional[int], typer.Option(
        help="Measurements held out to test the result (default: every 4th, from 8 "
             "measurements on; 0 for none).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        help="Write the identified robot file (YAML) here, and its residual figure beside "
             "it (.png).")] = None,
    as_json: JsonFlag = False) -> None:
    """Kinematic calibration: the robot's table, base and tool from measured tool positions."""
    from armkit.calibration.identify import calibrate, select_poses

    model = armkit.robot(robot)
    if out is not None:
        out = output_path(out, folder=False, formats=YAML,
                          files=(Path(out).with_suffix(".png").name,))
    if pool is not None and select is None:
        raise InputError("--pool: expected with --select N (the number to choose), found "
                         "no --select")
    data = read_measurements(measurements, model)
    m = len(data.q)
    fit = np.arange(m)
    plan = None
    if select is not None and pool is not None:
        candidates = read_pool(pool, model)
        if not 1 <= select <= len(candidates):
            raise InputError(f"--select: expected 1 .. {len(candidates)} (the pool's size), "
                             f"found {select}")
        plan = select_poses(model, candidates, select)
        plan_q = candidates[plan]
    elif select is not None:
        if not 1 <= select <= m:
            raise InputError(f"--select: expected 1 .. {m} (the measurements), found {select}")
        fit = np.sort(select_poses(model, data.q, select))
    if holdout is not None and not 0 <= holdout < m:
        raise InputError(f"--holdout: expected 0 .. {m - 1}, found {holdout}")
    if select is not None and pool is None:
        held = np.setdiff1d(np.arange(m), fit)
    elif holdout is not None:
        held = np.arange(m - holdout, m)
    else:
        held = np.arange(3, m, 4) if m >= 8 else np.arange(0)
    fit = np.setdiff1d(fit, held)
    result = calibrate(model, data.q[fit], data.measured[fit],
                       holdout=(data.q[held], data.measured[held]) if held.size else None)
    u = model.units
    length = u.length_from_si
    factor = _file_factor(result.angular, u)
    unit = np.where(result.angular, u.angle, u.length)
    doc = {"robot": model.name, "measurements": m, "fitted": len(fit), "held_out": len(held),
           "units": {"length": u.length, "angle": u.angle}, "success": result.success,
           "reason": result.reason,
           "parameters": [{"name": n, "unit": str(un), "nominal": float(a * f),
                           "identified": float(b * f), "std": float(s * f),
                           "identifiable": bool(ok)}
                          for n, un, a, b, s, f, ok in zip(
                              result.names, unit, result.nominal, result.identified,
                              result.std, factor, result.identifiable)],
           "unidentifiable": {n: {o: c * factor[result.names.index(o)]
                                  / factor[result.names.index(n)] for o, c in comb.items()}
                              for n, comb in result.dependencies.items()},
           "added_at_fit": result.added,
           "residuals_before": _stats(result.residuals_before, length),
           "residuals_after": _stats(result.residuals_after, length),
           "holdout_before": _stats(result.holdout_before, length),
           "holdout_after": _stats(result.holdout_after, length),
           "condition_number": result.condition_number, "o1": result.o1,
           "iterations": result.iterations}
    if plan is not None:
        doc["selected"] = {"pool": str(pool), "rows": plan,
                           "q": model.q_from_si(plan_q)}
    if out is not None:
        from armkit.report.calibration import calibration_figure, save_figure

        save_robot(result.robot, out)
        doc["out"] = str(out)
        doc["figure"] = str(save_figure(calibration_figure(result, u), out.with_suffix(".png")))
    if as_json:
        print_json(doc)
    else:
        _show_calibration(doc, model)
    if not result.success:
        raise typer.Exit(EXIT_FAILED)


def _show_calibration(doc: dict, model) -> None:
    from armkit.calibration.identify import dependency_text

    L = doc["units"]["length"]
    stdout.print(f"{doc['robot']}: {doc['fitted']} measurements fitted, {doc['held_out']} "
                 f"held out")
    stdout.print("identified parameters (file units):")
    for p in doc["parameters"]:
        if p["identifiable"]:
            stdout.print(f"  {p['name']:<18} {p['nominal']:>12.6g} -> {p['identified']:<14.9g} "
                         f"± {p['std']:.2g} {p['unit']}")
    if doc["added_at_fit"]:
        stdout.print("held by the analysis at nominal, identified at the fitted values "
                     "(significance, standard deviations of the noise):")
        for name, z in doc["added_at_fit"].items():
            stdout.print(f"  {name} ({z:.3g})")
    stdout.print("held at nominal (not identifiable from these measurements):")
    for name, comb in doc["unidentifiable"].items():
        stdout.print(f"  {dependency_text(name, comb)}")
    for key, label in (("residuals", "fit set"), ("holdout", "hold-out")):
        b, a = doc[f"{key}_before"], doc[f"{key}_after"]
        if b["count"]:
            stdout.print(f"{label} error ({L}): mean {b['mean']:.4g} -> {a['mean']:.4g}, rms "
                         f"{b['rms']:.4g} -> {a['rms']:.4g}, max {b['max']:.4g} -> "
                         f"{a['max']:.4g}")
    stdout.print(f"condition number {doc['condition_number']:.4g}, O1 {doc['o1']:.4g}")
    if "selected" in doc:
        stdout.print(f"measure next (rows of {doc['selected']['pool']}, D-optimal): "
                     + " ".join(str(r) for r in doc["selected"]["rows"]))
    if "out" in doc:
        stdout.print(f"identified robot written to {doc['out']}, figure {doc['figure']}")


# --- accuracy ------------------------------------------------------------------------------------

@app.command(name="accuracy")
def accuracy_command(
    file: Annotated[Path, typer.Argument(help="Accuracy experiment (CSV): commanded and "
                                              "measured positions.")],
    tolerance: Annotated[Optional[float], typer.Option(
        help="Limit on every point's error, file units; exit 1 if a point exceeds it.",
        parser=number(0.0, COORDINATE, low_open=True))] = None,
    out: Annotated[Optional[Path], typer.Option(help="Write the figure (PNG) here.")] = None,
    as_json: JsonFlag = False) -> None:
    """Commanded against measured positions: error per point, mean, max, rms, bias per axis."""
    from armkit.calibration.accuracy import accuracy_report

    if out is not None:
        out = output_path(out, folder=False, formats=FIGURE_FORMATS)
    data = read_accuracy(file)
    u = data.units
    report = accuracy_report(data.commanded, data.measured,
                      None if tolerance is None else float(u.length_to_si(tolerance)))
    def length(x):          # file units, without the last-bit noise of the mm <-> m round trip
        return np.round(u.length_from_si(x), 9)

    doc = {"file": str(file), "units": {"length": u.length}, "points": len(report.distances),
           "errors": length(report.errors), "distances": length(report.distances),
           "mean": float(length(report.mean)), "max": float(length(report.max)),
           "rms": float(length(report.rms)), "bias": length(report.bias),
           "std": length(report.std), "tolerance": tolerance, "within": report.within}
    if out is not None:
        from armkit.report.calibration import accuracy_figure, save_figure

        doc["figure"] = str(save_figure(accuracy_figure(report, u), out))
    if as_json:
        print_json(doc)
    else:
        L = u.length
        stdout.print(f"{doc['points']} points ({L}):")
        for k, (e, d) in enumerate(zip(doc["errors"], doc["distances"]), start=1):
            stdout.print(f"  {k}: error {e[0]:+.4g} {e[1]:+.4g} {e[2]:+.4g}   |e| {d:.4g}")
        stdout.print(f"mean {doc['mean']:.4g}, max {doc['max']:.4g}, rms {doc['rms']:.4g} {L}")
        stdout.print("bias per axis (x y z): " + " ".join(f"{b:+.4g}" for b in doc["bias"])
                     + f" {L}")
        if tolerance is not None:
            stdout.print(("all within " if report.within else "NOT all within ")
                         + f"{tolerance:g} {L}")
        if "figure" in doc:
            stdout.print(f"figure written to {doc['figure']}")
    if report.within is False:
        raise typer.Exit(EXIT_FAILED)
