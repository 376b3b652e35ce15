"""Loaders of external IDS datasets mapped onto our feature names (the `cic` standard's).

Each loader returns one row per flow with the 47 `cic` feature columns (`uavcas.flows.standards.cic`; NaN
where the dataset has no counterpart) in the `cic` standard's units (times in microseconds,
lengths in TCP/UDP payload bytes), plus `label` (the dataset's own class string), `label_binary`
(0 benign / 1 attack) and `source`. Which features exist is in `MAPPED_<NAME>`.

- CICIDS2017: both the original CIC "MachineLearningCVE" CSVs (names with leading spaces,
  "Total Fwd Packets") and the improved re-extraction (Engelen et al.: "Total Fwd Packet",
  "CWR Flag Count"). These ARE CICFlowMeter features, so values are taken as they are: our `cic`
  standard computes the same definitions in the same units. Benign: label 'BENIGN'.
- UNSW-NB15 (training/testing set CSVs): dur (s -> us), spkts/dpkts, sbytes/dbytes, smean/dmean,
  sinpkt/dinpkt (mean inter-packet time, ms -> us), rate (packets/s); derived: Flow Bytes/s,
  Down/Up Ratio, Average Packet Size. Argus-based, so only approximately the CIC quantities
  (its byte counts include headers). Multiclass label = attack_cat ('Normal' = benign).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from uavcas.flows.standards.cic import FEATURES

US_PER_S = 1e6
# our name -> (candidate source names after stripping spaces, unit factor)
_CIC: dict[str, tuple[tuple[str, ...], float]] = {
    "Flow Duration": (("Flow Duration",), 1.0),
    "Flow Bytes/s": (("Flow Bytes/s",), 1.0),
    "Flow Packets/s": (("Flow Packets/s",), 1.0),
    "Flow IAT Mean": (("Flow IAT Mean",), 1.0),
    "Flow IAT Std": (("Flow IAT Std",), 1.0),
    "Flow IAT Max": (("Flow IAT Max",), 1.0),
    "Flow IAT Min": (("Flow IAT Min",), 1.0),
    "Min Packet Length": (("Min Packet Length", "Packet Length Min"), 1.0),
    "Max Packet Length": (("Max Packet Length", "Packet Length Max"), 1.0),
    "Packet Length Mean": (("Packet Length Mean",), 1.0),
    "Packet Length Std": (("Packet Length Std",), 1.0),
    "Packet Length Variance": (("Packet Length Variance",), 1.0),
    "FIN Flag Count": (("FIN Flag Count",), 1.0),
    "SYN Flag Count": (("SYN Flag Count",), 1.0),
    "RST Flag Count": (("RST Flag Count",), 1.0),
    "PSH Flag Count": (("PSH Flag Count",), 1.0),
    "ACK Flag Count": (("ACK Flag Count",), 1.0),
    "URG Flag Count": (("URG Flag Count",), 1.0),
    "CWE Flag Count": (("CWE Flag Count", "CWR Flag Count"), 1.0),
    "ECE Flag Count": (("ECE Flag Count",), 1.0),
    "Down/Up Ratio": (("Down/Up Ratio",), 1.0),
    "Average Packet Size": (("Average Packet Size",), 1.0),
    "Active Mean": (("Active Mean",), 1.0),
    "Idle Mean": (("Idle Mean",), 1.0),
    "Idle Max": (("Idle Max",), 1.0),
    "Total Fwd Packets": (("Total Fwd Packets", "Total Fwd Packet"), 1.0),
    "Total Backward Packets": (("Total Backward Packets", "Total Bwd packets", "Total Bwd Packets"), 1.0),
    "Total Length of Fwd Packets": (("Total Length of Fwd Packets", "Total Length of Fwd Packet"), 1.0),
    "Total Length of Bwd Packets": (("Total Length of Bwd Packets", "Total Length of Bwd Packet"), 1.0),
    "Fwd Packet Length Max": (("Fwd Packet Length Max",), 1.0),
    "Fwd Packet Length Min": (("Fwd Packet Length Min",), 1.0),
    "Fwd Packet Length Mean": (("Fwd Packet Length Mean",), 1.0),
    "Fwd Packet Length Std": (("Fwd Packet Length Std",), 1.0),
    "Bwd Packet Length Max": (("Bwd Packet Length Max",), 1.0),
    "Bwd Packet Length Min": (("Bwd Packet Length Min",), 1.0),
    "Bwd Packet Length Mean": (("Bwd Packet Length Mean",), 1.0),
    "Bwd Packet Length Std": (("Bwd Packet Length Std",), 1.0),
    "Fwd IAT Total": (("Fwd IAT Total",), 1.0),
    "Fwd IAT Mean": (("Fwd IAT Mean",), 1.0),
    "Fwd IAT Std": (("Fwd IAT Std",), 1.0),
    "Fwd IAT Max": (("Fwd IAT Max",), 1.0),
    "Bwd IAT Total": (("Bwd IAT Total",), 1.0),
    "Bwd IAT Mean": (("Bwd IAT Mean",), 1.0),
    "Bwd IAT Std": (("Bwd IAT Std",), 1.0),
    "Bwd IAT Max": (("Bwd IAT Max",), 1.0),
    "Fwd Header Length": (("Fwd Header Length",), 1.0),
    "Bwd Header Length": (("Bwd Header Length",), 1.0),
}
MAPPED_CICIDS2017: tuple[str, ...] = tuple(_CIC)
_UNSW_DIRECT: dict[str, tuple[str, float]] = {
    "Flow Duration": ("dur", US_PER_S),
    "Flow Packets/s": ("rate", 1.0),
    "Total Fwd Packets": ("spkts", 1.0),
    "Total Backward Packets": ("dpkts", 1.0),
    "Total Length of Fwd Packets": ("sbytes", 1.0),
    "Total Length of Bwd Packets": ("dbytes", 1.0),
    "Fwd Packet Length Mean": ("smean", 1.0),
    "Bwd Packet Length Mean": ("dmean", 1.0),
    "Fwd IAT Mean": ("sinpkt", 1e3),
    "Bwd IAT Mean": ("dinpkt", 1e3),
}
MAPPED_UNSW_NB15: tuple[str, ...] = tuple(_UNSW_DIRECT) + ("Flow Bytes/s", "Down/Up Ratio", "Average Packet Size")


class ExternalFormatError(ValueError):
    """A CSV that is not the expected external format; names the file and what is missing."""


def _csv_files(path: Path) -> list[Path]:
    path = Path(path)
    if path.is_dir():
        files = sorted(p for p in path.glob("*.csv") if "header_reference" not in p.name)
    else:
        files = [path]
    if not files or not all(f.exists() for f in files):
        raise ExternalFormatError(f"{path}: no CSV files")
    return files


def _read(files: list[Path]) -> pd.DataFrame:
    frames = []
    for f in files:
        try:
            df = pd.read_csv(f, low_memory=False, encoding="utf-8-sig")
        except (OSError, pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise ExternalFormatError(f"{f}: cannot read CSV ({str(exc).splitlines()[0]})") from None
        df.columns = [str(c).strip() for c in df.columns]
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def _frame(n: int) -> dict[str, np.ndarray]:
    return {f: np.full(n, np.nan) for f in FEATURES}


def load_cicids2017(path: str | Path) -> pd.DataFrame:
    files = _csv_files(Path(path))
    raw = _read(files)
    if "Label" not in raw.columns:
        raise ExternalFormatError(f"{files[0]}: no 'Label' column (not a CICIDS2017 CSV)")
    cols = _frame(len(raw))
    for ours, (names, factor) in _CIC.items():
        src = next((c for c in names if c in raw.columns), None)
        if src is not None:
            cols[ours] = pd.to_numeric(raw[src], errors="coerce").to_numpy(np.float64) * factor
    out = pd.DataFrame(cols)
    for ours, theirs in (("src_ip", "Src IP"), ("src_port", "Src Port"), ("dst_ip", "Dst IP"), ("dst_port", "Dst Port"),
                         ("protocol", "Protocol")):
        for cand in (theirs, theirs.replace("Src", "Source").replace("Dst", "Destination")):
            if cand in raw.columns:
                out.insert(len(out.columns) - len(FEATURES), ours, raw[cand].to_numpy())
                break
    label = raw["Label"].astype(str).str.strip()
    out["label"] = label.to_numpy()
    out["label_binary"] = (label.str.upper() != "BENIGN").astype(np.int8).to_numpy()
    out["source"] = "cicids2017"
    return out


def load_unsw_nb15(path: str | Path) -> pd.DataFrame:
    files = _csv_files(Path(path))
    raw = _read(files)
    need = [c for c in ("dur", "spkts", "dpkts", "sbytes", "dbytes", "attack_cat") if c not in raw.columns]
    if need:
        raise ExternalFormatError(f"{files[0]}: missing UNSW-NB15 columns {need}")
    cols = _frame(len(raw))
    for ours, (theirs, factor) in _UNSW_DIRECT.items():
        if theirs in raw.columns:
            cols[ours] = pd.to_numeric(raw[theirs], errors="coerce").to_numpy(np.float64) * factor
    dur, sp, dp = cols["Flow Duration"], cols["Total Fwd Packets"], cols["Total Backward Packets"]
    total_bytes = cols["Total Length of Fwd Packets"] + cols["Total Length of Bwd Packets"]
    with np.errstate(divide="ignore", invalid="ignore"):
        cols["Flow Bytes/s"] = np.where(dur > 0, total_bytes / np.where(dur > 0, dur / US_PER_S, 1), 0.0)
        cols["Down/Up Ratio"] = np.where(sp > 0, dp / np.where(sp > 0, sp, 1), 0.0)
        cols["Average Packet Size"] = np.where(sp + dp > 0, total_bytes / np.maximum(sp + dp, 1), 0.0)
    out = pd.DataFrame(cols)
    if "proto" in raw.columns:
        out.insert(0, "protocol", raw["proto"].astype(str).to_numpy())
    cat = raw["attack_cat"].fillna("Normal").astype(str).str.strip().replace({"": "Normal", "-": "Normal"})
    out["label"] = cat.to_numpy()
    if "label" in raw.columns:
        out["label_binary"] = pd.to_numeric(raw["label"], errors="coerce").fillna(0).astype(np.int8).to_numpy()
    else:
        out["label_binary"] = (cat != "Normal").astype(np.int8).to_numpy()
    out["source"] = "unsw-nb15"
    return out


LOADERS = {"cicids2017": load_cicids2017, "unsw-nb15": load_unsw_nb15}
