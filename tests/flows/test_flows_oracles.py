"""Oracles: nfstream's stored per-flow counts, and an independent tshark field extraction."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest

from helpers.pcapgen import A, B, C, http_session, syn_flood, udp, write
from uavcas.flows import FlowConfig, extract_flows

# nfstream's defaults: idle_timeout=120 s, active_timeout=1800 s, no FIN/RST or SYN rule.
NFSTREAM = FlowConfig(termination="timeout")
# the paper's pipeline: one flow per 5-tuple
WHOLE = FlowConfig(termination="timeout", idle_timeout_s=0, active_timeout_s=0)


@pytest.mark.shared
@pytest.mark.parametrize("cfg", [FlowConfig(), NFSTREAM], ids=["connection", "timeout"])
def test_counts_equal_nfstream(shared_data, cfg):
    # the default policy (one TCP connection, one flow) and nfstream's own timeouts alike
    pcaps = sorted((shared_data / "pcaps" / "nfstream-tests").glob("*.pcap"))
    assert len(pcaps) == 5
    for pcap in pcaps:
        ref = pd.read_csv(f"{pcap}.nfstream_result.csv")
        df = extract_flows([pcap], cfg, sequences=False).frame
        ours = sorted(zip(df.packets.tolist(), df.bytes.tolist()))
        theirs = sorted(zip(ref.bidirectional_packets.tolist(), ref.bidirectional_bytes.tolist()))
        assert ours == theirs, pcap.name


TSHARK_FIELDS = ("frame.time_epoch", "frame.len", "ip.src", "ip.dst", "tcp.srcport", "tcp.dstport",
                 "udp.srcport", "udp.dstport", "ip.proto", "tcp.flags")  # fmt: skip


def _tshark_flows(pcap) -> pd.DataFrame:
    """The paper's pipeline, written independently: tshark fields -> pandas 5-tuple flows."""
    cmd = ["tshark", "-n", "-r", str(pcap), "-Y", "ip && !icmp", "-T", "fields", "-E", "separator=,", "-E",
           "occurrence=f"]
    for f in TSHARK_FIELDS:
        cmd += ["-e", f]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True, timeout=60).stdout
    rows = [line.split(",") for line in out.splitlines() if line]
    df = pd.DataFrame(rows, columns=list(TSHARK_FIELDS))
    df["t"] = df["frame.time_epoch"].astype(float)
    df["sp"] = pd.to_numeric(df["tcp.srcport"].where(df["tcp.srcport"] != "", df["udp.srcport"]),
                             errors="coerce").fillna(0).astype(int)
    df["dp"] = pd.to_numeric(df["tcp.dstport"].where(df["tcp.dstport"] != "", df["udp.dstport"]),
                             errors="coerce").fillna(0).astype(int)
    df["fl"] = df["tcp.flags"].map(lambda s: int(s, 16) if s else 0)
    a = list(zip(df["ip.src"], df.sp))
    b = list(zip(df["ip.dst"], df.dp))
    df["key"] = [tuple(sorted((x, y))) + (p,) for x, y, p in zip(a, b, df["ip.proto"])]
    rows = []
    for key, g in df.groupby("key", sort=False):
        g = g.sort_values("t", kind="stable")
        iat = np.diff(g.t.to_numpy())
        first_src = (g["ip.src"].iloc[0], g.sp.iloc[0])
        fwd = [(s, p) == first_src for s, p in zip(g["ip.src"], g.sp)]
        rows.append(
            {
                "src": first_src,
                "packets": len(g),
                "bytes": g["frame.len"].astype(int).sum(),
                "duration": g.t.iloc[-1] - g.t.iloc[0],
                "syn": int(((g.fl & 0x02) > 0).sum()),
                "ack": int(((g.fl & 0x10) > 0).sum()),
                "fin": int(((g.fl & 0x01) > 0).sum()),
                "psh": int(((g.fl & 0x08) > 0).sum()),
                "rst": int(((g.fl & 0x04) > 0).sum()),
                "iat_mean": iat.mean() if len(iat) else 0.0,
                "iat_std": iat.std(ddof=1) if len(iat) > 1 else 0.0,
                "iat_max": iat.max() if len(iat) else 0.0,
                "iat_min": iat.min() if len(iat) else 0.0,
                "fwd": int(sum(fwd)),
            }
        )
    return pd.DataFrame(rows)


def _compare(pcap):
    theirs = _tshark_flows(pcap)
    ours = extract_flows([pcap], WHOLE, sequences=False).frame
    ours = ours[ours.protocol.isin([6, 17])]
    assert len(ours) == len(theirs)
    ours = ours.assign(src=list(zip(ours.src_ip, ours.src_port))).set_index("src").sort_index()
    theirs = theirs.set_index("src").sort_index()
    assert ours.index.tolist() == theirs.index.tolist()
    pairs = {
        "packets": "packets", "bytes": "bytes", "duration": "Flow Duration", "syn": "SYN Flag Count",
        "ack": "ACK Flag Count", "fin": "FIN Flag Count", "psh": "PSH Flag Count", "rst": "RST Flag Count",
        "iat_mean": "Flow IAT Mean", "iat_std": "Flow IAT Std", "iat_max": "Flow IAT Max",
        "iat_min": "Flow IAT Min", "fwd": "Total Fwd Packets",
    }  # fmt: skip
    us = {"duration", "iat_mean", "iat_std", "iat_max", "iat_min"}  # cic times are microseconds
    for t_col, o_col in pairs.items():
        ref = theirs[t_col].to_numpy(float) * (1e6 if t_col in us else 1)
        got = ours[o_col].to_numpy(float)
        if t_col.startswith("iat"):  # CICFlowMeter has no IAT of a one-packet flow
            got = np.where(ours["packets"].to_numpy() > 1, got, 0.0)
        np.testing.assert_allclose(got, ref, rtol=1e-6, atol=2, err_msg=f"{pcap.name}: {o_col}")


@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark is not installed")
def test_against_tshark_synthetic(tmp_path):
    pk = http_session(0.0, A, B) + syn_flood(10, 0.5, C, B) + [udp(0.2 + 0.1 * k, A, C, 5000, 53) for k in range(5)]
    _compare(write(tmp_path / "mix.pcap", sorted(pk, key=lambda p: p.time)))


@pytest.mark.shared
@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark is not installed")
def test_against_tshark_real(shared_data):
    for name in ("nfstream-tests/ftp.pcap", "nfstream-tests/http_auth.pcap", "lwerdna-filesamples/simple_http.pcap"):
        _compare(shared_data / "pcaps" / name)
