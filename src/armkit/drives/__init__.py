"""Motor drives over Modbus TCP: register maps, a client that checks every waypoint before it
leaves and never half-sends one, and a simulated drive that is a real Modbus TCP server."""

from armkit.drives.modbus import (DriveClient, DriveStatus, SendResult, check_waypoints,
                                  send_waypoints)
from armkit.drives.registers import JointRegister, RegisterMap
from armkit.drives.simdrive import FAULTS, SimDrive

# The file format lives in armkit.io.register_maps, which builds on this package: its loaders
# are imported on first use, so that either package may be imported first.
_FILE_FORMAT = ("load_register_map", "parse_register_map")


def __getattr__(name: str):
    if name in _FILE_FORMAT:
        from armkit.io import register_maps
        return getattr(register_maps, name)
    raise AttributeError(f"module 'armkit.drives' has no attribute {name!r}")


__all__ = ["RegisterMap", "JointRegister", "load_register_map", "parse_register_map",
           "check_waypoints", "send_waypoints", "DriveClient", "DriveStatus", "SendResult",
           "SimDrive", "FAULTS"]
