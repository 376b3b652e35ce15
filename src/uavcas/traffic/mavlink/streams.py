"""ArduCopter's telemetry streams: which messages each stream group sends, as ONE table.

Source: ArduPilot, ArduCopter/GCS_Mavlink.cpp at commit 0012da222672c2e8b3b9d03ef859af4e3b984f88
(the STREAM_*_msgs arrays and `all_stream_entries`), with libraries/GCS_MAVLink/GCS_Common.cpp
(`try_send_message`: one `ap_message` -> one MAVLink message, sent only when the vehicle has what
it reports) and libraries/GCS_MAVLink/ap_message.h (the MSG_* names). A stream's rate applies to
each of its messages: at rate R every message of the group is sent R times a second.

REQUEST_DATA_STREAM with MAV_DATA_STREAM_ALL sets every stream's rate but PARAMS
(GCS_Common.cpp handle_request_data_stream: "don't touch parameter streaming rate; it is
considered internal"); ADSB is set too but has nothing to send without an ADS-B receiver.

What a Copter without optional hardware sends (a board with two IMUs, one barometer, one GPS, one
battery monitor, no rangefinder, gimbal, flow sensor, RPM or ESC telemetry; the defaults of
ArduCopter 4.6, `params.py`): `messages` of each group below. What the group lists but such a
Copter does not send is in `left_out`, with the reason. TERRAIN: TERRAIN_ENABLE defaults to 1 on
Copter, and AP_Terrain::send_request (libraries/AP_Terrain/TerrainGCS.cpp, run for MSG_TERRAIN of
EXTRA3) always sends a TERRAIN_REPORT and, while grid blocks are missing, a TERRAIN_REQUEST at most
every 2 s (`TERRAIN_REQUEST_MIN_INTERVAL_S`); the ground station here answers no terrain request
(MAVProxy's terrain module needs SRTM tiles, which an offline ground station does not have), so
the blocks stay missing and the request keeps coming.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict
from pymavlink.dialects.v20 import ardupilotmega as apm

TERRAIN_REQUEST_MIN_INTERVAL_S = 2.0  # AP_Terrain::send_request: "too soon to request again" below 2000 ms
HEARTBEAT_RATE_HZ = 1.0  # GCS_MAVLINK::update_send: HEARTBEAT every 1000 ms, whatever the streams


class StreamGroup(BaseModel):
    """One ArduPilot stream: its MAV_DATA_STREAM id, its SRn_ parameter and its messages."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str  # ArduPilot's STREAM_* name
    stream_id: int  # MAV_DATA_STREAM_* (REQUEST_DATA_STREAM's req_stream_id)
    param: str  # the SRn_ parameter that holds its rate
    messages: tuple[str, ...]  # what this Copter sends each tick of the stream
    left_out: dict[str, str] = {}  # listed in the source, not sent here: why


