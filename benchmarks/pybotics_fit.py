"""pybotics' kinematic calibration of one data set, for benchmarks/calibration.py.

Run by that benchmark with the interpreter named by ARMKIT_PYBOTICS_PYTHON (an environment of
its own: pybotics pins numpy < 2), never imported by armkit:

    python pybotics_fit.py DATA.npz

DATA.npz holds the nominal arm as pybotics takes it (modified DH rows ``mdh`` (n, 4) as alpha,
a, theta, d in m and rad; ``world`` and ``tool`` (4, 4)), the measurements ``q`` (m, n) rad and
``measured`` (m, 3) m, and the hold-out joint values ``hold_q``. The fit is pybotics' own:
its OptimizationHandler with every kinematic-chain parameter, the tool's position and the
world frame free, and scipy's least_squares on pybotics' residual (the distance per
measurement), as pybotics' calibration example does (it frees the joint offsets only; here
every parameter is off nominal), stopped after MAX_EVALUATIONS evaluations. One JSON document
on stdout: the solve's time (s), the hold-out positions predicted by the fitted arm (m), how
far the parameters moved, least_squares' status and evaluations, and the hold-out positions of
the nominal arm (to show that pybotics models the same arm as armkit).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from pybotics.optimization import OptimizationHandler, optimize_accuracy
from pybotics.robot import Robot
from pybotics.tool import Tool
from scipy.optimize import least_squares


MAX_EVALUATIONS = 30     # of the residual, beside the 33 per finite-difference Jacobian


def main() -> None:
    data = np.load(sys.argv[1])
    robot = Robot.from_parameters(np.array(data["mdh"], dtype=float))
    robot.tool = Tool(matrix=np.array(data["tool"], dtype=float))
    robot.world_frame = np.array(data["world"], dtype=float)
    handler = OptimizationHandler(robot=robot, kinematic_chain_mask=True,
                                  tool_mask=[True, True, True, False, False, False],
                                  world_mask=True)
    x0 = handler.generate_optimization_vector()
    nominal = np.array([handler.robot.fk(q)[:3, 3] for q in data["hold_q"]])
    start = time.perf_counter()
    # Capped: with the redundant parameters free (the world frame against the first link, the
    # tool against the last) trf does not meet its tolerances and runs on for many minutes.
    fit = least_squares(optimize_accuracy, x0, args=(handler, data["q"], data["measured"]),
                        max_nfev=MAX_EVALUATIONS)
    seconds = time.perf_counter() - start
    handler.apply_optimization_vector(fit.x)
    predicted = np.array([handler.robot.fk(q)[:3, 3] for q in data["hold_q"]])
    chain = np.array(handler.robot.kinematic_chain.matrix) - np.array(data["mdh"])
    json.dump({"seconds": seconds, "holdout_positions": predicted.tolist(),
               "nominal_holdout_positions": nominal.tolist(),
               "largest_length_change_m": float(np.abs(chain[:, [1, 3]]).max()),
               "largest_angle_change_rad": float(np.abs(chain[:, [0, 2]]).max()),
               "status": int(fit.status), "evaluations": int(fit.nfev)}, sys.stdout)


if __name__ == "__main__":
    main()
