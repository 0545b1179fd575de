"""Rigid-body dynamics of serial arms (SPEC.md section 5a), on the kinematic core.

- `inverse_dynamics`, `gravity_torques`, `coriolis`: joint torques of a motion, at rest, and
  its velocity-product part;
- `mass_matrix`, `coriolis_matrix`: M(q) and C(q, qd);
- `forward_dynamics`: joint accelerations under given torques;
- `with_payload`: the robot holding a load at its tool;
- `torque_profile`, `TorqueLimits`: the torques along a trajectory against the limits, and the
  torque constraint `armkit.retime` takes.

Inertial parameters come from robot files (``inertia:``) and URDF ``<inertial>`` elements
(`armkit.model.inertia`). The names are loaded on first use (PEP 562).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.dynamics.equations import (coriolis, coriolis_matrix, forward_dynamics,
                                           gravity_torques, inverse_dynamics, mass_matrix,
                                           with_payload)
    from armkit.dynamics.torques import TorqueLimits, TorqueProfile, torque_profile
    from armkit.model.inertia import Inertia, InertialModel


__getattr__, __dir__, __all__ = lazy_names(__name__)


