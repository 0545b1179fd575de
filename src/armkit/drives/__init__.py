"""Motor drives over Modbus TCP: register maps, a client that checks every waypoint before it
leaves and never half-sends one, and a simulated drive that is a real Modbus TCP server."""

from armkit.drives.modbus import (DriveClient, DriveStatus, SendResult, check_waypoints,
                                  send_waypoints)
from armkit.drives.registers import (JointRegister, RegisterMap, load_register_map,
                                     parse_register_map)
from armkit.drives.simdrive import FAULTS, SimDrive

__all__ = ["RegisterMap", "JointRegister", "load_register_map", "parse_register_map",
           "check_waypoints", "send_waypoints", "DriveClient", "DriveStatus", "SendResult",
           "SimDrive", "FAULTS"]
