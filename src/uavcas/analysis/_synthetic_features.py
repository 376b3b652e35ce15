"""The 47 flow statistics of synthetic sequences, vectorised over all packets with pandas.

Simplified CICFlowMeter rules, good enough for synthetic data (the real extractor is
`uavcas.flows`): header length 40 B per packet, idle gaps > ACTIVITY_TIMEOUT_S.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from uavcas.dataset import schema

_FLAGS = {"FIN": 0x01, "SYN": 0x02, "RST": 0x04, "PSH": 0x08, "ACK": 0x10, "URG": 0x20, "ECE": 0x40, "CWE": 0x80}


def features_from_sequences(seqs) -> pd.DataFrame:
    """seqs: list of (times, sizes, dirs, flags) arrays; returns one row per flow, FEATURES order."""
    n = np.array([len(s[0]) for s in seqs])
    fid = np.repeat(np.arange(len(seqs)), n)
    t = np.concatenate([s[0] for s in seqs]).astype(float)
    size = np.concatenate([s[1] for s in seqs]).astype(float)
    d = np.concatenate([s[2] for s in seqs]).astype(np.int8)
    fl = np.concatenate([s[3] for s in seqs]).astype(np.int64)
    pk = pd.DataFrame({"f": fid, "t": t, "size": size, "d": d})
    g = pk.groupby("f", sort=True)
    out = pd.DataFrame(index=np.arange(len(seqs)))
    dur = (g["t"].max() - g["t"].min()).to_numpy()
    total = g["size"].sum().to_numpy()
    safe = np.where(dur > 0, dur, np.nan)
    out["Flow Duration"] = dur
    out["Flow Bytes/s"] = np.nan_to_num(total / safe)
    out["Flow Packets/s"] = np.nan_to_num(n / safe)
    iat = np.diff(t)
    same = fid[1:] == fid[:-1]
    ia = pd.DataFrame({"f": fid[1:][same], "iat": iat[same]}).groupby("f")["iat"]
    for name, fn in (("Mean", "mean"), ("Std", "std"), ("Max", "max"), ("Min", "min")):
        out[f"Flow IAT {name}"] = getattr(ia, fn)().reindex(out.index).fillna(0).to_numpy()
    out["Min Packet Length"] = g["size"].min().to_numpy()
    out["Max Packet Length"] = g["size"].max().to_numpy()
    out["Packet Length Mean"] = g["size"].mean().to_numpy()
    out["Packet Length Std"] = g["size"].std().fillna(0).to_numpy()
    out["Packet Length Variance"] = out["Packet Length Std"] ** 2
    for k in ("FIN", "SYN", "RST", "PSH", "ACK", "URG", "CWE", "ECE"):
        out[f"{k} Flag Count"] = np.bincount(fid, weights=(fl & _FLAGS[k]) > 0, minlength=len(seqs))
    fwd_n = np.bincount(fid, weights=d == 0, minlength=len(seqs))
    bwd_n = n - fwd_n
    out["Down/Up Ratio"] = np.where(fwd_n > 0, bwd_n / np.maximum(fwd_n, 1), 0)
    out["Average Packet Size"] = total / n
    gaps = np.where(same, iat, 0.0)
    idle = gaps > schema.ACTIVITY_TIMEOUT_S
    idle_df = pd.DataFrame({"f": fid[1:][idle], "g": gaps[idle]}).groupby("f")["g"]
    idle_sum = idle_df.sum().reindex(out.index).fillna(0).to_numpy()
    idle_cnt = idle_df.count().reindex(out.index).fillna(0).to_numpy()
    out["Active Mean"] = (dur - idle_sum) / (idle_cnt + 1)
    out["Idle Mean"] = np.where(idle_cnt > 0, idle_sum / np.maximum(idle_cnt, 1), 0)
    out["Idle Max"] = idle_df.max().reindex(out.index).fillna(0).to_numpy()
    for side, code in (("Fwd", 0), ("Bwd", 1)):
        m = d == code
        sg = pk[m].groupby("f")["size"]
        cnt = np.bincount(fid[m], minlength=len(seqs))
        tot = np.bincount(fid[m], weights=size[m], minlength=len(seqs))
        if side == "Fwd":
            out["Total Fwd Packets"] = cnt
        else:
            out["Total Backward Packets"] = cnt
        out[f"Total Length of {side} Packets"] = tot
        for name, fn in (("Max", "max"), ("Min", "min"), ("Mean", "mean"), ("Std", "std")):
            out[f"{side} Packet Length {name}"] = getattr(sg, fn)().reindex(out.index).fillna(0).to_numpy()
        ts, fs = t[m], fid[m]
        di = np.diff(ts)
        sm = fs[1:] == fs[:-1]
        dg = pd.DataFrame({"f": fs[1:][sm], "iat": di[sm]}).groupby("f")["iat"]
        out[f"{side} IAT Total"] = dg.sum().reindex(out.index).fillna(0).to_numpy()
        for name, fn in (("Mean", "mean"), ("Std", "std"), ("Max", "max")):
            out[f"{side} IAT {name}"] = getattr(dg, fn)().reindex(out.index).fillna(0).to_numpy()
        out[f"{side} Header Length"] = 40.0 * cnt
    return out[list(schema.FEATURES)].astype(float)
