"""What a COMMAND_LONG does to the autopilot: its flight mode and commanded speed.

ArduCopter (ArduCopter/GCS_MAVLink_Copter.cpp: a COMMAND_LONG is handled as the command it
carries) accepts, among others:
* MAV_CMD_NAV_RETURN_TO_LAUNCH -> mode RTL (custom_mode 6), COMMAND_ACK MAV_RESULT_ACCEPTED;
* MAV_CMD_NAV_LAND -> mode LAND (custom_mode 9), ACCEPTED;
* MAV_CMD_DO_CHANGE_SPEED -> param2 m/s becomes the waypoint speed, ACCEPTED;
and answers what it does not implement with MAV_RESULT_UNSUPPORTED. Mode numbers are
ArduCopter's `Mode::Number` (ArduCopter/mode.h: AUTO = 3, RTL = 6, LAND = 9). The new mode shows
in every HEARTBEAT's custom_mode from then on.

What changes is the vehicle's state as it reports it, not its flight: the plan's track (which
drives the channel and the telemetry's positions) is the plan's whatever was commanded; a
commanded speed is logged (`command` lines of the endpoint's log) and not reported in the
streamed messages, none of which carries a target speed (VFR_HUD's groundspeed is the measured
one, the track's). An attacker's RTL therefore shows in HEARTBEAT while the positions keep
following the plan; a plan whose track obeys the command is not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass

from .specs import COPTER_MODE_AUTO

COPTER_MODE_RTL = 6
COPTER_MODE_LAND = 9


@dataclass
class VehicleState:
    """The autopilot's commanded state: flight mode (ArduCopter custom_mode) and speed (m/s)."""

    custom_mode: int = COPTER_MODE_AUTO
    speed_mps: float | None = None  # the last DO_CHANGE_SPEED's, None: none received

    def command(self, m, msg) -> int:
        """Apply one COMMAND_LONG (pymavlink message of dialect module `m`); its MAV_RESULT."""
        if msg.command == m.MAV_CMD_DO_CHANGE_SPEED:
            self.speed_mps = float(msg.param2)
        elif msg.command == m.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            self.custom_mode = COPTER_MODE_RTL
        elif msg.command == m.MAV_CMD_NAV_LAND:
            self.custom_mode = COPTER_MODE_LAND
        else:
            return m.MAV_RESULT_UNSUPPORTED
        return m.MAV_RESULT_ACCEPTED
