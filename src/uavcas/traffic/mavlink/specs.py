"""The MAVLink endpoints' typed specs, and what the plan puts in them."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field
from pymavlink.dialects.v20 import common

from uavcas.twin.model import DEFAULT_STREAM_HZ, Site
from uavcas.twin.track import Track, local_to_geodetic

from . import radio as _radio
from .params import TELEM_BAUD
from .signing import SigningSpec
from .streams import message_rates_hz

GCS_PORT = 14550  # the customary ground-station UDP port (MAVProxy, QGroundControl, Mission Planner)
# The autopilot's own UDP port: fixed (the customary MAVLink port on both ends), so that a sender
# other than its ground station (an attacker, `attacks.mavlink_inject`) can address it; a real
# attacker would read the port from one sniffed datagram. It answers commands from any address.
UAV_PORT = 14550
COMPONENT_AUTOPILOT = 1  # MAV_COMP_ID_AUTOPILOT1
COMPONENT_GCS = 190  # MAV_COMP_ID_MISSIONPLANNER, what ground stations use
COPTER_MODE_AUTO = 3  # ArduCopter custom_mode AUTO: flying the uploaded mission
GPS_FIX_3D = 3
GPS_SATELLITES = 12


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class StreamRates(_Frozen):
    """What the GCS requests, as MAVProxy does (MAVProxy/mavproxy.py at f76c4d3d, `set_stream_rates`):
    one REQUEST_DATA_STREAM with MAV_DATA_STREAM_ALL at its `streamrate` setting (default 4,
    `MPSetting('streamrate', int, 4, ...)`) to each vehicle it has detected (a non-GCS HEARTBEAT,
    mavproxy_link.py `master_callback`), sent again every 15 s (`msg_period =
    mavutil.periodic_event(1.0/15)`), so a request lost on the link is repaired 15 s later. ArduPilot
    applies it to every stream but PARAMS (`streams.py`); its own HEARTBEAT stays 1 Hz. The GCS's
    heartbeat: MAVProxy's `heartbeat` setting, 1 Hz.
    """

    stream_rate_hz: int = Field(default=DEFAULT_STREAM_HZ, ge=1, le=50)  # MAVProxy `streamrate`
    heartbeat_rate_hz: float = Field(default=1.0, gt=0, le=50)
    rerequest_s: float = Field(default=15.0, gt=0)  # MAVProxy msg_period

    def requests(self) -> list[tuple[int, int]]:
        """(MAV_DATA_STREAM id, rate Hz) pairs the GCS sends: one, for all streams."""
        return [(common.MAV_DATA_STREAM_ALL, self.stream_rate_hz)]

    def expected_hz(self) -> dict[str, float]:
        """Message type -> rate the UAV sends it at once the request is granted."""
        return message_rates_hz(self.stream_rate_hz)


class BatterySpec(_Frozen):
    """A constant-current discharge: remaining = 1 - current * t / capacity, the voltage linear in
    the remaining charge from full to empty (a 4S LiPo: 4.2 V to 3.5 V per cell)."""

    capacity_mah: float = Field(default=5000.0, gt=0)
    current_a: float = Field(default=20.0, ge=0)  # a ~2 kg quadrotor's hover draw: 15 min on 5 Ah
    full_v: float = 16.8
    empty_v: float = 14.0

    def at(self, t_s: float) -> tuple[int, int, int]:
        """(voltage mV, current cA, remaining %) at plan time t."""
        used = self.current_a * max(t_s, 0.0) / 3600.0 * 1000.0 / self.capacity_mah
        remaining = min(1.0, max(0.0, 1.0 - used))
        volts = self.empty_v + (self.full_v - self.empty_v) * remaining
        return round(volts * 1000), round(self.current_a * 100), round(remaining * 100)


class RetrySpec(_Frozen):
    timeout_s: float = Field(default=0.5, gt=0)  # MAVSDK's default MAVLink transfer timeout
    mission_retries: int = Field(default=5, ge=0)
    command_retries: int = Field(default=3, ge=0)


class UavSpec(_Frozen):
    kind: Literal["uav"] = "uav"
    name: str
    sysid: int = Field(ge=1, le=255)
    gcs_ip: str
    gcs_port: int = GCS_PORT
    bind_ip: str = "0.0.0.0"
    bind_port: int = Field(default=UAV_PORT, ge=0, le=65535)  # 0: an ephemeral port (tests)
    signing: SigningSpec | None = None  # MAVLink 2 signing (signing.py), None: off
    site: Site
    times_s: list[float]  # the plan's track: window starts ...
    positions_m: list[tuple[float, float, float]]  # ... and the UAV's position at each
    t0_unix: float | None = None  # plan t = 0; None: read from t0_path once it appears
    t0_path: Path | None = None
    duration_s: float
    battery: BatterySpec = BatterySpec()
    retry: RetrySpec = RetrySpec()
    log_path: Path
    gps_path: Path | None = None  # where an attack may publish a GPS spoofer (gps.control_path)
    # the telemetry port's baud rate, which paces the parameter download (params.param_rate_hz)
    telem_baud: int = Field(default=TELEM_BAUD, gt=0)
    # the sensor noise stream: uavcas.seeding stream (plan_seed, "mavlink-sensors", uav_index)
    plan_seed: int = Field(default=0, ge=0)
    uav_index: int = Field(default=0, ge=0)
    radio: _radio.RadioSpec | None = None  # the telemetry radio's RADIO_STATUS reports (radio.py), None: none

    def track(self) -> Track:
        return Track(tuple(self.times_s), tuple(tuple(p) for p in self.positions_m))


class GcsTarget(_Frozen):
    name: str
    sysid: int = Field(ge=1, le=255)
    waypoints: list[tuple[float, float, float]]  # lat deg, lon deg, metres above the site
    speeds_mps: list[float]  # planned ground speed in each window


class GcsSpec(_Frozen):
    kind: Literal["gcs"] = "gcs"
    name: str
    sysid: int = Field(ge=1, le=255)
    bind_ip: str = "0.0.0.0"
    port: int = GCS_PORT
    signing: SigningSpec | None = None  # MAVLink 2 signing (signing.py), None: off
    rates: StreamRates = StreamRates()
    retry: RetrySpec = RetrySpec()
    uavs: list[GcsTarget]
    t0_unix: float | None = None  # as UavSpec
    t0_path: Path | None = None
    window_s: float = Field(gt=0)
    n_windows: int = Field(ge=1)
    duration_s: float
    log_path: Path


def gcs_target(plan, uav: str) -> GcsTarget:
    """What a GCS knows of a UAV it serves: its waypoints and per-window speeds, from the plan."""
    node = plan.node(uav)
    if node.sysid is None:
        raise ValueError(f"{uav} has no MAVLink system id in the plan")
    track = Track.of(plan, uav)
    return GcsTarget(name=uav, sysid=node.sysid, waypoints=mission_waypoints(plan.site, track),
                     speeds_mps=[track.speed_in_window_mps(k) for k in range(len(plan.windows))])


def mission_waypoints(site: Site, track: Track) -> list[tuple[float, float, float]]:
    """The track's window-start positions as mission waypoints: lat deg, lon deg, metres above the
    site (what the GCS uploads and the autopilot navigates to)."""
    wps = [local_to_geodetic(site, *p) for p in track.positions_m]
    return [(lat, lon, alt - site.alt_m) for lat, lon, alt in wps]


def uav_spec(plan, uav: str, gcs_ip: str, t0_unix: float | None, duration_s: float, log_path: Path,
             **kw) -> UavSpec:
    node = plan.node(uav)
    if node.sysid is None:
        raise ValueError(f"{uav} has no MAVLink system id in the plan")
    track = Track.of(plan, uav)
    index = node.index  # the UAV's index, as the radio's stream takes it (radio.radio_reports)
    if "radio" not in kw:  # the caller's, else the one the plan's stream rate loads
        kw["radio"] = radio_spec(plan, uav)
    return UavSpec(name=uav, sysid=node.sysid, gcs_ip=gcs_ip, site=plan.site, times_s=list(track.times_s),
                   positions_m=list(track.positions_m), t0_unix=t0_unix, duration_s=duration_s,
                   log_path=log_path, plan_seed=plan.seed, uav_index=index, **kw)


def radio_spec(plan, uav: str, rates: StreamRates | None = None) -> _radio.RadioSpec:
    """The UAV radio's reports (radio.py): its load is the telemetry the GCS's `rates` ask for
    (default: the plan's stream rate), and it receives the GCS's heartbeats (the GCS's one
    periodic message to it)."""
    rates = rates or StreamRates(stream_rate_hz=plan.mavlink_stream_hz)
    offered_bps, frame_bytes = _radio.mavlink_load(rates.expected_hz())
    return _radio.RadioSpec(reports=_radio.radio_reports(plan, uav, offered_bps, frame_bytes,
                                                         rates.heartbeat_rate_hz))
