"""`armkit detect CLOUD`: the water inlet in a point cloud, in the sensor and base frames."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.text import Text

from armkit.cli.command import EXIT_FAILED, JsonFlag, app, output_folder, print_json, stdout
from armkit.cli.values import COORDINATE, check_number, shown
from armkit.errors import InputError
from armkit.spatial import matrix_to_rpy

_CHOICES = {"--units": ("m", "mm"), "--kind": ("pipe", "hole"),
            "--nonfinite": ("drop", "refuse"), "--choose": ("largest", "nearest", "highest")}


def _one_of(name: str, value: str) -> str:
    allowed = _CHOICES[name]
    if value not in allowed:
        raise InputError(f"{name}: expected one of {', '.join(allowed)}, found {shown(value)}")
    return value


def _length(name: str, text: str | None) -> float | None:
    """An option's length in the cloud's units, or None: above 0 and at most 1e9 (checked
    against 1000 m once the units are known)."""
    if text is None:
        return None
    return check_number(name, text, 0.0, COORDINATE, low_open=True, unit="(the cloud's units)")


def _pose(T: np.ndarray, k: float) -> dict:
    """A pose as the CLI prints it: position in the file's length unit, axis, rpy in deg."""
    M = T.copy()
    M[:3, 3] *= k
    rpy = matrix_to_rpy(T[:3, :3], degrees=True)
    rpy[np.abs(rpy) < 1e-9] = 0.0           # rounding dust, e.g. 1e-14 deg of pitch
    return {"position": M[:3, 3], "axis": T[:3, 2], "rpy_deg": rpy, "matrix": M}


def _candidate(c, k: float) -> dict:
    """A weighed candidate as the JSON shows it, lengths in the file's units."""
    return {"kind": c.kind, "size": c.size, "centre": c.centre * k,
            "centroid": c.centroid * k, "radius": c.radius * k,
            "fit_rms": c.fit_rms * k, "rms_limit": c.rms_limit * k,
            "arc_deg": np.degrees(c.coverage), "standoff": c.standoff * k,
            "passed": c.passed, "reason": c.reason}


