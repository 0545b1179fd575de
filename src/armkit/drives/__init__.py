"""Motor drives over Modbus TCP: register maps, a client that checks every waypoint before it
leaves and never half-sends one, and a simulated drive that is a real Modbus TCP server.

The names are loaded on first use (PEP 562). The file format lives in
`armkit.io.register_maps` (`load_register_map`, also `armkit.load_register_map`), which builds
on this package; drives take the objects it makes and open no files.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.lazy import lazy_names

if TYPE_CHECKING:
    from armkit.drives.modbus import (DriveClient, DriveStatus, SendResult, check_waypoints,
                                      send_waypoints)
    from armkit.drives.registers import JointRegister, RegisterMap, default_register_map
    from armkit.drives.simdrive import FAULTS, SimDrive

__getattr__, __dir__, __all__ = lazy_names(__name__)

