"""`armkit handeye`, `armkit calibrate`, `armkit accuracy`, run as users run them."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import armkit
from armkit.io.camera import read_camera_mount
from armkit.io.measurements import read_measurements
from armkit.spatial import invert
from tests.calibration.synthetic import handeye_data

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

EXAMPLES = Path(__file__).parents[2] / "examples" / "calibration"


def armkit_cli(*args):
    return subprocess.run([sys.executable, "-m", "armkit", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def _bad_input(run, *words):
    assert run.returncode == 2, run.stdout + run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in run.stderr, run.stderr
    for w in words:
        assert w in lines[0], lines[0]


def test_handeye_json_and_result_file(tmp_path):
    out = tmp_path / "handeye.yaml"
    run = armkit_cli("handeye", EXAMPLES / "handeye_poses.yaml", "--json", "--out", out)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["success"] and doc["units"] == {"length": "mm", "angle": "deg"}
    assert doc["X"]["frame"] == "T_gripper_camera"
    assert np.abs(np.array(doc["X"]["xyz"]) - [40, -25, 90]).max() < 1.5
    assert len(doc["residuals"]["rotation"]) == 12 and doc["residuals"]["rotation_rms"] < 0.5
    mount = read_camera_mount(out)
    assert mount.kind == "eye_in_hand"
    assert np.allclose(mount.T[:3, 3] * 1000, doc["X"]["xyz"])


def test_handeye_text_and_methods():
    run = armkit_cli("handeye", EXAMPLES / "handeye_poses.yaml", "--method", "tsai")
    assert run.returncode == 0, run.stderr
    assert "hand-eye eye_in_hand (tsai), 12 pose pairs" in run.stdout
    assert "T_gripper_camera: xyz (mm)" in run.stdout and "residuals per pose pair" in run.stdout


def _poses_file(tmp_path, G, C):
    doc = {"units": {"length": "m", "angle": "rad"}, "mode": "eye_in_hand",
           "poses": [{"gripper": {"matrix": g.tolist()}, "camera": {"matrix": c.tolist()}}
                     for g, c in zip(G, C)]}
    path = tmp_path / "poses.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return path


def test_handeye_refusals_exit_1_with_the_reason(tmp_path):
    G, C, _, _ = handeye_data(8, seed=3, axis=[0, 0, 1])
    run = armkit_cli("handeye", _poses_file(tmp_path, G, C))
    assert run.returncode == 1 and run.stdout.startswith("refused: rotations about one axis")
    G, C, _, _ = handeye_data(8, seed=3, noise_rotation=0.001)
    run = armkit_cli("handeye", _poses_file(tmp_path, invert(G), C), "--json")
    doc = json.loads(run.stdout)
    assert run.returncode == 1 and not doc["success"]
    assert "check the pose convention" in doc["reason"] and "X" not in doc


def test_handeye_bad_input(tmp_path):
    _bad_input(armkit_cli("handeye", tmp_path / "none.yaml"), "none.yaml", "a readable file")
    G, C, _, _ = handeye_data(2, seed=3)
    _bad_input(armkit_cli("handeye", _poses_file(tmp_path, G, C)),
               "robot_poses: expected at least 3 pose pairs", "found 2")
    _bad_input(armkit_cli("handeye", EXAMPLES / "handeye_poses.yaml", "--method", "best"),
               "--method: expected one of tsai, park, horaud, pairs, joint, found 'best'")
    _bad_input(armkit_cli("handeye", EXAMPLES / "handeye_poses.yaml", "--out",
                          tmp_path / "no" / "r.yaml"), "--out: expected a file in an existing "
                                                        "folder")
    bad = tmp_path / "bad.yaml"
    bad.write_text("units: {length: mm, angle: deg}\nmode: eye_in_hand\nposes: []\n",
                   encoding="utf-8")
    _bad_input(armkit_cli("handeye", bad), "bad.yaml: poses: expected at least 1 item(s), "
                                           "found 0")


def test_calibrate_json_and_identified_robot(tmp_path):
    out = tmp_path / "ws_calibrated.yaml"
    measurements = EXAMPLES / "water_supply_measurements.csv"
    run = armkit_cli("calibrate", "water_supply", measurements, "--json", "--out", out)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["measurements"] == 20 and doc["held_out"] == 5 and doc["fitted"] == 15
    assert doc["holdout_after"]["mean"] < 0.25 < 2 < doc["holdout_before"]["mean"]
    assert doc["residuals_after"]["rms"] < 0.15
    names = {p["name"]: p for p in doc["parameters"]}
    assert names["base.d"]["identifiable"] and not names["lift.d"]["identifiable"]
    assert doc["unidentifiable"]["lift.d"] == pytest.approx({"base.d": 1.0})
    assert doc["unidentifiable"]["swing3.theta"] == {}
    assert names["swing2.a"]["identified"] == pytest.approx(760 - 1.4, abs=0.1)
    assert doc["condition_number"] > 1 and doc["o1"] > 0
    # The identified robot file loads and reproduces the measurements (to their noise).
    robot = armkit.load_robot(out)
    data = read_measurements(measurements, robot)
    error = np.linalg.norm(armkit.fk(robot, data.q)[:, :3, 3] - data.measured, axis=-1)
    assert error.max() < 0.3e-3
    assert Path(doc["figure"]).read_bytes()[:4] == b"\x89PNG"


def test_calibrate_text_and_selection(tmp_path):
    measurements = EXAMPLES / "water_supply_measurements.csv"
    run = armkit_cli("calibrate", "water_supply", measurements, "--select", "12")
    assert run.returncode == 0, run.stderr
    assert "12 measurements fitted, 8 held out" in run.stdout
    assert "lift.d: moves the tool as 1*base.d does" in run.stdout
    assert "swing3.theta: has no effect on the measurements" in run.stdout
    run = armkit_cli("calibrate", "water_supply", measurements, "--select", "6", "--pool",
                     EXAMPLES / "water_supply_pool.csv", "--json", "--holdout", "0")
    doc = json.loads(run.stdout)
    assert run.returncode == 0 and len(doc["selected"]["rows"]) == 6
    assert len(set(doc["selected"]["rows"])) == 6 and np.shape(doc["selected"]["q"]) == (6, 4)
    assert doc["held_out"] == 0 and doc["holdout_before"]["count"] == 0


def test_calibrate_bad_input(tmp_path):
    measurements = EXAMPLES / "water_supply_measurements.csv"
    _bad_input(armkit_cli("calibrate", "water_supply", measurements, "--pool",
                          EXAMPLES / "water_supply_pool.csv"), "--pool: expected with --select")
    _bad_input(armkit_cli("calibrate", "water_supply", measurements, "--select", "21"),
               "--select: expected 1 .. 20 (the measurements), found 21")
    _bad_input(armkit_cli("calibrate", "water_supply", measurements, "--holdout", "20"),
               "--holdout: expected 0 .. 19, found 20")
    _bad_input(armkit_cli("calibrate", "ur5", measurements), "header: expected the joints of ur5")
    _bad_input(armkit_cli("calibrate", "water_suply", measurements), "did you mean "
                                                                     "'water_supply'")
    bad = tmp_path / "bad.csv"
    bad.write_text("q1,q2,q3,q4,x,y,z\n1,2,3,4,5,6\n", encoding="utf-8")
    _bad_input(armkit_cli("calibrate", "water_supply", bad), "bad.csv: line 2: expected 7 "
                                                             "values")


def test_accuracy(tmp_path):
    example = EXAMPLES / "inspection_6dof_accuracy.csv"
    figure = tmp_path / "accuracy.png"
    run = armkit_cli("accuracy", example, "--tolerance", "10", "--json", "--out", figure)
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["within"] is True and doc["max"] == pytest.approx(np.sqrt(98))
    assert doc["bias"] == pytest.approx([0.2, -1.4, 0.0])
    assert figure.read_bytes()[:4] == b"\x89PNG"
    run = armkit_cli("accuracy", example, "--tolerance", "9")
    assert run.returncode == 1 and "NOT all within 9 mm" in run.stdout
    run = armkit_cli("accuracy", example)
    assert run.returncode == 0 and "mean 7.079, max 9.899, rms 7.239 mm" in run.stdout


def test_accuracy_bad_input(tmp_path):
    example = EXAMPLES / "inspection_6dof_accuracy.csv"
    _bad_input(armkit_cli("accuracy", example, "--tolerance", "-1"),
               "--tolerance: expected a number above 0 and at most 1e+09, found -1")
    _bad_input(armkit_cli("accuracy", tmp_path / "missing.csv"), "missing.csv",
               "expected a readable file")
    bad = tmp_path / "bad.csv"
    bad.write_text("# units: mm\ncommanded_x,commanded_y\n1,2\n", encoding="utf-8")
    _bad_input(armkit_cli("accuracy", bad), "bad.csv: header: expected the columns")


def test_calibrate_names_what_the_second_pass_adds(tmp_path):
    """UR5 with every parameter off nominal, noise-free: the parameters that only look
    dependent at nominal are listed as identified at the fitted values, in JSON and text."""
    from armkit.calibration.identify import identified_robot, parametric_model

    robot = armkit.robot("ur5")
    model = parametric_model(robot)
    rng = np.random.default_rng(2)
    truth = model.nominal + np.where(model.angular, np.deg2rad(0.2), 5e-4) * rng.normal(
        size=len(model.names))
    q = rng.uniform(-np.pi, np.pi, (120, 6))
    p = armkit.fk(identified_robot(model, truth), q)[:, :3, 3]
    path = tmp_path / "ur5_measurements.csv"
    rows = [",".join(f"{v:.12g}" for v in (*np.rad2deg(qi), *pi)) for qi, pi in zip(q, p)]
    path.write_text("# units: m deg\nshoulder_pan,shoulder_lift,elbow,wrist1,wrist2,wrist3,x,y,z\n"
                    + "\n".join(rows) + "\n")
    run = armkit_cli("calibrate", "ur5", path, "--json")
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert len(doc["added_at_fit"]) == 2
    assert all(n.startswith("wrist2.") and n not in doc["unidentifiable"]
               for n in doc["added_at_fit"])
    assert doc["holdout_after"]["max"] < 1e-7
    run = armkit_cli("calibrate", "ur5", path)
    assert run.returncode == 0, run.stderr
    assert "identified at the fitted values" in run.stdout
    assert all(f"  {n} (" in run.stdout for n in doc["added_at_fit"])
