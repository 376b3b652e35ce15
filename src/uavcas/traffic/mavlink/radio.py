"""The UAV's telemetry radio: what it reports in RADIO_STATUS, per second, from the plan (pure).

Which radio, and where its report enters. The fields, units, counters and ids are those of the
SiK firmware of the 3DR / HM-TRP Si1000 radios (ArduPilot/SiK, commit 50189f2990a9, 2023-10-29,
"added basic CI build"; every SiK citation below is that commit):

* message: RADIO_STATUS, id 109, common dialect (Firmware/radio/mavlink.c:
  MAVLINK_MSG_ID_RADIO_STATUS 109, CRC extra 185). SiK never sends RADIO (166, ardupilotmega);
  it only answers a PROTOCOL_VERSION request with PROTOCOL_VERSION (id 300), which no endpoint
  here sends.
* ids: system '3' = 51, component 'D' = 68 ("use '3D' for 3DRadio": RADIO_SOURCE_SYSTEM and
  RADIO_SOURCE_COMPONENT in mavlink.c). Ground stations key the unit conversion on them:
  QGroundControl converts rssi/remrssi to dBm only when sysid == '3' and compid == 'D'
  (src/Vehicle/Vehicle.cc, Vehicle::_handleRadioStatus; older releases in MAVLinkProtocol.cc).
  Every SiK radio has these ids: a capture tells two UAVs' radios apart by their addresses, as
  a real one would (a UAV whose own sysid is 51, uav50, shares it with every radio).
* rate: SiK injects one report after each MAVLink heartbeat it sees on its serial input
  (packet.c check_response sets seen_mavlink; tdm.c's loop calls MAVLink_report() and clears
  it), i.e. at the autopilot's 1 Hz heartbeat; the MAVLink version is the heartbeat's (2 here).
  The frame is unsigned (mavlink.c writes incompat flags 0); signing receivers accept an
  unsigned RADIO_STATUS (ArduPilot GCS_Signing.cpp accept_unsigned_callback; `signing.py`).
* fields (mavlink.c MAVLink_report): rssi = statistics.average_rssi, remrssi =
  remote_statistics.average_rssi, noise / remnoise = the average_noise of each end, txbuf =
  serial_read_space(), rxerrors = errors.rx_errors, fixed = errors.corrected_packets.

Where it enters. A SiK radio writes its report to its own serial port (mavlink.c:
serial_write_buf), i.e. to the autopilot on the aircraft and to the GCS on the ground, and
ArduPilot does not forward RADIO_STATUS (libraries/GCS_MAVLink/MAVLink_routing.cpp,
check_and_forward: "don't forward RADIO packets", ArduPilot/ardupilot 6dc77c97ce52): a SiK
pair puts no report on the air. A WiFi MAVLink bridge does: mavesp8266 (MavESP8266GCS::
readMessage / _sendRadioStatus) is the vehicle's UDP endpoint and sends RADIO_STATUS at 1 Hz
to the GCS from the same UDP socket as the vehicle's traffic. The twin's air link is a WiFi one
and the UAV's namespace is its UDP endpoint, so the report is modelled where such a bridge
sends it: on the UAV end, from the autopilot's own socket (UDP 14550) to its GCS, one datagram
after each heartbeat. In a capture it is part of the UAV's MAVLink flow (same 5-tuple), which
crosses the emulated air link and can be lost on it like any other datagram; its contents are
SiK's (ids, units, counters) because SiK's are the documented ones.

Values (`radio_reports`), per UAV and second k (t = k s, the k-th heartbeat), from the plan:
* the radio's link is the first hop of the UAV's benign route to its BS (Route.hops[0] ->
  hops[1]) in the window holding t; its received power is P_rx = snr_db + noise_dbm, which is
  P_tx + G_tx + G_rx - pathloss_db with the plan's shadowing already in pathloss_db
  (`channel.linkchain.ChainedLinks`): the channel's numbers, not a second channel.
* small-scale fading: one Rician power gain g per end and report (E g = 1), with the K factor
  the profile's fading model gives at the link's aerial end (`channel.fading.KFactorProfile`,
  the altitude the chain uses: the UAV's for UAV-BS, the higher UAV's for UAV-UAV), drawn from
  the named stream `seeding.generator(plan.seed, RADIO_STREAM, uav index)` (the profile is
  found by the plan's recorded name and SHA-256, `plan_fading`; none found: no fading). rssi
  is the local end's P_rx + g_local, remrssi the peer's P_rx + g_remote (the path is
  reciprocal; the two ends' averages are taken at different instants, so their fades are
  independent draws). SiK smooths the register over received packets (tdm.c: avg = (last +
  7 avg) / 8); one draw per report stands for that average, which overstates its spread (no
  per-packet model here).
* units: the Si1000 RSSI register, dBm = units / 1.9 - 127 (QGroundControl Vehicle.cc, citing
  the Si1000 datasheet fig. 23.25 and Silicon Labs AN474), so units = round((dBm + 127) * 1.9),
  clipped to 0..255 (the register and the field are uint8; radio_443x.c reads
  EZRADIOPRO_RECEIVED_SIGNAL_STRENGTH_INDICATOR into last_rssi). SiK measures noise with the
  same register (tdm.c: average_noise from radio_current_rssi()), so noise and remnoise are the
  noise floor (the scenario's noise_dbm) in the same units, raised by a jammer's power at that
  end while a plan LinkOverride of that direction is active.
* rxerrors: SiK counts a receive error per air packet that fails its checks and saturates at
  0xFFFF (radio_443x.c: `if (errors.rx_errors != 0xFFFF) errors.rx_errors++`). Per second,
  Binomial(rx_frames_per_s, loss) new errors, loss the planned loss of the peer -> UAV
  direction (a LinkOverride's while it jams), accumulated from 0 at t0 and saturated the same way.
* fixed: corrected_packets counts packets repaired by the Golay code, which runs only with ECC
  on, and SiK's default is ECC 0 (parameters.c: {"ECC", 0}): a default radio reports 0.
* txbuf: serial_read_space() = % free of the radio's serial input buffer (serial.c:
  RX_BUFF_MAX 1850 bytes for the Si1000, in 8-byte steps: 100 * (free / 8) / (1850 / 8)). The
  queue is modelled as M/M/1 at utilisation rho = offered_bps / (rate_mbps * 1e6): mean
  occupancy rho / (1 - rho) frames of the UAV's mean MAVLink frame, capped at the buffer (full
  when rho >= 1). At the planned MAVLink load (kB/s) against the link's Mb/s, txbuf is 100, as
  on an idle SiK radio; it falls only on a link near saturation.
* disconnected (the route is marked disconnected, no first hop): the radio still reports
  (tdm.c keeps calling MAVLink_report), its receiver reads the background (rssi = noise), and
  with no peer heard SiK clears remote_statistics (tdm.c: memset when unlock_count > 5):
  remrssi = remnoise = 0. No frames arrive, so rxerrors does not grow; txbuf stays at its
  idle 100: tdm.c's transmit path takes the next packet from the serial buffer
  (packet_get_next) in each of its transmit windows without checking that the peer is locked,
  so the buffer drains whether or not anyone hears.
  ArduPilot reads remrssi == 0 as "the GCS hears no radio" (GCS_Common.cpp
  handle_radio_status records last_radio_status.remrssi_ms only when remrssi != 0).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field
from pymavlink.dialects.v20 import ardupilotmega, common

from uavcas import seeding
from uavcas.channel.fading import KFactorProfile
from uavcas.twin.model import Link, Plan, Window
from uavcas.twin.profile import ProfileError, load_profile, profile_sha256

RADIO_STREAM = "radio-status"  # the named stream of the reports' fading and error draws
SIK_SYSID = ord("3")  # SiK mavlink.c RADIO_SOURCE_SYSTEM '3' = 51
SIK_COMPID = ord("D")  # SiK mavlink.c RADIO_SOURCE_COMPONENT 'D' = 68
REPORT_PERIOD_S = 1.0  # one report per autopilot heartbeat (SiK tdm.c/packet.c; module docstring)
RSSI_OFFSET_DBM = -127.0  # dBm = units / 1.9 - 127 (QGroundControl Vehicle.cc; Si1000 datasheet fig. 23.25)
RSSI_UNITS_PER_DB = 1.9
SERIAL_BUFFER_BYTES = 1850  # SiK serial.c RX_BUFF_MAX for the Si1000 (not CPU_SI1030)
MAVLINK2_OVERHEAD_BYTES = 12  # MAVLink 2 frame: 10 bytes of header + 2 of CRC (unsigned)
COUNTER_MAX = 0xFFFF  # SiK radio_443x.c: the uint16 error counters saturate, never wrap


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class RadioReport(_Frozen):
    """One RADIO_STATUS's field values, in the radio's units (module docstring)."""

    t_s: float  # plan time of the heartbeat it follows
    rssi: int = Field(ge=0, le=255)
    remrssi: int = Field(ge=0, le=255)
    txbuf: int = Field(ge=0, le=100)
    noise: int = Field(ge=0, le=255)
    remnoise: int = Field(ge=0, le=255)
    rxerrors: int = Field(ge=0, le=COUNTER_MAX)
    fixed: int = Field(ge=0, le=COUNTER_MAX)


class HopBudget(_Frozen):
    """The UAV's first hop in one window, as the plan's channel computed it (module docstring)."""

    window: int
    peer: str | None  # next hop; None: the route is disconnected
    rx_dbm: float | None  # received power at either end: snr_db + noise_dbm
    k_db: float | None  # Rician K at the aerial end; None: the profile has no fading
    loss: float  # planned residual loss of each direction (the link's; 1.0 with no link)
    rate_mbps: float  # the link's planned rate (0 with no link)


class RadioSpec(_Frozen):
    """What the autopilot's radio sends: its ids and the precomputed reports, one per second."""

    sysid: int = Field(default=SIK_SYSID, ge=1, le=255)
    compid: int = Field(default=SIK_COMPID, ge=0, le=255)
    reports: list[RadioReport]

    def report_at(self, t_s: float) -> RadioReport | None:
        """The report of the heartbeat at plan time t (second k = floor(t)); past the plan (an
        endpoint runs a little longer than it) the last one: its last window's state persists.
        None only when there are no reports."""
        if not self.reports:
            return None
        k = max(0, math.floor(t_s / REPORT_PERIOD_S + 1e-6))
        return self.reports[min(k, len(self.reports) - 1)]


