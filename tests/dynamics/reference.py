"""Pinocchio models of armkit's robots, built from the same source, for the dynamics tests and
benchmarks: from the URDF file itself (Pinocchio's own parser), or from a DH or screw table's
numbers (its joints placed by the table's formulas, not by armkit's chain)."""

from __future__ import annotations

import importlib.metadata

import numpy as np
import pinocchio as pin

import armkit
from armkit.model.dh import DHTable, dh_transform
from armkit.model.inertia import home_link_frames
from armkit.model.poe import ScrewTable
from armkit.model.urdf import URDFTable
from armkit.spatial import rotz, transform, translation


def robot_file(suffix: str) -> str:
    """The installed example-robot-data file whose path ends with `suffix`."""
    dist = importlib.metadata.distribution("example-robot-data")
    found = [f for f in dist.files or () if str(f).replace("\\", "/").endswith(suffix)]
    assert len(found) == 1, f"example-robot-data holds {len(found)} files ending {suffix}"
    return str(dist.locate_file(found[0]))


class Reference:
    """A Pinocchio model of an armkit robot, and the map between their joint vectors.

    Each of armkit's moving joints (mimic ones too) is a Pinocchio joint; a mimic joint's
    value, rate and acceleration follow its leader's, and its torque adds, times the
    multiplier, to the leader's. Bodies that armkit leaves out of the arm (moved by joints off
    the chain) weigh nothing here.
    """

    def __init__(self, robot: armkit.Robot, model: pin.Model, joint_ids: list[int]):
        self.robot, self.model, self.data = robot, model, model.createData()
        self.model.gravity.linear[:] = robot.inertia.gravity
        k = robot.chain.kernel
        self.ids, self.source, self.scale = joint_ids, k.source, k.scale
        # d(pinocchio v)/d(armkit qd): the coupling, placed at each joint's velocity index.
        self.coupling = np.zeros((model.nv, robot.n))
        for i, s, jid in zip(self.source, self.scale, joint_ids):
            self.coupling[model.joints[jid].idx_v, i] = s

    def q(self, q: np.ndarray) -> np.ndarray:
        out = pin.neutral(self.model)
        for joint, i, s, jid in zip(self.robot.chain.joints, self.source, self.scale,
                                    self.ids):
            value = s * q[i] + (joint.mimic_offset if joint.leader is not None else 0.0)
            at, nq = self.model.joints[jid].idx_q, self.model.joints[jid].nq
            out[at:at + nq] = [np.cos(value), np.sin(value)] if nq == 2 else [value]
        return out

    def v(self, qd: np.ndarray) -> np.ndarray:
        return self.coupling @ qd

    def rnea(self, q, qd, qdd):
        tau = pin.rnea(self.model, self.data, self.q(q), self.v(qd), self.v(qdd))
        return self.coupling.T @ tau

    def mass(self, q):
        M = pin.crba(self.model, self.data, self.q(q))
        M = np.triu(M) + np.triu(M, 1).T
        return self.coupling.T @ M @ self.coupling

    def coriolis(self, q, qd):
        C = pin.computeCoriolisMatrix(self.model, self.data, self.q(q), self.v(qd))
        return self.coupling.T @ C @ self.coupling

    def gravity(self, q):
        return self.coupling.T @ pin.computeGeneralizedGravity(self.model, self.data,
                                                               self.q(q))

    def aba(self, q, qd, tau):
        """Forward dynamics: Pinocchio's ABA where its joints are armkit's; else (a whole tree
        kept, mimic joints) the coupled system solved with Pinocchio's M and bias torques."""
        if np.array_equal(self.coupling, np.eye(self.robot.n)):
            return pin.aba(self.model, self.data, self.q(q), qd, tau)
        return np.linalg.solve(self.mass(q), tau - self.rnea(q, qd, np.zeros_like(q)))


