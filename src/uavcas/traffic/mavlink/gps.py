"""The UAV's GPS receiver, and what a spoofer makes it believe (the `gps_spoof` attack's realisation).

Model (`Spoofing`): while a spoofer is believed, during [start, stop), the receiver's fix is the
true track plus an offset that grows from zero at `start` at `drift_mps` along the lure's bearing
(compass degrees from the victim's planned position at the attack's planned start), until it
reaches the lure's distance, where it stays: offset(t) = min(drift_mps * (t - start), distance_m)
* (sin bearing, cos bearing, 0) in metres east, north, up. This is the spoofer's "carry-off": the
counterfeit signal starts aligned with the true one, so the fix does not jump, and is then
pulled away at a rate the receiver's own tracking follows. The reported velocity is the true one
plus the offset's rate (drift_mps along the bearing while the offset grows, nothing once it
holds); the course over ground follows that velocity. From `stop` on the receiver re-acquires
the true signal (offset 0). The vehicle's heading (GLOBAL_POSITION_INT hdg, ATTITUDE yaw) is the
compass's, not the receiver's: unchanged. The messages the fix feeds are GLOBAL_POSITION_INT
(lat, lon, alt, vx, vy, vz) and GPS_RAW_INT (lat, lon, alt, vel, cog): `POSITION_MESSAGES`.

Run time (`GpsReceiver`, in the autopilot): the attack executor publishes the spoofer's [start,
stop) in a small control file per UAV (`control_path`, JSON `Spoofing`, written atomically) with
both boundaries ahead of the moment it writes them, and logs exactly those times as the attack's
start and stop (the spoofer's side: `uavcas.attacks.tools.gps_spoofer`). Before each position
message the autopilot takes the time, then reads the file (a stat; reread when it changed), and
a fix due less than GUARD_S before a boundary waits for the boundary: so a message's spoofing is
decided by the same clock and the same numbers as the logged [start, stop), and a message decided
before a boundary has left the host (and been stamped at the victim's switch, the truth rule's
observation) before it. A message whose send still ended after a boundary its decision preceded
is counted (`straddled`) in the autopilot's log, so a run shows whether the agreement held.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from uavcas.twin.track import Track, TrackPoint

POSITION_MESSAGES: tuple[str, ...] = ("GLOBAL_POSITION_INT", "GPS_RAW_INT")  # what a GPS fix feeds
GUARD_S = 0.02  # a fix due this close before a boundary waits for it (>> the send's ~0.1 ms)


class Spoofing(BaseModel):
    """What the spoofer does to one receiver (the control file's content)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    start_unix: float
    stop_unix: float | None = None  # None: not stopped yet
    drift_mps: float = Field(gt=0)
    bearing_deg: float = Field(ge=0, lt=360)  # towards the lure, compass (0 north, clockwise)
    distance_m: float = Field(gt=0)  # the lure's distance: the offset grows no further

    def active(self, t_unix: float) -> bool:
        return self.start_unix <= t_unix and (self.stop_unix is None or t_unix < self.stop_unix)

    def _unit(self) -> tuple[float, float]:
        b = math.radians(self.bearing_deg)
        return math.sin(b), math.cos(b)

    def offset_m(self, t_unix: float) -> tuple[float, float, float]:
        """Claimed minus true position at t: (east, north, up) metres."""
        if not self.active(t_unix):
            return 0.0, 0.0, 0.0
        d = min(self.drift_mps * (t_unix - self.start_unix), self.distance_m)
        e, n = self._unit()
        return d * e, d * n, 0.0

    def drift_velocity_mps(self, t_unix: float) -> tuple[float, float, float]:
        """Claimed minus true velocity at t: the offset's rate (east, north, up)."""
        if not self.active(t_unix) or self.drift_mps * (t_unix - self.start_unix) >= self.distance_m:
            return 0.0, 0.0, 0.0
        e, n = self._unit()
        return self.drift_mps * e, self.drift_mps * n, 0.0

    def boundaries(self) -> list[float]:
        return [self.start_unix] + ([self.stop_unix] if self.stop_unix is not None else [])


def claimed(p: TrackPoint, spoof: Spoofing | None, t_unix: float) -> TrackPoint:
    """The fix the receiver reports for the true point p at t (p itself when no spoofer is believed)."""
    if spoof is None or not spoof.active(t_unix):
        return p
    (de, dn, du), (ve, vn, vu) = spoof.offset_m(t_unix), spoof.drift_velocity_mps(t_unix)
    return replace(p, x_m=p.x_m + de, y_m=p.y_m + dn, z_m=p.z_m + du, vx_mps=p.vx_mps + ve, vy_mps=p.vy_mps + vn,
                   vz_mps=p.vz_mps + vu)


def course_deg(p: TrackPoint) -> float:
    """Course over ground (GPS_RAW_INT cog): the velocity's compass bearing; at rest the track's
    heading (the last move's), as `uavcas.twin.track` defines it."""
    if p.groundspeed_mps <= 1e-9:
        return p.heading_deg
    return math.degrees(math.atan2(p.vx_mps, p.vy_mps)) % 360.0


# --- the control file: executor -> autopilot ------------------------------------------------------


def control_path(apps_dir: Path, uav: str) -> Path:
    """Where the executor publishes the spoofer of `uav` (beside the MAVLink specs and t0 file)."""
    return Path(apps_dir) / "mavlink" / f"gps-{uav}.json"


class GpsReceiver:
    """The autopilot's GPS: true fixes, or the spoofer's while the control file says so."""

    def __init__(self, path: Path | None, log: Callable[..., None] | None = None) -> None:
        self.path, self.log = path, log or (lambda *a, **k: None)
        self.spoof: Spoofing | None = None
        self._seen: tuple[int, int] | None = None
        self.spoofed = 0  # position messages sent with a spoofed fix
        self.straddled = 0  # ... whose send ended past a boundary their decision preceded

    def poll(self) -> None:
        if self.path is None:
            return
        try:
            st = self.path.stat()
            if (st.st_mtime_ns, st.st_size) == self._seen:
                return
            self.spoof = Spoofing.model_validate_json(self.path.read_text())
            self._seen = (st.st_mtime_ns, st.st_size)
        except (FileNotFoundError, ValueError):
            return  # not published (yet); the writer renames whole files, so no torn read
        self.log("gps_control", start_unix=self.spoof.start_unix, stop_unix=self.spoof.stop_unix)

    def settle(self) -> float:
        """The decision time of the next fix: taken before the control file is read (a file that
        appears after it was published >= GUARD_S before its boundary, so this fix is not near
        it); a fix due within GUARD_S before a boundary waits for the boundary."""
        while True:
            t = time.time()
            self.poll()
            near = [b for b in (self.spoof.boundaries() if self.spoof else []) if t < b <= t + GUARD_S]
            if not near:
                return t
            time.sleep(min(near) - t)

    def report(self, track: Track, t0_unix: float, send: Callable[[TrackPoint, float], None]) -> None:
        """Send one position message: `send(fix, plan time)` with this instant's fix."""
        t = self.settle()
        spoofed = self.spoof is not None and self.spoof.active(t)
        send(claimed(track.at(t - t0_unix), self.spoof, t), t - t0_unix)
        done = time.time()
        self.spoofed += spoofed
        if self.spoof is not None and any(t < b <= done for b in self.spoof.boundaries()):
            self.straddled += 1
            self.log("gps_straddled", decided_unix=t, sent_unix=done)

    def summary(self) -> dict:
        return {"spoofed": self.spoofed, "straddled": self.straddled}
