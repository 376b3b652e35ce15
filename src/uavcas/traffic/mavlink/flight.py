"""The flight state the autopilot reports: what the plan's track implies for every sensor.

Two tracks (the physical/believed split): the PHYSICAL one is where the vehicle is and how it
moves (the plan's track): IMU, gyro, magnetometer, barometer, attitude and motors follow it. The
BELIEVED one is the GPS receiver's fix (`fix`: `gps.claimed`, the spoofer's offset while one is
believed). Today the fix goes into GPS_RAW_INT and GLOBAL_POSITION_INT only (the autopilot
builds those from the receiver's report of their own instant), because those are the messages
the `gps_spoof` attack's truth rule labels; LOCAL_POSITION_NED, AHRS2's position, TERRAIN_REPORT
and the navigation to the next waypoint read `fix` too, and get the physical track from the
autopilot, so that no unlabelled message carries a spoofed position. A later change that labels
them can hand them the receiver's fix. `ekf_innovation_m` is where a later model can feed the
filter's disagreement between the two into EKF_STATUS_REPORT; it is 0 for now.

Attitude model. Positions are the track's (piecewise linear, velocity v_k constant in window k).
A copter holds v against drag by tilting: SITL's default multicopter (ArduPilot
libraries/SITL/SIM_Frame.h, commit 07b1fa1a, Model refSpd 15.08 m/s at refAngle 45 deg, i.e.
quadratic drag with a_drag(15.08 m/s) = g tan 45) needs a_drag = g tan(refAngle) (|v|/refSpd)^2
along v. At a window boundary the velocity changes by dv; ArduCopter's waypoint controller
accelerates at WPNAV_ACCEL (250 cm/s^2) horizontally and WPNAV_ACCEL_Z (100 cm/s^2) vertically
(4.6 defaults, params.py), so for |dv| / WPNAV_ACCEL seconds after the boundary the vehicle also
accelerates along dv at that rate (its reported positions stay the plan's: the track is the
contract, and the transition only shows in attitude, IMU and motors). The thrust then points
along T = a_needed + (0, 0, g) (ENU, a_needed = transition + drag); with yaw = the track's heading
psi, forward/right components (a_f, a_r) give pitch = atan2(-a_f, g + a_u) and roll =
asin(a_r / |T|) (Z-Y-X Euler, ArduPilot's convention). Body rates are 0 (attitude constant
between these steps). The accelerometer measures the specific force a_kin - g (NED), rotated into
the body frame: at constant speed it reads the drag as a backward force. Motor output: throttle =
MOT_THST_HOVER * |T| / g, PWM = MOT_PWM_MIN + (MOT_SPIN_MIN + (MOT_SPIN_MAX - MOT_SPIN_MIN) *
throttle) * (MOT_PWM_MAX - MOT_PWM_MIN) (AP_MotorsMulticopter's output scaling, linear thrust).
The magnetometer reads a fixed Earth field at the site (`MagField`) rotated into the body frame.
Barometer: ISA pressure and temperature at the altitude (ICAO Doc 7488).

Noise comes from a named seeded stream per UAV (`uavcas.seeding`: plan seed, "mavlink-sensors",
UAV index), drawn in the order the messages are built; its sizes (`SensorNoise`) are datasheet
values of the parts a Pixhawk-class board carries, not fitted to anything.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from uavcas.twin.track import Track, TrackPoint, local_to_geodetic

from .params import default_value

GRAVITY_MSS = 9.80665  # ArduPilot's GRAVITY_MSS
REF_SPEED_MPS = 15.08  # SIM_Frame.h Model.refSpd
REF_ANGLE_DEG = 45.0  # SIM_Frame.h Model.refAngle
WPNAV_ACCEL_MSS = default_value("WPNAV_ACCEL") / 100.0
WPNAV_ACCEL_Z_MSS = default_value("WPNAV_ACCEL_Z") / 100.0
MOT_THST_HOVER = default_value("MOT_THST_HOVER")
MOT_PWM_MIN, MOT_PWM_MAX = default_value("MOT_PWM_MIN"), default_value("MOT_PWM_MAX")
MOT_SPIN_MIN, MOT_SPIN_MAX = default_value("MOT_SPIN_MIN"), default_value("MOT_SPIN_MAX")
ISA_P0_PA, ISA_T0_K, ISA_LAPSE_K_PER_M = 101325.0, 288.15, 0.0065


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class MagField(_Frozen):
    """The Earth's field at the site (default: the AERPAW LW1 site, NOAA WMM2020 for 2024,
    rounded: 50 uT, inclination 64 deg down, declination 9 deg west)."""

    intensity_mgauss: float = 500.0
    inclination_deg: float = 64.0
    declination_deg: float = -9.0

    def ned(self) -> tuple[float, float, float]:
        i, d = math.radians(self.inclination_deg), math.radians(self.declination_deg)
        return (self.intensity_mgauss * math.cos(i) * math.cos(d), self.intensity_mgauss * math.cos(i) * math.sin(d),
                self.intensity_mgauss * math.sin(i))


class SensorNoise(_Frozen):
    """1-sigma noise of each reading, after ArduPilot's default 20 Hz IMU filters (INS_ACCEL_FILTER,
    INS_GYRO_FILTER): ICM-20602 noise density 100 ug/sqrt(Hz) and 0.004 deg/s/sqrt(Hz) over the
    filter's noise bandwidth (1.57 * 20 Hz); MS5611 RMS resolution 0.012 mbar at OSR 4096;
    a magnetometer's 2 mGauss. `vibration_mps2` is what VIBRATION reports per axis, a
    well-mounted frame (ArduPilot's wiki: below 15 m/s/s is good; 30 the limit)."""

    accel_mps2: float = 100e-6 * GRAVITY_MSS * math.sqrt(1.57 * 20)
    gyro_radps: float = math.radians(0.004) * math.sqrt(1.57 * 20)
    pressure_pa: float = 1.2
    mag_mgauss: float = 2.0
    vibration_mps2: tuple[float, float, float] = (3.0, 3.0, 5.0)


class FlightState(_Frozen):
    """Everything the telemetry builders read, at one instant (units in the names; NED/FRD where
    MAVLink wants them)."""

    t_s: float  # plan time
    unix_s: float
    window: int = Field(ge=0)  # the window being flown
    # physical
    roll_rad: float
    pitch_rad: float
    yaw_rad: float
    gyro_radps: tuple[float, float, float]  # body FRD rates
    accel_mps2: tuple[float, float, float]  # specific force, body FRD
    mag_mgauss: tuple[float, float, float]  # body FRD
    pressure_hpa: float
    temperature_c: float
    throttle: float  # 0..1 of the motors' range
    motor_pwm_us: tuple[int, int, int, int]
    alt_m: float  # physical altitude above the site (the barometer's)
    climb_mps: float
    # believed (GPS-fed)
    fix: TrackPoint
    lat_deg: float
    lon_deg: float
    amsl_m: float
    groundspeed_mps: float
    # navigation to the next waypoint (from the believed position)
    target_seq: int
    target_lat_deg: float
    target_lon_deg: float
    target_alt_m: float  # above the site
    target_bearing_deg: float
    target_distance_m: float
    ekf_innovation_m: float = 0.0  # believed vs physical, as the filter sees it: 0 for now


def needed_acceleration(track: Track, t_s: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(kinematic acceleration, thrust acceleration minus gravity's share) ENU m/s^2 at t: the
    WPNAV transition after a window boundary, plus the drag the tilt holds the speed against."""
    p = track.at(t_s)
    k = track._segment(t_s)
    akin = [0.0, 0.0, 0.0]
    if k > 0:
        v0, v1 = track._velocity(k - 1), track._velocity(k)
        dt = t_s - track.times_s[k]
        dh = (v1[0] - v0[0], v1[1] - v0[1])
        mag = math.hypot(*dh)
        if mag > 1e-9 and dt < mag / WPNAV_ACCEL_MSS:
            akin[0], akin[1] = dh[0] / mag * WPNAV_ACCEL_MSS, dh[1] / mag * WPNAV_ACCEL_MSS
        dz = v1[2] - v0[2]
        if abs(dz) > 1e-9 and dt < abs(dz) / WPNAV_ACCEL_Z_MSS:
            akin[2] = math.copysign(WPNAV_ACCEL_Z_MSS, dz)
    gs = p.groundspeed_mps
    drag = GRAVITY_MSS * math.tan(math.radians(REF_ANGLE_DEG)) * (gs / REF_SPEED_MPS) ** 2
    athr = list(akin)
    if gs > 1e-9:
        athr[0] += drag * p.vx_mps / gs
        athr[1] += drag * p.vy_mps / gs
    return tuple(akin), tuple(athr)  # type: ignore[return-value]


def _rotate_to_body(v_ned, roll: float, pitch: float, yaw: float) -> tuple[float, float, float]:
    """R^T v for R = Rz(yaw) Ry(pitch) Rx(roll) (body FRD -> NED)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    n, e, d = v_ned
    x = cp * cy * n + cp * sy * e - sp * d
    y = (sr * sp * cy - cr * sy) * n + (sr * sp * sy + cr * cy) * e + sr * cp * d
    z = (cr * sp * cy + sr * sy) * n + (cr * sp * sy - sr * cy) * e + cr * cp * d
    return x, y, z


def isa(alt_amsl_m: float) -> tuple[float, float]:
    """(pressure Pa, temperature deg C) of the ICAO standard atmosphere below 11 km."""
    t_k = ISA_T0_K - ISA_LAPSE_K_PER_M * alt_amsl_m
    return ISA_P0_PA * (t_k / ISA_T0_K) ** 5.25588, t_k - 273.15


class Sensors:
    """One UAV's sensor model: its seeded noise stream, the site's field, the noise sizes."""

    def __init__(self, rng: np.random.Generator, site_alt_m: float, mag: MagField = MagField(),
                 noise: SensorNoise = SensorNoise()) -> None:
        self.rng, self.site_alt_m, self.mag, self.noise = rng, site_alt_m, mag, noise

    def _n(self, sigma: float, k: int = 3) -> list[float]:
        return [float(x) for x in self.rng.normal(0.0, sigma, k)]

    def state(self, track: Track, site, t_s: float, unix_s: float, fix: TrackPoint,
              waypoints: list[tuple[float, float, float]]) -> FlightState:
        """The state at plan time t: physical from `track`, believed from the GPS `fix`."""
        p = track.at(t_s)
        akin, athr = needed_acceleration(track, t_s)
        yaw = math.radians(p.heading_deg)
        # thrust direction in (forward, right, up) of the heading frame
        a_f = athr[1] * math.cos(yaw) + athr[0] * math.sin(yaw)
        a_r = -athr[1] * math.sin(yaw) + athr[0] * math.cos(yaw)
        up = GRAVITY_MSS + athr[2]
        thrust = math.sqrt(a_f * a_f + a_r * a_r + up * up)
        pitch, roll = math.atan2(-a_f, up), math.asin(max(-1.0, min(1.0, a_r / thrust)))
        f_ned = (akin[1], akin[0], -(GRAVITY_MSS + akin[2]))  # specific force, NED
        acc = [a + n for a, n in zip(_rotate_to_body(f_ned, roll, pitch, yaw), self._n(self.noise.accel_mps2))]
        gyro = self._n(self.noise.gyro_radps)
        mag = [a + n for a, n in zip(_rotate_to_body(self.mag.ned(), roll, pitch, yaw), self._n(self.noise.mag_mgauss))]
        press_pa, temp_c = isa(self.site_alt_m + p.z_m)
        press_pa += self._n(self.noise.pressure_pa, 1)[0]
        throttle = min(1.0, MOT_THST_HOVER * thrust / GRAVITY_MSS)
        actuator = MOT_SPIN_MIN + (MOT_SPIN_MAX - MOT_SPIN_MIN) * throttle
        pwm = round(MOT_PWM_MIN + actuator * (MOT_PWM_MAX - MOT_PWM_MIN))
        lat, lon, amsl = local_to_geodetic(site, fix.x_m, fix.y_m, fix.z_m)
        k = track._segment(t_s)
        seq = min(k + 1, len(waypoints) - 1)
        tlat, tlon, talt = waypoints[seq]
        tx, ty = track.positions_m[seq][0], track.positions_m[seq][1]
        dx, dy = tx - fix.x_m, ty - fix.y_m
        return FlightState(
            t_s=t_s, unix_s=unix_s, window=k, roll_rad=roll, pitch_rad=pitch,
            yaw_rad=math.atan2(math.sin(yaw), math.cos(yaw)), gyro_radps=tuple(gyro), accel_mps2=tuple(acc),
            mag_mgauss=tuple(mag), pressure_hpa=press_pa / 100.0, temperature_c=temp_c, throttle=throttle,
            motor_pwm_us=(pwm, pwm, pwm, pwm), alt_m=p.z_m, climb_mps=p.vz_mps, fix=fix, lat_deg=lat, lon_deg=lon,
            amsl_m=amsl, groundspeed_mps=fix.groundspeed_mps, target_seq=seq, target_lat_deg=tlat,
            target_lon_deg=tlon, target_alt_m=talt, target_bearing_deg=math.degrees(math.atan2(dx, dy)) % 360.0,
            target_distance_m=math.hypot(dx, dy))

    def vibration(self) -> tuple[float, float, float]:
        return tuple(max(0.0, v + x) for v, x in zip(self.noise.vibration_mps2, self._n(0.1)))  # type: ignore[return-value]
