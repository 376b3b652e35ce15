"""Readers for the AERPAW measurement files the calibration uses, in any of their published forms.

Formats accepted for every table: MATLAB v5/v7 ``.mat`` (scipy.io.loadmat), MATLAB v7.3 ``.mat``
(HDF5; read with h5py when it is installed, otherwise refused with a one-line error saying so),
and ``.csv`` / ``.csv.gz`` with one column per 1-D array (the ``derived_csv`` conversion).

Layouts: files are found by *name* anywhere below the `--data` folder (``rglob``), so the shared
copy (``aerpaw/data_gen/...`` + ``aerpaw/derived_csv``), the upstream repository checkout
(``uav-spectrum-sensing-insights/data_gen/...``) and a flat folder of downloads all work. When a
table exists as .mat and as CSV the .mat wins (it is the original). Names recognised:

* Maeng LTE processed, one per altitude h:  ``filtererd_data_with_dist_ori_{h}_meas_rad.mat``
  (upstream spelling; ``filtered_`` accepted) or ``lte_maeng_processed_{h}m.csv[.gz]``.
* Maeng antenna pattern: ``rad_pat.mat`` holding ``G_t_dB``/``G_r_dB`` on ``theta2`` x ``phi2``.
* Multi-band processed: ``results_cole_with_tworay_tilt_src_alt_{h}m_fs{bw}MHz`` (.mat / CSV, the
  CSV carries a ``multibw_processed_data_`` prefix).
* AFAR flights: raw ``results_useful_ori_exp_{team}_loc_{k}`` and processed
  ``results_useful_with_tworay_tilt_src_exp_{team}_loc_{k}`` (.mat / CSV).

Malformed input (unreadable, missing a column, wrong length, no finite value) raises
`CalibrationDataError` whose message is one line naming the file and what is wrong.
"""

from __future__ import annotations

import gzip
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.io
from scipy.optimize import least_squares

try:
    import h5py  # optional (the `mat73` extra): only MATLAB v7.3 files need it
except ImportError:
    h5py = None


class CalibrationDataError(ValueError):
    """A measurement file that cannot be used; the message is one line naming the file."""


# ---------------------------------------------------------------------------------------------
# Generic table reading
# ---------------------------------------------------------------------------------------------


def _read_mat(path: Path) -> dict[str, np.ndarray]:
    try:
        raw = scipy.io.loadmat(str(path), squeeze_me=True)
    except NotImplementedError:  # scipy says so for v7.3 files: they are HDF5
        return _read_mat73(path)
    except Exception as e:  # scipy raises ValueError/TypeError/OSError on garbage
        raise CalibrationDataError(f"{path}: not a readable MATLAB file ({_first_line(e)})") from None
    return {k: np.asarray(v) for k, v in raw.items() if not k.startswith("__")}


def _read_mat73(path: Path) -> dict[str, np.ndarray]:
    if h5py is None:
        raise CalibrationDataError(
            f"{path}: MATLAB v7.3 (HDF5) file; install h5py or re-save it with save(..., '-v7')"
        )
    out: dict[str, np.ndarray] = {}
    with h5py.File(path, "r") as f:
        for k, v in f.items():
            if isinstance(v, h5py.Dataset) and v.dtype.kind in "fiu":
                out[k] = np.asarray(v).T.squeeze()  # MATLAB stores column-major
    return out


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    try:
        if path.name.endswith(".gz"):
            with gzip.open(path, "rb") as fh:
                df = pd.read_csv(io.BytesIO(fh.read()))
        else:
            df = pd.read_csv(path)
    except Exception as e:
        raise CalibrationDataError(f"{path}: not a readable CSV table ({_first_line(e)})") from None
    return {str(c): df[c].to_numpy() for c in df.columns}