def dbm_to_units(dbm: float) -> int:
    """SiK's RSSI register value for a power in dBm: round((dBm + 127) * 1.9), clipped to uint8."""
    return int(min(255, max(0, round((dbm - RSSI_OFFSET_DBM) * RSSI_UNITS_PER_DB))))


def units_to_dbm(units: float) -> float:
    """The inverse (QGroundControl's conversion, without its [-120, 0] clamp)."""
    return units / RSSI_UNITS_PER_DB + RSSI_OFFSET_DBM


def txbuf_percent(offered_bps: float, rate_mbps: float, frame_bytes: float) -> int:
    """serial_read_space() of an M/M/1 queue at rho = offered / rate (module docstring)."""
    if offered_bps <= 0:
        used = 0.0
    elif rate_mbps <= 0 or offered_bps >= rate_mbps * 1e6:
        used = float(SERIAL_BUFFER_BYTES)
    else:
        rho = offered_bps / (rate_mbps * 1e6)
        used = min(float(SERIAL_BUFFER_BYTES), rho / (1.0 - rho) * frame_bytes)
    free = SERIAL_BUFFER_BYTES - int(math.ceil(used))
    return (100 * (free // 8)) // (SERIAL_BUFFER_BYTES // 8)  # serial.c's integer steps


def _bs_of(plan: Plan, uav: str) -> str:
    """The UAV's base station: UAV i <-> BS i mod n_bs (`twin.plan`)."""
    bss = [n.name for n in plan.nodes if n.kind == "bs"]
    return bss[plan.node(uav).index % len(bss)]


def _link(window: Window, a: str, b: str) -> Link | None:
    for link in window.links:
        if {link.a, link.b} == {a, b} and link.kind == "air":
            return link
    return None


def _aerial_altitude_m(plan: Plan, window: Window, a: str, b: str) -> float:
    """The link's aerial end's altitude, as the channel chain takes it (`channel.geometry`)."""
    kind = {n.name: n.kind for n in plan.nodes}
    za, zb = window.positions[a][2], window.positions[b][2]
    if (kind[a] == "bs") != (kind[b] == "bs"):
        return zb if kind[a] == "bs" else za
    return max(za, zb)


def plan_fading(plan: Plan) -> KFactorProfile | None:
    """The K model of the profile the plan was made with, found by the name the plan records and
    checked against its recorded SHA-256. None when it has none, or when that name finds no
    profile or another one (a profile read from a file under another name, or since edited):
    the reports then carry no fading rather than another profile's."""
    try:
        prof = load_profile(plan.profile)
    except ProfileError:
        return None
    if plan.profile_sha256 is not None and profile_sha256(prof) != plan.profile_sha256:
        return None
    return prof.channel.fading


def first_hop_budgets(plan: Plan, uav: str,
                      fading: KFactorProfile | None | Literal["plan"] = "plan") -> list[HopBudget]:
    """Per window, the UAV's first hop towards its BS and its planned budget (module docstring).
    `fading`: the K model ("plan": `plan_fading`; None: no fading)."""
    if fading == "plan":
        fading = plan_fading(plan)
    noise_dbm = plan.scenario.noise_dbm
    bs = _bs_of(plan, uav)
    out = []
    for w in plan.windows:
        route = next((r for r in w.routes if r.src == uav and r.dst == bs), None)
        link = None
        if route is not None and not route.disconnected and len(route.hops) >= 2:
            link = _link(w, route.hops[0], route.hops[1])
        if link is None or link.snr_db is None:
            out.append(HopBudget(window=w.index, peer=None, rx_dbm=None, k_db=None, loss=1.0, rate_mbps=0.0))
            continue
        peer = link.b if link.a == uav else link.a
        k_db = None if fading is None else float(fading.at(_aerial_altitude_m(plan, w, uav, peer)))
        out.append(HopBudget(window=w.index, peer=peer, rx_dbm=link.snr_db + noise_dbm, k_db=k_db,
                             loss=link.loss, rate_mbps=link.rate_mbps))
    return out


def _fade_db(rng: np.random.Generator, k_db: float | None) -> float:
    """One Rician power gain in dB, E g = 1: (2 (K + 1)) g ~ noncentral chi2(2, 2K) (`channel.fading`)."""
    if k_db is None:
        return 0.0
    k = 10.0 ** (k_db / 10.0)
    return 10.0 * math.log10(max(rng.noncentral_chisquare(2, 2.0 * k) / (2.0 * (k + 1.0)), 1e-30))


def _jammed(window: Window, src: str, dst: str, t_s: float):
    """The LinkOverride of direction src -> dst active at t, if any (a jammer: `twin.interference`)."""
    for o in window.link_overrides:
        if o.src == src and o.dst == dst and o.start_s <= t_s < o.stop_s:
            return o
    return None


def _noise_dbm(noise_dbm: float, override) -> float:
    if override is None:
        return noise_dbm
    return 10.0 * math.log10(10.0 ** (noise_dbm / 10.0) + 10.0 ** (override.interference_dbm / 10.0))


def radio_reports(plan: Plan, uav: str, offered_bps: float, frame_bytes: float, rx_frames_per_s: float,
                  fading: KFactorProfile | None | Literal["plan"] = "plan") -> list[RadioReport]:
    """The UAV radio's RADIO_STATUS values for each second of the plan (module docstring).

    offered_bps: the UAV's planned MAVLink load into its radio (bits/s), frame_bytes its mean
    frame; rx_frames_per_s: air frames per second the UAV's radio receives from its peer."""
    budgets = first_hop_budgets(plan, uav, fading)
    rng = seeding.generator(plan.seed, RADIO_STREAM, plan.node(uav).index)
    noise_dbm = plan.scenario.noise_dbm
    n = int(math.ceil(plan.duration_s / REPORT_PERIOD_S - 1e-9))
    rxerrors, out = 0, []
    for k in range(n):
        t = k * REPORT_PERIOD_S
        w_index = min(int(t // plan.window_s), len(plan.windows) - 1)
        window, hop = plan.windows[w_index], budgets[w_index]
        fade_local, fade_remote = _fade_db(rng, hop.k_db), _fade_db(rng, hop.k_db)
        if hop.peer is None:
            floor = dbm_to_units(noise_dbm)
            out.append(RadioReport(t_s=t, rssi=floor, remrssi=0, txbuf=100, noise=floor, remnoise=0,
                                   rxerrors=rxerrors, fixed=0))
            continue
        down, up = _jammed(window, hop.peer, uav, t), _jammed(window, uav, hop.peer, t)
        loss_down = hop.loss if down is None else down.loss
        rate = hop.rate_mbps if up is None else up.rate_mbps
        rxerrors = min(COUNTER_MAX, rxerrors + int(rng.binomial(max(0, round(rx_frames_per_s * REPORT_PERIOD_S)),
                                                                min(1.0, max(0.0, loss_down)))))
        out.append(RadioReport(
            t_s=t, rssi=dbm_to_units(hop.rx_dbm + fade_local), remrssi=dbm_to_units(hop.rx_dbm + fade_remote),
            txbuf=txbuf_percent(offered_bps, rate, frame_bytes),
            noise=dbm_to_units(_noise_dbm(noise_dbm, down)), remnoise=dbm_to_units(_noise_dbm(noise_dbm, up)),
            rxerrors=rxerrors, fixed=0))
    return out


def message(report: RadioReport):
    """The report as pymavlink's RADIO_STATUS (packed by the sender's MAVLink object, its ids)."""
    return common.MAVLink_radio_status_message(report.rssi, report.remrssi, report.txbuf, report.noise,
                                               report.remnoise, report.rxerrors, report.fixed)


def mavlink_load(rates_hz: dict[str, float]) -> tuple[float, float]:
    """(offered bits/s, mean frame bytes) of MAVLink 2 messages sent at these rates: each frame
    is its payload (pymavlink's full, untruncated length) + 12 bytes (10 of header, 2 of CRC)."""
    sizes = {name: getattr(ardupilotmega, f"MAVLink_{name.lower()}_message").unpacker.size + MAVLINK2_OVERHEAD_BYTES
             for name in rates_hz}
    frames = sum(rates_hz.values())
    bytes_per_s = sum(rates_hz[name] * sizes[name] for name in rates_hz)
    return 8.0 * bytes_per_s, (bytes_per_s / frames if frames > 0 else 0.0)
