"""The 47 features against hand-computed values on a known HTTP session."""

from __future__ import annotations

import numpy as np
import pytest
from pcapgen import A, B, http_session, udp, write

from uavcas.flows import FlowConfig, extract_flows
from uavcas.schema import FEATURES

TIMES = np.array([0, 0.01, 0.02, 0.03, 0.05, 0.06, 0.07, 0.10, 0.11, 0.12, 0.13])
FWD = np.array([1, 0, 1, 1, 0, 0, 0, 1, 0, 1, 0], dtype=bool)
SIZES = np.array([54, 54, 54, 72, 1054, 1054, 1054, 54, 54, 54, 54])


def test_http_session_features(tmp_path):
    df = extract_flows([write(tmp_path / "h.pcap", http_session(0.0, A, B))]).frame
    assert list(df.columns[-47:]) == list(FEATURES)
    r = df.iloc[0]
    iat, fiat, biat = np.diff(TIMES), np.diff(TIMES[FWD]), np.diff(TIMES[~FWD])
    expect = {
        "Flow Duration": 0.13,
        "Flow Bytes/s": SIZES.sum() / 0.13,
        "Flow Packets/s": 11 / 0.13,
        "Flow IAT Mean": iat.mean(),
        "Flow IAT Std": iat.std(ddof=1),
        "Flow IAT Max": 0.03,
        "Flow IAT Min": 0.01,
        "Min Packet Length": 54,
        "Max Packet Length": 1054,
        "Packet Length Mean": SIZES.mean(),
        "Packet Length Std": SIZES.std(ddof=1),
        "Packet Length Variance": SIZES.var(ddof=1),
        "FIN Flag Count": 2,
        "SYN Flag Count": 2,
        "RST Flag Count": 0,
        "PSH Flag Count": 1,
        "ACK Flag Count": 10,
        "URG Flag Count": 0,
        "CWE Flag Count": 0,
        "ECE Flag Count": 0,
        "Down/Up Ratio": 6 / 5,
        "Average Packet Size": SIZES.mean(),
        "Active Mean": 0.13,
        "Idle Mean": 0,
        "Idle Max": 0,
        "Total Fwd Packets": 5,
        "Total Backward Packets": 6,
        "Total Length of Fwd Packets": SIZES[FWD].sum(),
        "Total Length of Bwd Packets": SIZES[~FWD].sum(),
        "Fwd Packet Length Max": 72,
        "Fwd Packet Length Min": 54,
        "Fwd Packet Length Mean": SIZES[FWD].mean(),
        "Fwd Packet Length Std": SIZES[FWD].std(ddof=1),
        "Bwd Packet Length Max": 1054,
        "Bwd Packet Length Min": 54,
        "Bwd Packet Length Mean": SIZES[~FWD].mean(),
        "Bwd Packet Length Std": SIZES[~FWD].std(ddof=1),
        "Fwd IAT Total": fiat.sum(),
        "Fwd IAT Mean": fiat.mean(),
        "Fwd IAT Std": fiat.std(ddof=1),
        "Fwd IAT Max": fiat.max(),
        "Bwd IAT Total": biat.sum(),
        "Bwd IAT Mean": biat.mean(),
        "Bwd IAT Std": biat.std(ddof=1),
        "Bwd IAT Max": biat.max(),
        "Fwd Header Length": 5 * 40,
        "Bwd Header Length": 6 * 40,
    }
    assert set(expect) == set(FEATURES)
    for k, v in expect.items():
        assert r[k] == pytest.approx(v, rel=1e-5, abs=2e-6), k
    assert (r.packets, r.bytes, r.duration_s) == (11, SIZES.sum(), pytest.approx(0.13, abs=2e-6))
    np.testing.assert_allclose(np.asarray(r.seq_time_s), TIMES, atol=2e-6)
    assert list(r.seq_size) == SIZES.tolist()
    assert list(r.seq_dir) == np.where(FWD, 1, -1).tolist()
    assert list(r.seq_flags)[:2] == [0x02, 0x12]


def test_idle_active_and_single_packet(tmp_path):
    pk = [udp(t, A, B, 1000, 2000) for t in (0, 1, 2, 200, 201)] + [udp(5, B, A, 9, 9)]
    df = extract_flows([write(tmp_path / "i.pcap", pk)], FlowConfig()).frame.set_index("src_port")
    r = df.loc[1000]
    assert r["Idle Mean"] == pytest.approx(198) and r["Idle Max"] == pytest.approx(198)
    assert r["Active Mean"] == pytest.approx(1.5)
    single = df.loc[9]
    assert single["Flow Duration"] == 0 and single["Flow Bytes/s"] == 0 and single["Flow IAT Std"] == 0
    assert single["Fwd Header Length"] == 28 and single["Down/Up Ratio"] == 0
    assert np.isfinite(df[list(FEATURES)].to_numpy()).all()
