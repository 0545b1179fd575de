"""`armkit detect`: the example scan end to end in a subprocess, JSON in the file's units, the
base frame, the picture, "no target" as exit 1, and every bad argument as one line and exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from armkit.cli import app
from armkit.io.clouds import read_cloud, write_pcd
from armkit.calibration import camera_to_base
from armkit.io.camera import read_camera_mount
from armkit.perception import detect_target, synthetic_scene

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

EXAMPLES = Path(__file__).parents[2] / "examples" / "perception"
SCAN, POSE = str(EXAMPLES / "inlet_scan.pcd"), str(EXAMPLES / "sensor_to_base.yaml")
runner = CliRunner()


def armkit(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "armkit", *args], capture_output=True,
                          text=True, timeout=120)


def test_example_scan_json_in_millimetres_with_base_frame_and_picture(tmp_path):
    done = armkit("detect", SCAN, "--sensor-to-base", POSE, "--radius", "40", "--json",
                  "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    expected = detect_target(read_cloud(SCAN), radius=0.04,
                             T_base_sensor=camera_to_base(read_camera_mount(POSE)))
    assert doc["success"] and doc["units"] == "mm" and doc["radius"] == pytest.approx(40)
    np.testing.assert_allclose(doc["sensor"]["position"], expected.centre * 1000, atol=1e-9)
    np.testing.assert_allclose(doc["base"]["position"], expected.T_base_target[:3, 3] * 1000,
                               atol=1e-9)
    np.testing.assert_allclose(doc["base"]["axis"], expected.T_base_target[:3, 2], atol=1e-12)
    # The example's truth (synthetic_scene, seed 18): the pipe's mouth at this point, in mm.
    np.testing.assert_allclose(doc["sensor"]["position"], [1295.2366, -14.2972, -28.6395],
                               atol=0.5)
    assert doc["quality"]["cluster_size"] > 50 and doc["quality"]["fit_rms"] < 2
    with open(doc["figure"], "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_text_output_and_no_target_exit_1(tmp_path):
    done = armkit("detect", SCAN)
    assert done.returncode == 0 and "pipe in the sensor frame: centre (1295" in done.stdout
    wall = synthetic_scene("hole", radius=0.001, depth=None, n_points=3000, seed=2)
    path = write_pcd(tmp_path / "wall.pcd", wall.points, "m")
    done = armkit("detect", str(path), "--json", "--out", str(tmp_path))
    assert done.returncode == 1 and done.stderr == ""
    doc = json.loads(done.stdout)
    assert doc["success"] is False and "off the wall" in doc["reason"] and doc["sensor"] is None
    assert (tmp_path / "wall_detection.png").exists()


@pytest.mark.parametrize("args, message", [
    (["missing.pcd"], "missing.pcd: expected a readable file"),
    (["{bad}"], "bad.pcd: expected a PCD file (starting with #, VERSION or FIELDS), found "),
    (["{npy}"], "a.npy: units: expected a length unit, m or mm, declared in the file or given"),
    (["{npy}", "--units", "cm"], "--units: expected one of m, mm, found 'cm'"),
    (["{npy}", "--units", "mm"], "a.npy: points: expected a scene at least 5 cm across"),
    ([SCAN, "--units", "m"], "inlet_scan.pcd: units: expected m as given by the caller, found "
                             "the file declares mm"),
    ([SCAN, "--kind", "slot"], "--kind: expected one of pipe, hole, found 'slot'"),
    ([SCAN, "--choose", "first"], "--choose: expected one of largest, nearest, highest, found"),
    ([SCAN, "--nonfinite", "keep"], "--nonfinite: expected one of drop, refuse, found 'keep'"),
    ([SCAN, "--radius", "-4"], "--radius: expected a number above 0 and at most 1e+09 (the "
                               "cloud's units), found -4"),
    ([SCAN, "--radius", "nan"], "--radius: expected a finite number above 0"),
    ([SCAN, "--radius", "1e300"], "--radius: expected a number above 0 and at most 1e+09"),
    ([SCAN, "--radius", "2e6"], "--radius: expected a length of at most 1000 m (1e+06 mm), "
                                "found 2e+06 mm"),
    ([SCAN, "--radius", "4cm"], "--radius: expected a number above 0 and at most 1e+09 (the "
                                "cloud's units), found '4cm'"),
    ([SCAN, "--eps", "0"], "--eps: expected a number above 0 and at most 1e+09 (the cloud's "
                           "units), found 0"),
    ([SCAN, "--eps", "x"], "--eps: expected a number above 0 and at most 1e+09 (the cloud's "
                           "units), found 'x'"),
    ([SCAN, "--out", "{file}"], "--out: expected a folder armkit can write, found "),
    ([SCAN, "--sensor-to-base", "{tf}"], "tf.yaml: units: expected a value, found nothing"),
    (["{nan}", "--units", "m", "--nonfinite", "refuse"], "n.npy: points: expected finite coordinates, found 1 "
                                         "point(s) with NaN or inf, the first at index 0"),
])
def test_bad_input_one_line_exit_2(tmp_path, args, message):
    (tmp_path / "bad.pcd").write_bytes(b"\x89PNG\r\n\x1a\n")
    np.save(tmp_path / "a.npy", synthetic_scene(n_points=500).points)
    nan = synthetic_scene(n_points=500).points
    nan[0, 0] = np.nan
    np.save(tmp_path / "n.npy", nan)
    (tmp_path / "tf.yaml").write_text("camera_to_base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}\n")
    (tmp_path / "plain").write_text("a file, not a folder")
    files = {"{bad}": tmp_path / "bad.pcd", "{npy}": tmp_path / "a.npy",
             "{file}": tmp_path / "plain" / "sub",
             "{tf}": tmp_path / "tf.yaml", "{nan}": tmp_path / "n.npy"}
    files["missing.pcd"] = tmp_path / "missing.pcd"
    args = [str(files[a]) if a in files else a for a in args]
    result = runner.invoke(app, ["detect", *args])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and result.stdout == ""


def test_eps_in_the_clouds_units_for_a_ring_scan(tmp_path):
    scene = synthetic_scene(noise=0.002, n_points=20_000, rings=24, seed=3)
    path = write_pcd(tmp_path / "rings.pcd", scene.points, "mm")
    result = runner.invoke(app, ["detect", str(path), "--radius", "40", "--eps", "40",
                                 "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    truth = scene.T_sensor_target[:3, 3] * 1000
    axis = scene.T_sensor_target[:3, 2]
    d = np.array(doc["sensor"]["position"]) - truth
    assert np.linalg.norm(d - (d @ axis) * axis) < 1.5                 # mm, off the axis


def test_bad_input_in_a_subprocess(tmp_path):
    (tmp_path / "bad.ply").write_text("not a cloud\n")
    done = armkit("detect", str(tmp_path / "bad.ply"), "--units", "mm")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().count("\n") == 0
    assert "bad.ply: expected a PLY file (starting with ply), found b'not a cloud" in done.stderr
    assert "Traceback" not in done.stderr
