"""What a robot is: the canonical chain, its front-ends (DH, modified DH, screws, URDF) and
robot files.

The loader of robots by name or file is `armkit.robot` (defined in `armkit.model.files`); it is
not re-exported here, so that ``armkit.model.robot`` stays the module of the `Robot` class.
"""

from armkit.model.chain import Chain, Joint, KernelChain, Limits
from armkit.model.dh import DHRow, DHTable, chain_from_dh
from armkit.model.files import load_robot, robot_document, robots, save_robot
from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
from armkit.model.robot import SI, Robot, Units, joint_array
from armkit.model.urdf import URDFCollision, URDFTable, chain_from_urdf, read_urdf

__all__ = ["Chain", "Joint", "KernelChain", "Limits", "DHRow", "DHTable", "chain_from_dh",
           "ScrewRow", "ScrewTable", "chain_from_poe", "URDFTable",
           "chain_from_urdf", "read_urdf", "Robot", "Units", "SI", "joint_array", "robots",
           "load_robot", "save_robot", "robot_document", "URDFCollision"]