def from_urdf(robot: armkit.Robot) -> Reference:
    """Pinocchio's model of the robot's URDF, with every body off armkit's chain massless."""
    table = robot.table
    assert isinstance(table, URDFTable)
    full = pin.buildModelFromUrdf(table.path)
    names = [j.name for j in robot.chain.joints]
    ids = [full.getJointId(name) for name in names]
    assert all(i < full.njoints for i in ids)
    for jid in range(1, full.njoints):
        if jid not in ids:
            full.inertias[jid] = pin.Inertia.Zero()
    # The joints off the chain locked at zero (their bodies weigh nothing now): the model's
    # joints are then armkit's moving joints.
    locked = [j for j in range(1, full.njoints) if j not in ids]
    try:
        model = pin.buildReducedModel(full, locked, pin.neutral(full)) if locked else full
    except ValueError:              # two frames of one name (z1.urdf): keep the whole tree
        model = full
    return Reference(robot, model, [model.getJointId(name) for name in names])


def _inertia(body) -> pin.Inertia:
    return pin.Inertia(body.mass, np.array(body.com), np.array(body.tensor))


def from_table(robot: armkit.Robot) -> Reference:
    """Pinocchio's model built from the robot's DH or screw table and inertial model: joint
    placements by the table's formulas, each body's inertia placed in its joint's frame."""
    table, model = robot.table, pin.Model()
    inertia = robot.inertia
    parent, ids = 0, []
    if isinstance(table, DHTable):
        placement = table.T_base.copy()
        fixed_before = np.eye(4)
        moving = 0
        for row in table.rows:
            if row.kind == "fixed":
                # Only before the first joint here (water_supply's base): a fixed row after a
                # joint would belong to that joint's link frame.
                assert moving == 0, "a fixed row after a moving one"
                fixed_before = fixed_before @ dh_transform(row, table.modified)
                continue
            revolute = row.kind == "revolute"
            if table.modified:
                # Joint frame: Rx(alpha) Tx(a) from the previous link frame; link frame i is
                # the joint frame then Rz(theta) Tz(d), the joint value added to its column.
                before = placement @ fixed_before @ dh_transform(
                    type(row)(row.kind, row.alpha, row.a, 0.0, 0.0), True)
                to_link = transform(rotz(row.theta)) @ translation([0, 0, row.d])
            else:
                before = placement @ fixed_before
                to_link = dh_transform(row, False)
            fixed_before = np.eye(4)
            joint = pin.JointModelRZ() if revolute else pin.JointModelPZ()
            jid = model.addJoint(parent, joint, pin.SE3(before[:3, :3], before[:3, 3]),
                                 f"q{moving}")
            # The motion is about (along) z of the joint frame; the row's theta and d follow
            # it, up to the link frame, where the file gives the body.
            body = inertia.links[moving].moved(to_link)
            if moving == robot.chain.n_joints - 1 and inertia.payload is not None:
                body = body + inertia.payload.moved(to_link @ table.T_tool)
            model.appendBodyToJoint(jid, _inertia(body), pin.SE3.Identity())
            ids.append(jid)
            parent, placement = jid, to_link
            moving += 1
    else:
        assert isinstance(table, ScrewTable)
        # The file gives each body in the base frame at home (q = 0), as the screws; at home,
        # joint frame i is the base frame moved to the joint's point.
        home = home_link_frames(robot.chain)
        previous = np.zeros(3)
        for i, row in enumerate(table.rows):
            point = previous if row.point is None else np.asarray(row.point)
            axis = np.asarray(row.axis) / np.linalg.norm(row.axis)
            joint = (pin.JointModelRevoluteUnaligned(axis) if row.kind == "revolute"
                     else pin.JointModelPrismaticUnaligned(axis))
            place = (table.T_base if i == 0 else np.eye(4)) @ translation(point - previous)
            jid = model.addJoint(parent, joint, pin.SE3(place[:3, :3], place[:3, 3]), f"q{i}")
            to_joint = np.linalg.inv(table.T_base @ translation(point))
            body = inertia.links[i].moved(to_joint @ home[i])
            if i == robot.n - 1 and inertia.payload is not None:
                body = body + inertia.payload.moved(to_joint @ home[i] @ robot.chain.T_tool)
            model.appendBodyToJoint(jid, _inertia(body), pin.SE3.Identity())
            ids.append(jid)
            parent, previous = jid, point
    model.armature[:] = [robot.inertia.armature[i] for i in robot.chain.kernel.source]
    return Reference(robot, model, ids)