STREAM_GROUPS: tuple[StreamGroup, ...] = (
    StreamGroup(name="RAW_SENSORS", stream_id=apm.MAV_DATA_STREAM_RAW_SENSORS, param="RAW_SENS",
                messages=("RAW_IMU", "SCALED_IMU2", "SCALED_PRESSURE", "SENSOR_OFFSETS"),
                left_out={"SCALED_IMU3": "a third IMU (send_scaled_imu(2) returns without one)",
                          "SCALED_PRESSURE2": "a second barometer", "SCALED_PRESSURE3": "a third barometer"}),
    StreamGroup(name="EXTENDED_STATUS", stream_id=apm.MAV_DATA_STREAM_EXTENDED_STATUS, param="EXT_STAT",
                messages=("SYS_STATUS", "POWER_STATUS", "MEMINFO", "MISSION_CURRENT", "GPS_RAW_INT",
                          "NAV_CONTROLLER_OUTPUT", "POSITION_TARGET_GLOBAL_INT"),
                left_out={"GPS_RTK": "an RTK GPS", "GPS2_RAW": "a second GPS", "GPS2_RTK": "a second RTK GPS",
                          "FENCE_STATUS": "a fence (FENCE_ENABLE defaults to 0)"}),
    StreamGroup(name="POSITION", stream_id=apm.MAV_DATA_STREAM_POSITION, param="POSITION",
                messages=("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED")),
    StreamGroup(name="RC_CHANNELS", stream_id=apm.MAV_DATA_STREAM_RC_CHANNELS, param="RC_CHAN",
                messages=("SERVO_OUTPUT_RAW", "RC_CHANNELS"),
                left_out={"RC_CHANNELS_RAW": "sent only on a MAVLink 1 link; this one is MAVLink 2"}),
    StreamGroup(name="EXTRA1", stream_id=apm.MAV_DATA_STREAM_EXTRA1, param="EXTRA1",
                messages=("ATTITUDE", "AHRS2"),
                left_out={"SIMSTATE": "SITL only", "AHRS3": "EKF2 and EKF3 both running (EK2_ENABLE is 0)",
                          "PID_TUNING": "GCS_PID_MASK defaults to 0"}),
    StreamGroup(name="EXTRA2", stream_id=apm.MAV_DATA_STREAM_EXTRA2, param="EXTRA2", messages=("VFR_HUD",)),
    StreamGroup(name="EXTRA3", stream_id=apm.MAV_DATA_STREAM_EXTRA3, param="EXTRA3",
                messages=("AHRS", "HWSTATUS", "SYSTEM_TIME", "TERRAIN_REPORT", "BATTERY_STATUS",
                          "EKF_STATUS_REPORT", "VIBRATION"),
                left_out={"RANGEFINDER": "a rangefinder", "DISTANCE_SENSOR": "a rangefinder",
                          "BATTERY2": "a second battery monitor", "MOUNT_STATUS": "a gimbal (MNT1_TYPE 0)",
                          "OPTICAL_FLOW": "a flow sensor", "GIMBAL_REPORT": "a Solo gimbal",
                          "MAG_CAL_REPORT": "a compass calibration in progress",
                          "MAG_CAL_PROGRESS": "a compass calibration in progress", "RPM": "an RPM sensor",
                          "ESC_TELEMETRY_1_TO_4": "ESC telemetry (MSG_ESC_TELEMETRY)",
                          "TERRAIN_REQUEST": "sent, but at most every 2 s (TERRAIN_REQUEST_MIN_INTERVAL_S), "
                                             "not every tick"}),
    StreamGroup(name="ADSB", stream_id=-1, param="ADSB", messages=(),  # no MAV_DATA_STREAM id of its own
                left_out={"ADSB_VEHICLE": "an ADS-B receiver"}),
)

GROUP_BY_ID = {g.stream_id: g for g in STREAM_GROUPS if g.stream_id >= 0}
GROUP_OF = {msg: g.name for g in STREAM_GROUPS for msg in g.messages}  # message -> its stream
STREAMED = tuple(msg for g in STREAM_GROUPS for msg in g.messages)


def message_rates_hz(rate_hz: float) -> dict[str, float]:
    """Message -> rate once MAV_DATA_STREAM_ALL at `rate_hz` is granted (HEARTBEAT and the
    rate-limited TERRAIN_REQUEST included; PARAM_VALUE, mission and command traffic not)."""
    out = {msg: float(rate_hz) for msg in STREAMED}
    out["HEARTBEAT"] = HEARTBEAT_RATE_HZ
    if rate_hz > 0:  # one TERRAIN_REQUEST per EXTRA3 tick at most, and at most one per 2 s
        out["TERRAIN_REQUEST"] = min(float(rate_hz), 1.0 / TERRAIN_REQUEST_MIN_INTERVAL_S)
    return out


def frames_per_s(rate_hz: float) -> float:
    """Frames a second one autopilot sends in steady state at `rate_hz` (`message_rates_hz` summed)."""
    return sum(message_rates_hz(rate_hz).values())
