"""The streamed messages, built from one `FlightState` (pymavlink `ardupilotmega` dialect).

Each builder fills a message as ArduPilot's sender does (libraries/GCS_MAVLink/GCS_Common.cpp,
ArduCopter/GCS_Mavlink.cpp; units as MAVLink defines them: RAW_IMU/SCALED_IMU2 acceleration in
mG, rates in mrad/s, field in mGauss; SCALED_PRESSURE hPa and cdegC). Constants without a flight
meaning are what a healthy vehicle of this kind reports and say so where they are set.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pydantic import BaseModel, ConfigDict

from .flight import GRAVITY_MSS, FlightState, Sensors
from .specs import GPS_FIX_3D, GPS_SATELLITES, BatterySpec

# EKF_STATUS_REPORT flags of a healthy EKF3 in flight: attitude, horizontal and vertical velocity,
# relative and absolute horizontal position, absolute vertical position, and the predicted ones
# (ArduPilot NavEKF3 send_status_report: 0x033F is what a flying, healthy vehicle reports)
EKF_HEALTHY_FLAGS = 0x033F
EKF_VARIANCE_FLOOR = 0.02  # a converged filter's normalised innovation variances (0.5 and above is "bad")
BOARD_VCC_MV = 5000  # POWER_STATUS/HWSTATUS Vcc: the 5 V rail
POWER_BRICK_VALID = 1  # MAV_POWER_STATUS_BRICK_VALID
FREE_MEMORY_BYTES = 80000  # MEMINFO: ChibiOS heap free on an STM32F7 board after boot (order of magnitude)
RC_NEUTRAL_US = 1500  # RCn_TRIM default: sticks centred while AUTO flies
RC_CHANNELS_USED = 8
RC_UNUSED = 65535  # RC_CHANNELS: UINT16_MAX marks a channel the receiver does not have
RSSI_UNKNOWN = 255
TERRAIN_SPACING_M = 100  # TERRAIN_SPACING default


class TelemetryContext(BaseModel):
    """What the builders read besides the flight state: the vehicle's fixed facts and its sensors."""

    model_config = ConfigDict(frozen=True, extra="forbid", arbitrary_types_allowed=True)

    battery: BatterySpec
    mission_count: int
    sensors: Sensors
    custom_mode: int = 3  # AUTO


def _boot_ms(s: FlightState) -> int:
    return max(0, round(s.t_s * 1000)) & 0xFFFFFFFF


def _imu(s: FlightState) -> tuple[int, ...]:
    acc = [round(a * 1000 / GRAVITY_MSS) for a in s.accel_mps2]
    gyr = [round(g * 1000) for g in s.gyro_radps]
    mag = [round(x) for x in s.mag_mgauss]
    return (*acc, *gyr, *mag)


def _sensor_bits(m) -> int:
    return (m.MAV_SYS_STATUS_SENSOR_3D_GYRO | m.MAV_SYS_STATUS_SENSOR_3D_ACCEL | m.MAV_SYS_STATUS_SENSOR_3D_MAG
            | m.MAV_SYS_STATUS_SENSOR_GPS | m.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE | m.MAV_SYS_STATUS_SENSOR_BATTERY
            | m.MAV_SYS_STATUS_AHRS | m.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS)


def _global_position_int(m, s, c):  # velocities NED, cm/s
    f = s.fix
    return m.MAVLink_global_position_int_message(
        _boot_ms(s), round(s.lat_deg * 1e7), round(s.lon_deg * 1e7), round(s.amsl_m * 1000), round(f.z_m * 1000),
        round(f.vy_mps * 100), round(f.vx_mps * 100), round(-f.vz_mps * 100), round(f.heading_deg * 100) % 36000)


def _gps_raw_int(m, s, c):
    f = s.fix
    gs = f.groundspeed_mps
    cog = f.heading_deg if gs <= 1e-9 else math.degrees(math.atan2(f.vx_mps, f.vy_mps)) % 360.0
    return m.MAVLink_gps_raw_int_message(
        _boot_ms(s) * 1000, GPS_FIX_3D, round(s.lat_deg * 1e7), round(s.lon_deg * 1e7), round(s.amsl_m * 1000),
        100, 100, round(gs * 100), round(cog * 100) % 36000, GPS_SATELLITES)


