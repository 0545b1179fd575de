"""`armkit demo`: the end-to-end job on built-in defaults, as far as it is built."""

from __future__ import annotations

import numpy as np
from rich.table import Table

import armkit
from armkit.cli.app import JsonFlag, app, print_json, stdout
from armkit.cli.robots import pose_view, show

DEMO_ROBOT = "water_supply"
# Configurations in the file's units (mm, deg): home, reaching out, folded back.
DEMO_Q = [[0, 0, 0, 0], [300, 30, -45, 15], [550, -90, 120, -30]]
NOT_BUILT = ["target from camera to base frame", "inverse kinematics with the optimal solution",
             "collision-free plan", "smooth trajectory", "waypoints to the drives", "report"]


@app.command()
def demo(as_json: JsonFlag = False) -> None:
    """Run the end-to-end job on the built-in water-supply robot and task."""
    robot = armkit.robot(DEMO_ROBOT)
    q = robot.q_to_si(DEMO_Q)
    poses = armkit.fk(robot, q)
    J = armkit.jacobian(robot, q)
    mask = [True, True, True, False, False, True]          # the arm's task: x, y, z, yaw
    measures = {"manipulability": armkit.manipulability(robot, q, mask),
                "min_singular_value": armkit.min_singular_value(robot, q, mask),
                "condition_number": armkit.condition_number(robot, q, mask)}
    steps = [{"q": qi, **pose_view(T, robot.units), "jacobian": Ji,
              **{k: v[i] for k, v in measures.items()}}
             for i, (qi, T, Ji) in enumerate(zip(DEMO_Q, poses, J))]
    if as_json:
        return print_json({"robot": DEMO_ROBOT, "forward_kinematics": steps,
                           "not_built": NOT_BUILT})
    stdout.rule(f"armkit demo: {DEMO_ROBOT}")
    show(DEMO_ROBOT)
    table = Table("q (mm, deg)", "x y z (mm)", "yaw (deg)", "manipulability", "cond(J)",
                  title="forward kinematics and Jacobian (task rows x y z yaw)", box=None,
                  title_justify="left")
    for s in steps:
        table.add_row(" ".join(f"{v:g}" for v in s["q"]),
                      " ".join(f"{v:.1f}" for v in s["position"]), f"{s['rpy'][2]:.1f}",
                      f"{s['manipulability']:.4g}", f"{s['condition_number']:.3g}")
    stdout.print(table)
    stdout.print("\nNot built yet: " + "; ".join(NOT_BUILT) + ".")
