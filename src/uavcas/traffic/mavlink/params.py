"""ArduCopter's parameters as the autopilot streams them (PARAM_VALUE), and the pace it uses.

The list (`data/arducopter_params.csv`, 1095 parameters of ArduCopter 4.6 with their defaults
and MAV_PARAM_TYPE) and how it was made: `scripts/make_arducopter_params.py`. It is sent in the
file's (alphabetical) order; a real vehicle sends its storage order, which only the firmware knows.
Two values differ from the defaults because this vehicle is configured: SYSID_THISMAV is the
UAV's MAVLink system id, and BATT_MONITOR is 4 (analog voltage and current), the monitor that
makes it report the battery it reports (SYS_STATUS, BATTERY_STATUS).

Pace (libraries/GCS_MAVLink/GCS_Param.cpp, `GCS_MAVLINK::queued_param_send`, ArduPilot master as
stored): parameters get at most 30 % of the port's bandwidth (`bytes_allowed = link_bw * dt /
3333`), at most 5 per call without flow control. The port is the telemetry radio's UART at
SERIAL1_BAUD 57 (57600 baud, the default), whose bandwidth AP_HAL reports as baud / 10 = 5760
bytes/s; a MAVLink 2 PARAM_VALUE frame is 25 + 12 bytes, so 0.3 * 5760 / 37 = 46.7 per second.
A PARAM_REQUEST_READ is answered at once (`send_parameter_async_replies`, before the list).
"""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources

from pydantic import BaseModel, ConfigDict
from pymavlink.dialects.v20 import ardupilotmega as apm

TELEM_BAUD = 57600  # SERIAL1_BAUD 57, ArduCopter's default for the telemetry radio port
PARAM_SHARE = 0.3  # queued_param_send: "use at most 30% of bandwidth on parameters"
PARAM_VALUE_FRAME_BYTES = 25 + 12  # MAVLINK_MSG_ID_PARAM_VALUE_LEN + MAVLink 2 header and CRC


def param_rate_hz(baud: int = TELEM_BAUD) -> float:
    """PARAM_VALUE frames a second on a port of `baud` (46.7 at the default 57600)."""
    return PARAM_SHARE * baud / 10 / PARAM_VALUE_FRAME_BYTES


PARAM_RATE_HZ = param_rate_hz()
BATT_MONITOR_ANALOG = 4  # BATT_MONITOR: analog voltage and current

_TYPES = {"INT8": apm.MAV_PARAM_TYPE_INT8, "INT16": apm.MAV_PARAM_TYPE_INT16, "INT32": apm.MAV_PARAM_TYPE_INT32,
          "REAL32": apm.MAV_PARAM_TYPE_REAL32}


class Param(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str  # at most 16 characters (PARAM_VALUE param_id)
    value: float
    mav_type: int  # MAV_PARAM_TYPE


@cache
def default_params() -> tuple[Param, ...]:
    """ArduCopter 4.6's parameters with their defaults, in the file's order."""
    text = resources.files("uavcas.traffic.mavlink").joinpath("data/arducopter_params.csv").read_text()
    return tuple(Param(name=r["name"], value=float(r["default"]), mav_type=_TYPES[r["type"]])
                 for r in csv.DictReader(text.splitlines()))


def vehicle_params(sysid: int) -> tuple[Param, ...]:
    """This vehicle's parameters: the defaults with its system id and battery monitor."""
    set_ = {"SYSID_THISMAV": float(sysid), "BATT_MONITOR": float(BATT_MONITOR_ANALOG)}
    return tuple(p.model_copy(update={"value": set_[p.name]}) if p.name in set_ else p for p in default_params())


def param_value(m, params: tuple[Param, ...], index: int):
    """PARAM_VALUE of parameter `index` (pymavlink message of dialect `m`)."""
    p = params[index]
    return m.MAVLink_param_value_message(p.name.encode("ascii"), p.value, p.mav_type, len(params), index)


def default_value(name: str) -> float:
    """An ArduCopter default by name (the telemetry model reads its defaults here)."""
    return _by_name()[name]


@cache
def _by_name() -> dict[str, float]:
    return {p.name: p.value for p in default_params()}