def _local_position_ned(m, s, c):  # from the EKF origin (the site), believed
    f = s.fix
    return m.MAVLink_local_position_ned_message(_boot_ms(s), f.y_m, f.x_m, -f.z_m, f.vy_mps, f.vx_mps, -f.vz_mps)


def _attitude(m, s, c):
    g = s.gyro_radps
    return m.MAVLink_attitude_message(_boot_ms(s), s.roll_rad, s.pitch_rad, s.yaw_rad, g[0], g[1], g[2])


def _ahrs2(m, s, c):  # the secondary estimate (DCM): same attitude, the believed position
    return m.MAVLink_ahrs2_message(s.roll_rad, s.pitch_rad, s.yaw_rad, s.amsl_m, round(s.lat_deg * 1e7),
                                   round(s.lon_deg * 1e7))


def _ahrs(m, s, c):  # DCM's gyro drift estimate (omegaI) ~0, accel weight 0 (EKF flying), no renormalisation
    return m.MAVLink_ahrs_message(0.0, 0.0, 0.0, 0.0, 0.0, 0.002, 0.002)


def _vfr_hud(m, s, c):  # no wind: airspeed = ground speed; throttle in %
    return m.MAVLink_vfr_hud_message(s.groundspeed_mps, s.groundspeed_mps, round(math.degrees(s.yaw_rad)) % 360,
                                     round(s.throttle * 100), s.amsl_m, s.climb_mps)


def _sys_status(m, s, c):
    mv, ca, pct = c.battery.at(s.t_s)
    bits = _sensor_bits(m)
    return m.MAVLink_sys_status_message(bits, bits, bits, 250, mv, ca, pct, 0, 0, 0, 0, 0, 0)


def _battery_status(m, s, c):
    mv, ca, pct = c.battery.at(s.t_s)
    used_mah = round(c.battery.current_a * max(s.t_s, 0.0) / 3.6)
    cells = [65535] * 10
    cells[0] = mv  # ArduPilot reports the pack voltage in the first cell when it has no cell monitor
    return m.MAVLink_battery_status_message(0, 0, 0, 32767, cells, ca, used_mah, -1, pct)


def _raw_imu(m, s, c):
    return m.MAVLink_raw_imu_message(_boot_ms(s) * 1000, *_imu(s), 0, round(s.temperature_c * 100))


def _scaled_imu2(m, s, c):  # the second IMU: the same motion, its own noise
    n = c.sensors.noise
    acc = [a + x for a, x in zip(s.accel_mps2, c.sensors._n(n.accel_mps2))]
    gyr = [g + x for g, x in zip(s.gyro_radps, c.sensors._n(n.gyro_radps))]
    vals = ([round(a * 1000 / GRAVITY_MSS) for a in acc] + [round(g * 1000) for g in gyr]
            + [round(x) for x in s.mag_mgauss])
    return m.MAVLink_scaled_imu2_message(_boot_ms(s), *vals, round(s.temperature_c * 100))


def _scaled_pressure(m, s, c):
    return m.MAVLink_scaled_pressure_message(_boot_ms(s), s.pressure_hpa, 0.0, round(s.temperature_c * 100), 0)