def _first_line(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return text[0] if text else type(e).__name__


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """All arrays of a .mat / .csv / .csv.gz file, by name."""
    p = Path(path)
    if not p.is_file():
        raise CalibrationDataError(f"{p}: no such file")
    name = p.name.lower()
    if name.endswith(".mat"):
        return _read_mat(p)
    if name.endswith(".csv") or name.endswith(".csv.gz"):
        return _read_csv(p)
    raise CalibrationDataError(f"{p}: unknown format (expected .mat, .csv or .csv.gz)")


def columns(path: Path, table: dict[str, np.ndarray], names: tuple[str, ...],
            min_rows: int = 2) -> dict[str, np.ndarray]:
    """The 1-D float columns `names` of `table`, checked: present, numeric, equal length."""
    missing = [n for n in names if n not in table]
    if missing:
        raise CalibrationDataError(f"{path}: missing column(s) {', '.join(missing)}")
    out = {}
    for n in names:
        try:
            a = np.asarray(table[n], dtype=float).ravel()
        except (TypeError, ValueError):
            raise CalibrationDataError(f"{path}: column {n} is not numeric") from None
        out[n] = a
    lengths = {len(a) for a in out.values()}
    if len(lengths) != 1:
        raise CalibrationDataError(f"{path}: columns {', '.join(names)} have different lengths {sorted(lengths)}")
    if lengths.pop() < min_rows:
        raise CalibrationDataError(f"{path}: fewer than {min_rows} rows")
    if not any(np.isfinite(a).any() for a in out.values()):
        raise CalibrationDataError(f"{path}: no finite values")
    return out


def finite_rows(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Rows where every column is finite (raw logs carry -inf for undecoded frames)."""
    ok = np.logical_and.reduce([np.isfinite(a) for a in cols.values()])
    return {k: a[ok] for k, a in cols.items()}


# ---------------------------------------------------------------------------------------------
# Finding files by name under a data folder
# ---------------------------------------------------------------------------------------------

_EXT = r"\.(?:mat|csv|csv\.gz)$"


def _find(root: Path, pattern: str) -> dict[tuple, Path]:
    """Files under `root` whose name matches `pattern` (groups = key); .mat preferred over CSV."""
    rx = re.compile(pattern + _EXT, re.IGNORECASE)
    found: dict[tuple, Path] = {}
    for p in sorted(root.rglob("*")):
        m = rx.search(p.name)
        if not m or not p.is_file():
            continue
        key = m.groups()
        if key not in found or (p.suffix == ".mat" and found[key].suffix != ".mat"):
            found[key] = p
    return found


def _require_dir(root: str | Path) -> Path:
    r = Path(root)
    if not r.is_dir():
        raise CalibrationDataError(f"{r}: data folder not found")
    return r


# ---------------------------------------------------------------------------------------------
# Typed records
# ---------------------------------------------------------------------------------------------

MAENG_COLUMNS = ("RSRP_s", "RSRP_PL_free_s", "dist_3D_s", "dist_2D_new_s", "height_s", "elev_s", "azim_s", "ori_s")
MULTIBW_COLUMNS = ("power_all", "RSRP_PL_free", "dist_3D", "dist_2D_new", "h_all")
AFAR_RAW_COLUMNS = ("mX", "mY", "mZ", "mpower", "timestamp_power")
AFAR_PROC_COLUMNS = ("lat_all", "lon_all", "h_all", "dist_2D_new", "dist_3D")


@dataclass(frozen=True)
class PathLossSamples:
    """Per-sample geometry and received power of one altitude of one campaign."""

    source: Path
    campaign: str  # "maeng" | "multibw"
    altitude_m: float  # nominal flight altitude (file label)
    rx_dbm: np.ndarray  # RSRP (Maeng, dBm per resource element) or sounder power (dB)
    pred_free_dbm: np.ndarray  # the file's free-space prediction with the antenna pattern
    d3d_m: np.ndarray
    d2d_m: np.ndarray
    height_m: np.ndarray  # UAV height above ground
    elev_rad: np.ndarray | None = None
    azim_rad: np.ndarray | None = None
    ori_rad: np.ndarray | None = None
    label: str = ""

    def __len__(self) -> int:
        return len(self.rx_dbm)


@dataclass(frozen=True)
class RadiationPattern:
    """Gain tables in dB on elevation theta (deg, -90..90) x azimuth phi (deg)."""

    source: Path
    theta_deg: np.ndarray
    phi_deg: np.ndarray
    g_tx_db: np.ndarray
    g_rx_db: np.ndarray


@dataclass(frozen=True)
class AfarFlight:
    """One AFAR flight: raw log (time, lon/lat/alt, sounder power) and the rover position."""

    source: Path
    team: int
    location: int
    t_s: np.ndarray
    lon_deg: np.ndarray
    lat_deg: np.ndarray
    alt_m: np.ndarray
    power_db: np.ndarray  # uncalibrated channel-sounder power
    rover_lon_lat: tuple[float, float] | None = None
    rover_height_m: float = 1.5
    processed: Path | None = None  # the processed file the rover position came from
    extra: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        return f"{self.team}_loc_{self.location}"


def load_maeng(root: str | Path) -> list[PathLossSamples]:
    """The five Maeng altitudes (processed files), sorted by altitude."""
    r = _require_dir(root)
    found = _find(r, r"(?:filtererd|filtered)_data_with_dist_ori_(\d+)_meas_rad")
    found_csv = _find(r, r"lte_maeng_processed_(\d+)m")
    for k, p in found_csv.items():
        found.setdefault(k, p)
    if not found:
        raise CalibrationDataError(f"{r}: no Maeng LTE processed files (filtererd_data_with_dist_ori_*_meas_rad.mat or "
                                   "lte_maeng_processed_*m.csv.gz)")
    out = []
    for (h,), p in sorted(found.items(), key=lambda kv: int(kv[0][0])):
        c = finite_rows(columns(p, read_table(p), MAENG_COLUMNS))
        out.append(PathLossSamples(
            source=p, campaign="maeng", altitude_m=float(h), rx_dbm=c["RSRP_s"], pred_free_dbm=c["RSRP_PL_free_s"],
            d3d_m=c["dist_3D_s"], d2d_m=c["dist_2D_new_s"], height_m=c["height_s"], elev_rad=c["elev_s"],
            azim_rad=c["azim_s"], ori_rad=c["ori_s"], label=f"{h} m",
        ))
    return out


def load_multibw(root: str | Path) -> list[PathLossSamples]:
    """Multi-band channel-sounder flights (processed), sorted by altitude then bandwidth."""
    r = _require_dir(root)
    found = _find(r, r"results_cole_with_tworay_tilt_src_alt_(\d+)m_fs(\d+)MHz")
    if not found:
        raise CalibrationDataError(f"{r}: no multi-band processed files "
                                   "(results_cole_with_tworay_tilt_src_alt_*m_fs*MHz)")
    out = []
    for (h, bw), p in sorted(found.items(), key=lambda kv: (int(kv[0][0]), int(kv[0][1]))):
        c = finite_rows(columns(p, read_table(p), MULTIBW_COLUMNS))
        out.append(PathLossSamples(
            source=p, campaign="multibw", altitude_m=float(h), rx_dbm=c["power_all"], pred_free_dbm=c["RSRP_PL_free"],
            d3d_m=c["dist_3D"], d2d_m=c["dist_2D_new"], height_m=c["h_all"], label=f"{h} m fs {bw} MHz",
        ))
    return out


def load_pattern(root: str | Path) -> RadiationPattern | None:
    """The Maeng pattern (``rad_pat.mat`` with G_t_dB/G_r_dB); None if there is none."""
    r = _require_dir(root)
    for p in sorted(r.rglob("rad_pat.mat")):
        t = read_table(p)
        if not {"G_t_dB", "G_r_dB", "theta2", "phi2"} <= set(t):
            continue  # the AFAR/multi-band pattern file has other tables
        th, ph = np.asarray(t["theta2"], float).ravel(), np.asarray(t["phi2"], float).ravel()
        gt, gr = np.asarray(t["G_t_dB"], float), np.asarray(t["G_r_dB"], float)
        if gt.shape != (th.size, ph.size) or gr.shape != gt.shape:
            raise CalibrationDataError(f"{p}: pattern tables {gt.shape}/{gr.shape} do not match theta2 x phi2 = "
                                       f"{(th.size, ph.size)}")
        return RadiationPattern(source=p, theta_deg=th, phi_deg=ph, g_tx_db=gt, g_rx_db=gr)
    return None


_R_EARTH_M = 6371008.8


def local_xy_m(lon_deg, lat_deg, lon0: float, lat0: float) -> tuple[np.ndarray, np.ndarray]:
    """Equirectangular east/north metres about (lon0, lat0): < 1 mm error over a 1 km field."""
    x = np.radians(np.asarray(lon_deg, float) - lon0) * _R_EARTH_M * np.cos(np.radians(lat0))
    y = np.radians(np.asarray(lat_deg, float) - lat0) * _R_EARTH_M
    return x, y


def _rover_from_processed(p: Path) -> tuple[tuple[float, float], float]:
    """Rover lon/lat by least-squares trilateration of the processed file's 2-D distances,
    and its antenna height from the 3-D distances (h_rover = h_UAV - sqrt(d3^2 - d2^2))."""
    c = finite_rows(columns(p, read_table(p), AFAR_PROC_COLUMNS))
    lon0, lat0 = float(np.mean(c["lon_all"])), float(np.mean(c["lat_all"]))
    x, y = local_xy_m(c["lon_all"], c["lat_all"], lon0, lat0)
    fit = least_squares(lambda q: np.hypot(x - q[0], y - q[1]) - c["dist_2D_new"], x0=[0.0, 0.0])
    if np.sqrt(np.mean(fit.fun**2)) > 5.0:
        raise CalibrationDataError(f"{p}: distances to the rover are not consistent with one rover position")
    lon = lon0 + np.degrees(fit.x[0] / (_R_EARTH_M * np.cos(np.radians(lat0))))
    lat = lat0 + np.degrees(fit.x[1] / _R_EARTH_M)
    dz = np.sqrt(np.maximum(c["dist_3D"] ** 2 - c["dist_2D_new"] ** 2, 0.0))
    return (float(lon), float(lat)), float(np.median(c["h_all"] - dz))


def load_afar(root: str | Path) -> list[AfarFlight]:
    """All AFAR flights (raw logs), each with its rover position from the processed file."""
    r = _require_dir(root)
    raw = _find(r, r"results_useful_ori_exp_(\d+)_loc_(\d+)")
    proc = _find(r, r"results_useful_with_tworay_tilt_src_exp_(\d+)_loc_(\d+)")
    if not raw:
        raise CalibrationDataError(f"{r}: no AFAR raw flight logs (results_useful_ori_exp_*_loc_*)")
    out = []
    for key, p in sorted(raw.items(), key=lambda kv: (int(kv[0][0]), int(kv[0][1]))):
        c = finite_rows(columns(p, read_table(p), AFAR_RAW_COLUMNS, min_rows=10))
        order = np.argsort(c["timestamp_power"], kind="stable")
        t = c["timestamp_power"][order]
        keep = np.concatenate([[True], np.diff(t) > 0])  # drop duplicate time stamps
        sel = order[keep]
        rover, h_rover = (None, 1.5)
        if key in proc:
            rover, h_rover = _rover_from_processed(proc[key])
        out.append(AfarFlight(
            source=p, team=int(key[0]), location=int(key[1]), t_s=c["timestamp_power"][sel],
            lon_deg=c["mX"][sel], lat_deg=c["mY"][sel], alt_m=c["mZ"][sel], power_db=c["mpower"][sel],
            rover_lon_lat=rover, rover_height_m=h_rover, processed=proc.get(key),
        ))
    return out
