"""What a robot is: the canonical chain, its front-ends (DH, modified DH, screws, URDF) and
robot files.

The loader of robots by name or file is `armkit.robot` (defined in `armkit.model.files`); it is
not re-exported here, so that ``armkit.model.robot`` stays the module of the `Robot` class.
Every name below is loaded on first use (PEP 562): the chain alone (what trajectories and
kernels need) does not import the file readers and their pydantic.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

# name -> the module that defines it
_HOMES = {
    **dict.fromkeys(("Chain", "Joint", "KernelChain", "Limits"), "armkit.model.chain"),
    **dict.fromkeys(("DHRow", "DHTable", "chain_from_dh"), "armkit.model.dh"),
    **dict.fromkeys(("load_robot", "robot_document", "robots", "save_robot"),
                    "armkit.model.files"),
    **dict.fromkeys(("ScrewRow", "ScrewTable", "chain_from_poe"), "armkit.model.poe"),
    **dict.fromkeys(("SI", "Robot", "Units", "joint_array"), "armkit.model.robot"),
    **dict.fromkeys(("URDFCollision", "URDFTable", "chain_from_urdf", "read_urdf"),
                    "armkit.model.urdf"),
}

if TYPE_CHECKING:       # what the names are, for readers and type checkers
    from armkit.model.chain import Chain, Joint, KernelChain, Limits
    from armkit.model.dh import DHRow, DHTable, chain_from_dh
    from armkit.model.files import load_robot, robot_document, robots, save_robot
    from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
    from armkit.model.robot import SI, Robot, Units, joint_array
    from armkit.model.urdf import URDFCollision, URDFTable, chain_from_urdf, read_urdf


__getattr__, __dir__ = lazy_names(__name__, _HOMES)


__all__ = list(_HOMES)
