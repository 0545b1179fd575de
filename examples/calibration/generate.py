"""Writes the calibration examples of this folder from seeded simulated measurements.

    python examples/calibration/generate.py

handeye_poses.yaml: an eye-in-hand camera on a 6-axis arm, 12 pose pairs with 0.1 deg and
0.5 mm of noise on the camera's target poses (the true X: xyz 40 -25 90 mm, rpy 5 -3 92 deg).
water_supply_measurements.csv: 20 tool positions of a water-supply arm whose table is off the
nominal one by a few mm and tenths of a degree, with 0.05 mm of noise;
water_supply_pool.csv: 200 candidate configurations to choose measurements from.
"""

from pathlib import Path

import numpy as np
import yaml

import armkit
from armkit.calibration.identify import identified_robot, parametric_model
from armkit.spatial import invert, matrix_to_rpy, pose_from_xyz_rpy

HERE = Path(__file__).parent
rng = np.random.default_rng(2024)


def pose_doc(T):
    return {"xyz": [round(float(v), 4) for v in T[:3, 3] * 1000],
            "rpy": [round(float(v), 5) for v in np.rad2deg(matrix_to_rpy(T[:3, :3]))]}


# --- hand-eye ---------------------------------------------------------------------------------
X = pose_from_xyz_rpy([0.040, -0.025, 0.090], [5, -3, 92], degrees=True)
W = pose_from_xyz_rpy([0.9, 0.1, 0.0], [0, 0, 0], degrees=True)
arm = armkit.robot("inspection_6dof")
pairs = []
while len(pairs) < 12:
    q = rng.uniform(np.deg2rad(-60), np.deg2rad(60), 6)
    G = armkit.fk(arm, q)
    C = invert(G @ X) @ W
    if not 0.2 < C[2, 3] < 1.5:          # the target in front of the camera
        continue
    noise = pose_from_xyz_rpy(rng.normal(0, 0.0005, 3), rng.normal(0, np.deg2rad(0.1), 3))
    pairs.append({"gripper": pose_doc(G), "camera": pose_doc(C @ noise)})
document = {"units": {"length": "mm", "angle": "deg"}, "mode": "eye_in_hand",
            "convention": {"gripper": "gripper_to_base", "camera": "target_to_camera"},
            "poses": pairs}
(HERE / "handeye_poses.yaml").write_text(
    "# Simulated eye-in-hand calibration; written by generate.py.\n"
    + yaml.safe_dump(document, sort_keys=False, default_flow_style=None), encoding="utf-8")

# --- kinematic calibration --------------------------------------------------------------------
robot = armkit.robot("water_supply")
model = parametric_model(robot)
true = model.nominal.copy()
offsets = {"swing1.a": 0.0021, "swing2.a": -0.0014, "swing3.a": 0.0009, "base.d": 0.003,
           "swing1.theta": np.deg2rad(0.3), "swing2.theta": np.deg2rad(-0.2),
           "lift.alpha": np.deg2rad(0.05), "swing2.alpha": np.deg2rad(-0.04)}
for name, delta in offsets.items():
    true[model.names.index(name)] += delta
actual = identified_robot(model, true)


def joints(n):
    return rng.uniform(robot.lower, robot.upper, (n, robot.n))


def write_csv(path, q, p=None, comment=""):
    header = ",".join(robot.joint_names + (("x", "y", "z") if p is not None else ()))
    lines = [f"# {comment}", "# units: mm deg", header]
    qf = robot.q_from_si(q)
    for k in range(len(q)):
        values = list(qf[k]) + ([] if p is None else list(p[k] * 1000))
        lines.append(",".join(f"{v:.4f}" for v in values))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


q = joints(20)
p = armkit.fk(actual, q)[:, :3, 3] + rng.normal(0, 0.05e-3, (20, 3))
write_csv(HERE / "water_supply_measurements.csv", q, p,
          "Simulated tool positions of a water-supply arm; written by generate.py.")
write_csv(HERE / "water_supply_pool.csv", joints(200),
          comment="Candidate configurations to measure; written by generate.py.")