def _sensor_offsets(m, s, c):  # an uncalibrated-offset board: zero offsets, the raw barometer
    return m.MAVLink_sensor_offsets_message(0, 0, 0, math.radians(c.sensors.mag.declination_deg),
                                            round(s.pressure_hpa * 100), round(s.temperature_c * 100),
                                            0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _power_status(m, s, c):
    return m.MAVLink_power_status_message(BOARD_VCC_MV, 0, POWER_BRICK_VALID)


def _meminfo(m, s, c):
    return m.MAVLink_meminfo_message(0, min(FREE_MEMORY_BYTES, 65535), FREE_MEMORY_BYTES)


def _mission_current(m, s, c):
    done = s.target_seq >= c.mission_count - 1 and s.target_distance_m < 2.0
    return m.MAVLink_mission_current_message(s.target_seq, c.mission_count,
                                             m.MISSION_STATE_COMPLETE if done else m.MISSION_STATE_ACTIVE, 1)


def _nav_controller_output(m, s, c):
    return m.MAVLink_nav_controller_output_message(
        math.degrees(s.roll_rad), math.degrees(s.pitch_rad), round(math.degrees(s.yaw_rad)) % 360,
        round(s.target_bearing_deg) % 360, min(65535, round(s.target_distance_m)), s.target_alt_m - s.fix.z_m, 0.0, 0.0)


def _position_target_global_int(m, s, c):  # the waypoint being flown to; position only (0xFFF8)
    return m.MAVLink_position_target_global_int_message(
        _boot_ms(s), m.MAV_FRAME_GLOBAL, 0xFFF8, round(s.target_lat_deg * 1e7), round(s.target_lon_deg * 1e7),
        s.target_alt_m, 0, 0, 0, 0, 0, 0, 0, 0)


def _servo_output_raw(m, s, c):  # a quad: motors on SERVO1-4, nothing on the others
    return m.MAVLink_servo_output_raw_message(_boot_ms(s) * 1000, 0, *s.motor_pwm_us, 0, 0, 0, 0)


def _rc_channels(m, s, c):
    chans = [RC_NEUTRAL_US] * RC_CHANNELS_USED + [RC_UNUSED] * (18 - RC_CHANNELS_USED)
    return m.MAVLink_rc_channels_message(_boot_ms(s), RC_CHANNELS_USED, *chans, RSSI_UNKNOWN)


def _hwstatus(m, s, c):
    return m.MAVLink_hwstatus_message(BOARD_VCC_MV, 0)


def _system_time(m, s, c):
    return m.MAVLink_system_time_message(round(s.unix_s * 1e6), _boot_ms(s))


def _terrain_report(m, s, c):  # no terrain data arrived (the GCS sends none): height unknown, blocks pending
    return m.MAVLink_terrain_report_message(round(s.lat_deg * 1e7), round(s.lon_deg * 1e7), TERRAIN_SPACING_M,
                                            0.0, s.fix.z_m, 1, 0)


def _ekf_status_report(m, s, c):
    v = EKF_VARIANCE_FLOOR + s.ekf_innovation_m / 10.0  # the hook for a believed/physical disagreement
    return m.MAVLink_ekf_status_report_message(EKF_HEALTHY_FLAGS, EKF_VARIANCE_FLOOR, v, EKF_VARIANCE_FLOOR,
                                               EKF_VARIANCE_FLOOR, 0.0)


def _vibration(m, s, c):
    x, y, z = c.sensors.vibration()
    return m.MAVLink_vibration_message(_boot_ms(s) * 1000, x, y, z, 0, 0, 0)


BUILDERS: dict[str, Callable] = {
    "GLOBAL_POSITION_INT": _global_position_int, "GPS_RAW_INT": _gps_raw_int,
    "LOCAL_POSITION_NED": _local_position_ned, "ATTITUDE": _attitude, "AHRS2": _ahrs2, "AHRS": _ahrs,
    "VFR_HUD": _vfr_hud, "SYS_STATUS": _sys_status, "BATTERY_STATUS": _battery_status, "RAW_IMU": _raw_imu,
    "SCALED_IMU2": _scaled_imu2, "SCALED_PRESSURE": _scaled_pressure, "SENSOR_OFFSETS": _sensor_offsets,
    "POWER_STATUS": _power_status, "MEMINFO": _meminfo, "MISSION_CURRENT": _mission_current,
    "NAV_CONTROLLER_OUTPUT": _nav_controller_output, "POSITION_TARGET_GLOBAL_INT": _position_target_global_int,
    "SERVO_OUTPUT_RAW": _servo_output_raw, "RC_CHANNELS": _rc_channels, "HWSTATUS": _hwstatus,
    "SYSTEM_TIME": _system_time, "TERRAIN_REPORT": _terrain_report, "EKF_STATUS_REPORT": _ekf_status_report,
    "VIBRATION": _vibration,
}


def build(m, name: str, state: FlightState, ctx: TelemetryContext):
    """Message `name` of dialect module `m` for this instant."""
    try:
        return BUILDERS[name](m, state, ctx)
    except KeyError:
        raise ValueError(f"no telemetry message {name!r}") from None


def terrain_request(m, state: FlightState):
    """TERRAIN_REQUEST for the 4x4-block grid around the vehicle (all 56 blocks missing)."""
    return m.MAVLink_terrain_request_message(round(state.lat_deg * 1e7), round(state.lon_deg * 1e7),
                                             TERRAIN_SPACING_M, (1 << 56) - 1)
