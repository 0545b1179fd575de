"""Collision-free path planning in joint space (SPEC.md section 5).

A `Scene` of obstacles (`Box`, `Sphere`, `Cylinder`, `Capsule`), the arm as spheres and
capsules (`ArmGeometry`: from the robot file, a URDF's collision elements with its meshes
covered by spheres, or its joint origins; the pairs an SRDF leaves out), a `CollisionModel`
built once per robot and a compiled `CollisionChecker` per scene, planners that take any
validity checker (one table, `PLANNERS`: RRT, RRT-Connect, RRT*), shortcutting and resampling,
and `plan`, which does it all within a time limit and returns a `PlanResult`.

The shelf of the benchmark: from the lower compartment to the upper one, around a plate.

>>> arm = armkit.robot("inspection_6dof")
>>> shelf = Scene([Box.from_bounds([0.65, -0.5, 0.2], [1.1, 0.5, 0.24])])
>>> q_start = [0.5567789, -1.5882119, 1.3545770, -2.3713940, 2.2182614, -2.4618970]
>>> q_goal = [-0.8764912, -0.4068011, -1.3528886, 1.6921273, -0.9314323, 2.2978917]
>>> result = plan(arm, q_start, q_goal, scene=shelf, waypoints=10, seed=1, time_limit=np.inf)
>>> result.success, result.path.shape
(True, (10, 6))
"""

from armkit.lazy import public_names
from armkit.planning.collision import CollisionChecker, CollisionModel, displacement_weights
from armkit.planning.geometry import (ArmGeometry, arm_geometry, default_geometry, disabled_pairs,
                                      primitive_capsule, urdf_geometry)
from armkit.planning.plan import PlanResult, PlanSettings, goals_from_pose, plan
from armkit.planning.planners import PLANNERS
from armkit.planning.rrt import ValidityFunction
from armkit.planning.scene import Box, Capsule, Cylinder, Scene, Sphere
from armkit.planning.smooth import path_length, resample, resample_keeping_vertices, shortcut
from armkit.planning.spheres import spheres_from_mesh

__all__ = public_names(__name__)
