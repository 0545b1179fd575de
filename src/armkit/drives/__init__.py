"""Motor drives over Modbus TCP: register maps, a client that checks every waypoint before it
leaves and never half-sends one, and a simulated drive that is a real Modbus TCP server.

The names are loaded on first use (PEP 562). The file format lives in
`armkit.io.register_maps`, which builds on this package; its loaders are named here too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

_HOMES = {
    **dict.fromkeys(("DriveClient", "DriveStatus", "SendResult", "check_waypoints",
                     "send_waypoints"), "armkit.drives.modbus"),
    **dict.fromkeys(("JointRegister", "RegisterMap"), "armkit.drives.registers"),
    **dict.fromkeys(("FAULTS", "SimDrive"), "armkit.drives.simdrive"),
    **dict.fromkeys(("load_register_map", "parse_register_map"), "armkit.io.register_maps"),
}

if TYPE_CHECKING:
    from armkit.drives.modbus import (DriveClient, DriveStatus, SendResult, check_waypoints,
                                      send_waypoints)
    from armkit.drives.registers import JointRegister, RegisterMap
    from armkit.drives.simdrive import FAULTS, SimDrive
    from armkit.io.register_maps import load_register_map, parse_register_map

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

__all__ = list(_HOMES)
