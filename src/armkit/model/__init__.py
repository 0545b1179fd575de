"""What a robot is: the canonical chain and its front-ends (DH, modified DH, screws, URDF).

Files are read elsewhere: robot files and the loader of robots by name or file (`armkit.robot`)
in `armkit.io.robot_files`, URDF files in `armkit.io.urdf`. Every name below is loaded on first
use (PEP 562): the chain alone (what trajectories and kernels need) imports nothing else.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:       # the public names, each loaded at its first use (armkit.lazy)
    from armkit.model.chain import Chain, Joint, KernelChain, Limits
    from armkit.model.dh import DHRow, DHTable, chain_from_dh
    from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
    from armkit.model.robot import SI, Robot, Units, joint_array
    from armkit.model.urdf import URDFCollision, URDFTable, chain_from_urdf


__getattr__, __dir__, __all__ = lazy_names(__name__)