@app.command()
def detect(cloud: Annotated[Path, typer.Argument(help="Cloud file: .pcd, .ply, .csv, .xyz, "
                                                       ".txt or .npy.")],
           sensor_to_base: Annotated[Path | None, typer.Option(
               "--sensor-to-base", help="The sensor's pose in the robot's base frame: a "
                                        "camera-to-base file (units, camera_to_base: xyz/rpy "
                                        "or a matrix) or an eye-to-hand hand-eye result.")]
           = None,
           units: Annotated[str | None, typer.Option(
               help="The cloud's length unit, m or mm (needed unless the file declares it).")]
           = None,
           kind: Annotated[str, typer.Option(help="pipe or hole.")] = "pipe",
           radius: Annotated[str | None, typer.Option(
               help="Known inlet radius, in the cloud's units (default: fitted).")] = None,
           eps: Annotated[str | None, typer.Option(
               help="Clustering radius in the cloud's units (default: 4 x the wall's point "
                    "spacing; give it for ring scans whose rings lie farther apart).")] = None,
           nonfinite: Annotated[str, typer.Option(
               help="Points with NaN or inf: drop (and count) or refuse.")] = "drop",
           choose: Annotated[str, typer.Option(
               help="Rule for the target cluster: largest, nearest or highest.")] = "largest",
           out: Annotated[Path | None, typer.Option(
               help="Folder for the picture (cloud, wall, cluster, circle).")] = None,
           as_json: JsonFlag = False) -> None:
    """The inlet's centre and axis found in a scan of the train's side."""
    from armkit.io.clouds import UNITS, read_cloud
    from armkit.calibration import camera_to_base
    from armkit.io.camera import read_camera_mount
    from armkit.perception import detect_target

    if units is not None:
        _one_of("--units", units)
    # Parsed here, not by typer: a bad value is then one line like every other bad input.
    radius_value, eps_value = _length("--radius", radius), _length("--eps", eps)
    _one_of("--kind", kind)
    _one_of("--nonfinite", nonfinite)
    _one_of("--choose", choose)
    folder = (output_folder(out, files=(f"{cloud.stem}_detection.png",))
              if out is not None else None)
    T_base_sensor = (None if sensor_to_base is None else
                     camera_to_base(read_camera_mount(sensor_to_base)))
    data = read_cloud(cloud, units, nonfinite=nonfinite)
    k = 1.0 / UNITS[data.file_units]
    for name, value in (("--radius", radius_value), ("--eps", eps_value)):
        if value is not None and value / k > 1000.0:
            raise InputError(f"{name}: expected a length of at most 1000 m ({1000 * k:g} "
                             f"{data.file_units}), found {value:g} {data.file_units}")
    result = detect_target(data, kind=kind, choose=choose,
                           radius=None if radius_value is None else radius_value / k,
                           eps=None if eps_value is None else eps_value / k,
                           T_base_sensor=T_base_sensor)
    figure = None
    if folder is not None:
        from armkit.report.perception import save_detection_figure
        figure = save_detection_figure(result, folder, f"{cloud.stem}_detection")
    quality = {"points": len(result.points), "dropped": result.dropped,
               "plane_inliers": result.plane_inliers, "plane_rms": result.plane_rms * k,
               "candidates": result.candidates, "clusters": result.clusters,
               "cluster_size": result.cluster_size, "fit_points": result.fit_points,
               "fit_rms": result.fit_rms * k, "arc_deg": np.degrees(result.coverage)}
    scan = {"range_noise": result.range_noise * k, "plane_band": result.plane_band * k,
            "eps": result.eps * k, "rows": result.rows}
    considered = [_candidate(c, k) for c in result.considered]
    if as_json:
        print_json({
            "success": result.success, "reason": result.reason, "kind": result.kind,
            "cloud": str(cloud), "units": data.file_units,
            "sensor": _pose(result.T_sensor_target, k) if result.success else None,
            "base": (_pose(result.T_base_target, k)
                     if result.success and result.T_base_target is not None else None),
            "radius": result.radius * k, "radius_known": result.radius_known,
            "centroid_sensor": result.centroid * k, "quality": quality, "scan": scan,
            "rule": result.rule, "considered": considered,
            "figure": None if figure is None else str(figure)})
    else:
        u = data.file_units
        stdout.print(Text.assemble(
            (str(cloud), "bold"), f": {len(result.points):,} points ({u})"
            + (f", {result.dropped:,} with NaN or inf dropped" if result.dropped else "")))
        if result.success:
            for frame, T in (("sensor", result.T_sensor_target), ("base", result.T_base_target)):
                if T is None:
                    continue
                pose = _pose(T, k)
                stdout.print(f"{result.kind} in the {frame} frame: centre ("
                             + ", ".join(f"{x:.6g}" for x in pose["position"])
                             + f") {u}, axis (" + ", ".join(f"{x:.6f}" for x in pose["axis"])
                             + "), rpy (" + ", ".join(f"{x:.4g}" for x in pose["rpy_deg"])
                             + ") deg")
            stdout.print(f"radius {result.radius * k:.5g} {u}"
                         + (" (known)" if result.radius_known else " (fitted)")
                         + f"; fit RMS {quality['fit_rms']:.3g} {u} over "
                         f"{result.fit_points} points, arc {quality['arc_deg']:.0f} deg")
            stdout.print(f"chosen: {result.rule}")
        else:
            stdout.print(f"no target: {result.reason}")
        stdout.print(f"wall: {result.plane_inliers:,} inliers, RMS {quality['plane_rms']:.3g} "
                     f"{u}; {result.candidates:,} candidates off the wall, "
                     f"{result.clusters} cluster(s), target cluster {result.cluster_size:,} "
                     "points")
        stdout.print(f"scan: range noise {scan['range_noise']:.3g} {u}, wall band "
                     f"+-{scan['plane_band']:.3g} {u}, "
                     + (f"{result.rows} rows" if result.rows else "no rows")
                     + (f", clustering radius {scan['eps']:.3g} {u}"
                        if np.isfinite(scan["eps"]) else ""))
        if figure is not None:
            stdout.print(f"figure:  {figure}")
    if not result.success:
        raise typer.Exit(EXIT_FAILED)
