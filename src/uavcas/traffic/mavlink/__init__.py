"""MAVLink v2 between every UAV's autopilot and its base station's ground station (pymavlink).

Two endpoint processes, one per node, each a small MAVLink peer over UDP (one message per
datagram; every byte is packed and parsed by pymavlink's `dialects.v20.ardupilotmega`, common
plus ArduPilot's own messages, on both ends):

* `uav` (autopilot, in the UAV's namespace, bound to UDP `UAV_PORT` = 14550: a fixed port an
  attacker can address): HEARTBEAT at 1 Hz (MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_ARDUPILOTMEGA,
  Copter custom mode: AUTO = 3 until a command changes it) to its BS's port 14550, always, also
  while the plan marks it disconnected (a radio sends into the void). Its streams are
  ArduCopter's (`streams`: the stream groups RAW_SENSORS, EXTENDED_STATUS, POSITION, RC_CHANNELS,
  EXTRA1, EXTRA2, EXTRA3 with the messages ArduCopter/GCS_Mavlink.cpp lists, less those that need
  hardware this vehicle lacks: 25 messages per tick, plus TERRAIN_REQUEST at most every 2 s), at
  ArduCopter's default 0 Hz until a GCS asks with REQUEST_DATA_STREAM (MAV_DATA_STREAM_ALL: every
  stream but PARAMS). Every field comes from the plan's track (`uavcas.twin.track`) through a
  flight model (`flight`: attitude from the acceleration the track needs against drag and at its
  window boundaries, IMU specific force and rates, magnetometer, ISA barometer, motor outputs,
  battery; sensor noise from a seeded stream per UAV) built into messages by `telemetry`; the
  IMU, barometer and attitude follow the physical track, GPS_RAW_INT and GLOBAL_POSITION_INT the
  GPS receiver's fix (`gps`: a spoofer's while one is believed; the messages the attack's truth
  rule labels). It streams ArduCopter 4.6's 1095 parameters on
  PARAM_REQUEST_LIST at ArduPilot's pace and answers PARAM_REQUEST_READ (`params`). It accepts a
  mission (MISSION_COUNT -> MISSION_REQUEST_INT per item -> MISSION_ACK) and answers every
  COMMAND_LONG with COMMAND_ACK to the address it came from (`commands`: DO_CHANGE_SPEED,
  NAV_RETURN_TO_LAUNCH -> mode RTL 6, NAV_LAND -> mode LAND 9 ACCEPTED; anything else
  UNSUPPORTED), whoever sent it: a forged command is obeyed unless signing is on.
* the UAV's telemetry radio (`radio`, `bridge`; `UavSpec.radio`, filled by `uav_spec` /
  `radio_spec`): right after each autopilot heartbeat, one RADIO_STATUS (id 109) from the same
  socket to the same GCS address, unsigned, under SiK's ids (system '3' = 51, component 'D' =
  68), with SiK's fields and units: rssi / remrssi the plan's first-hop received power (snr_db +
  noise_dbm, shadowing included) plus a seeded Rician fade, in Si1000 register units
  (dBm + 127) * 1.9; noise / remnoise the noise floor (plus a jammer's power while a
  LinkOverride is active); rxerrors a saturating uint16 count of Binomial(GCS frames, planned
  loss) per second; fixed 0 (SiK's default ECC is off); txbuf SiK's % free serial buffer under
  an M/M/1 queue of the planned telemetry on the link's rate (100 when idle); a disconnected
  UAV reports rssi = noise and remrssi = remnoise = 0. Precomputed per second by the pure
  `radio.radio_reports` (a SiK pair keeps its report off the air; a WiFi bridge such as
  mavesp8266 sends it over UDP to the GCS, which is what the twin's link is: `radio`'s
  docstring). The GCS ignores it (not a UAV's sysid); captures and `uavcas mavlink` show it.
* `gcs` (ground station, in the BS's namespace, UDP 14550, all its UAVs), as MAVProxy: from a
  UAV's first datagram on, HEARTBEAT (MAV_TYPE_GCS) at 1 Hz to it; when its HEARTBEAT is heard,
  REQUEST_DATA_STREAM MAV_DATA_STREAM_ALL at `StreamRates.stream_rate_hz` (the plan's
  `mavlink_stream_hz`, default MAVProxy's `streamrate` 4), sent again every 15 s; the parameter
  download (PARAM_REQUEST_LIST, then PARAM_REQUEST_READ of the missing indices, 10 at a time,
  after 1 s without a PARAM_VALUE); the mission upload (the UAV's window-start positions as
  MAV_CMD_NAV_WAYPOINT items, relative altitude), and at every window boundary COMMAND_LONG
  MAV_CMD_DO_CHANGE_SPEED with the UAV's planned ground speed over the new window.

Retries: mission messages and commands are resent after `RetrySpec.timeout_s` (0.5 s, MAVSDK's
default MAVLink timeout), at most `mission_retries` / `command_retries` times (the command's
`confirmation` counts the resends, as the command protocol asks); a lost stream request is
repaired by the next periodic one (15 s, MAVProxy's), lost parameters by PARAM_REQUEST_READ.
Times are plan times from the run's t0 (time_boot_ms = ms since t0), which an endpoint started
before t0 reads from a file the runner writes at t0 (`write_t0`). Both ends stop at their
deadline or on SIGTERM and log JSON lines to `log_path`: one line per mission upload, command and
ack as they happen, and a final `summary` line with sent/received message counts per type.

Signing (`signing`, `UavSpec.signing` / `GcsSpec.signing`, the run option `--mavlink-signing`):
MAVLink 2 message signing with the run's key on both ends: every frame sent is signed, every
frame received unsigned or wrongly signed is dropped unanswered (and logged `rejected`).

Modules: `specs` (the typed specs and what the plan gives them), `link` (what both endpoints
share: t0, the UDP peer, the log), `streams` (ArduCopter's stream table), `flight` (the flight
state behind every field), `telemetry` (one builder per message), `params` (ArduCopter's
parameters and their pace), `autopilot` (the UAV end), `commands` (what a command does to
the autopilot's state), `signing` (MAVLink 2 signing and the run's key), `gps` (the UAV's GPS
receiver: true fixes, or a spoofer's that the `gps_spoof` attack publishes at run time), `ground`
(the GCS end), `radio` (what the UAV's radio reports, pure, from the plan), `bridge` (its sender).

Run: python -m uavcas.traffic.mavlink {uav|gcs} SPEC.json
"""

from . import gps
from .link import T0_WAIT_S, read_log, write_t0
from .signing import SigningSpec, signing_key, signing_spec
from .specs import (
    GCS_PORT,
    UAV_PORT,
    BatterySpec,
    GcsSpec,
    GcsTarget,
    RetrySpec,
    StreamRates,
    UavSpec,
    gcs_target,
    radio_spec,
    uav_spec,
)

__all__ = ["gps", "GCS_PORT", "T0_WAIT_S", "UAV_PORT", "BatterySpec", "GcsSpec", "GcsTarget", "RetrySpec",
           "SigningSpec", "StreamRates", "UavSpec", "gcs_target", "radio_spec", "read_log", "signing_key",
           "signing_spec", "uav_spec", "write_t0"]
