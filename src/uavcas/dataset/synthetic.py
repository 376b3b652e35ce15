"""Synthetic uavcas datasets with a known class structure, for trying the benchmark without root
and for tests (`uavcas dataset synth`).

Runs take the `medium` campaign preset's configurations of the paper's compositions in order (16
compositions in each of 4 channel settings, cycling), so a synthetic dataset has the same runs, axes and classes as the
benchmark's real one. Each run has benign flows and, in attack runs, flows of its attack class.
The structure is chosen so expected outcomes are known: an attack flow's packets are those one
of its families makes (`AttackFamily.synthetic_packets`: a flood's SYNs, separable), else
benign-like ones, then changed by each of its families in canonical order
(`AttackFamily.synthetic_change`: dropped answers, duplicated packets); each family's recipe is
in its module (`uavcas.attacks`). A family with no recipe leaves its flows exactly benign-like,
indistinguishable from Benign by construction (diversity ~ baseline, AUROC ~ 0.5).
Benign IATs depend on the axes (swarm size, TX power, mission, path loss) so internal diversity
per axis is non-zero. Each flow's packets go through the real extractor (`uavcas.flows`), so the
features are exactly those of captured flows; so do the context columns (`uavcas.flows.context`),
which carry little here: every flow has its own address and one capture point, so there is no
host, window or vantage structure to observe.
"""
from __future__ import annotations

import ipaddress
from pathlib import Path

import numpy as np
import pandas as pd

from uavcas import schema, seeding
from uavcas.atomic import atomic_dir
from uavcas.attacks import SyntheticPackets, family
from uavcas.flows.assemble import FlowConfig, assemble
from uavcas.flows.context import context_frame
from uavcas.flows.features import flow_frame
from uavcas.flows.packets import COLUMNS, NO_MAVLINK, QUOTE_COLUMNS, PacketTable, empty_columns
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.labels.label import constructed_truth
from uavcas.scenario.campaign import MEDIUM_PAPER_CONFIGS, run_seed
from uavcas.scenario.codec import parse
from uavcas.vocabulary import canonical_families

from .parquet import write_shard
from .store import rebuild

_SERVER_IP, _SERVER_PORT = "10.0.0.100", 80
FLAG = {"FIN": 0x01, "SYN": 0x02, "RST": 0x04, "PSH": 0x08, "ACK": 0x10, "URG": 0x20, "ECE": 0x40, "CWE": 0x80}
LABEL_SOURCE = "synthetic"


def _benign_like(rng, mean_iat: float) -> SyntheticPackets:
    n = int(np.clip(rng.lognormal(np.log(40), 0.8), 4, 400))
    iat = rng.lognormal(np.log(mean_iat) - 0.18, 0.6, n - 1)
    t = np.concatenate([[0.0], np.cumsum(iat)])
    d = (np.arange(n) % 2).astype(np.int8)  # request / response alternate
    size = np.where(d == 0, rng.integers(66, 160, n), rng.integers(60, 260, n))
    flags = np.full(n, FLAG["ACK"], dtype=np.int16)
    flags[rng.random(n) < 0.3] |= FLAG["PSH"]
    flags[0] = FLAG["SYN"]
    flags[-1] |= FLAG["FIN"]
    return t, size, d, flags


def flow_sequence(rng, families: tuple[str, ...], mean_iat: float) -> SyntheticPackets:
    """(times, sizes, dirs, flags) of one flow of the class `families` (empty = benign): the packets
    the first of its families that makes some makes, else benign-like ones, then what each of its
    families does to them, in canonical order (module docstring)."""
    fams = [family(f) for f in canonical_families(families)]
    made = None
    for f in fams:
        made = f.synthetic_packets(rng)
        if made is not None:
            break
    seq = made if made is not None else _benign_like(rng, mean_iat)
    for f in fams:
        seq = f.synthetic_change(rng, seq, made is not None)
    return seq


def _benign_mean_iat(n_uav: int, tx_dbm: int, mission: str, pathloss: str) -> float:
    # why: the axes must move benign timing so internal diversity per axis is non-zero
    f = (n_uav / 10.0) ** 0.5 * (1.25 if tx_dbm == 10 else 1.0)
    f *= {"spiral": 0.9, "grid": 1.0, "hover_transit": 1.05, "random": 1.2}[mission]
    f *= 1.15 if pathloss == "3gpp" else 1.0
    return 1.6 * f


def _packet_table(seqs, src_ips: list[int], src_ports: list[int], dst_ip: int, dst_port: int):
    """The packets of the flows `seqs` as a uavcas.flows packet table (TCP over IPv4, one capture
    point), so the synthetic features come from the real extractor."""
    n = np.array([len(s[0]) for s in seqs], dtype=np.int64)
    fid = np.repeat(np.arange(len(seqs)), n)
    back = np.concatenate([s[2] for s in seqs]).astype(bool)
    src = np.asarray(src_ips, dtype=np.uint64)[fid]
    sport = np.asarray(src_ports, dtype=np.uint16)[fid]
    mapped = np.uint64(0xFFFF00000000)  # IPv4-mapped, as the decoder stores IPv4
    size = np.concatenate([s[1] for s in seqs]).astype(np.uint32)
    total = int(n.sum())
    empty = empty_columns()
    cols = {
        "ts_ns": np.round(np.concatenate([s[0] for s in seqs]).astype(np.float64) * 1e9).astype(np.int64),
        "frame_len": size,
        "cap_len": size,
        "ip_version": np.full(total, 4, np.uint8),
        "src_hi": np.zeros(total, np.uint64),
        "src_lo": np.where(back, np.uint64(dst_ip), src) | mapped,
        "dst_hi": np.zeros(total, np.uint64),
        "dst_lo": np.where(back, src, np.uint64(dst_ip)) | mapped,
        "sport": np.where(back, np.uint16(dst_port), sport).astype(np.uint16),
        "dport": np.where(back, sport, np.uint16(dst_port)).astype(np.uint16),
        "proto": np.full(total, 6, np.uint8),
        "tcp_flags": np.concatenate([s[3] for s in seqs]).astype(np.uint16),
        "ttl": np.full(total, 64, np.uint8),
        "ip_id": np.zeros(total, np.uint32),
        "tcp_seq": np.zeros(total, np.uint32),
        "tcp_ack": np.zeros(total, np.uint32),
        "ip_len": np.maximum(size.astype(np.int64) - 14, 40).astype(np.uint32),  # Ethernet frames
        "ip_hdr_len": np.full(total, 20, np.uint16),
        "l4_hdr_len": np.full(total, 20, np.uint16),
        "frame_index": np.arange(total, dtype=np.int64),
        "point": np.zeros(total, np.int16),
    }
    # no ICMP errors: nothing quoted
    cols.update({c: np.zeros(total, empty[c].dtype) for c in QUOTE_COLUMNS})
    cols["mav_msgid"] = np.full(total, NO_MAVLINK, empty["mav_msgid"].dtype)  # TCP: no MAVLink
    assert tuple(cols) == COLUMNS
    return PacketTable(cols, ("s-synthetic",))


def _flow_table(seqs, src_ips: list[int], src_ports: list[int], sequences: bool) -> pd.DataFrame:
    """Identity, counts, sequences and the 47 features of `seqs`, computed by uavcas.flows."""
    dst_ip = int(ipaddress.IPv4Address(_SERVER_IP))
    table = _packet_table(seqs, src_ips, src_ports, dst_ip, _SERVER_PORT)
    # one flow per generated sequence: no termination rule may split one
    whole = FlowConfig(view="5tuple", termination="timeout", dedup=False, idle_timeout_s=0, active_timeout_s=0)
    flows = assemble(table, whole)
    if flows.n_flows != len(seqs):  # every flow has its own key by construction
        raise AssertionError(f"{len(seqs)} synthetic flows assembled into {flows.n_flows}")
    df = pd.concat([flow_frame(table, flows, sequences=sequences), context_frame(table, flows)], axis=1)
    # Flows come out in key order; put them back in generation order.
    key = pd.Series(np.arange(len(seqs)), index=pd.MultiIndex.from_arrays(
        [[str(ipaddress.IPv4Address(a)) for a in src_ips], src_ports]))
    pos = key.loc[list(zip(df["src_ip"], df["src_port"].astype(int)))].to_numpy()
    return df.iloc[np.argsort(pos)].drop(columns=["flow_id", "capture_point"]).reset_index(drop=True)


def make_flows(runs: int = 48, flows_per_run: int = 60, seed: int = 0, sequences: bool = True) -> pd.DataFrame:
    """A flow table in the dataset schema: run r has the preset's configuration r (cycling), so
    >= 16 runs hold all 15 classes and 64 runs are the whole medium design."""
    if runs < 1 or flows_per_run < 1:
        raise ValueError(f"need at least one run and one flow per run, got runs={runs}, flows_per_run={flows_per_run}")
    configs = MEDIUM_PAPER_CONFIGS
    rng = seeding.generator(seed)
    rows, seqs, src_ips, src_ports = [], [], [], []
    base_ip = int(ipaddress.IPv4Address("10.1.0.0"))
    for r in range(runs):
        config = configs[r % len(configs)]
        sc = parse(config)
        axes = sc.axes()
        fams = sc.families
        mean_iat = _benign_mean_iat(sc.n_uav, sc.tx_dbm, sc.mission, sc.pathloss)
        for i in range(flows_per_run):
            f = fams if (fams and rng.random() < 0.5) else ()
            seqs.append(flow_sequence(rng, f, mean_iat))
            src_ips.append(base_ip + len(rows))  # one address per flow: every flow its own key
            src_ports.append(int(rng.integers(1024, 65535)))
            row = dict(
                axes, run_id=f"run{r:05d}", config=config, seed=run_seed(seed, r), view="5tuple",
                flow_id=len(rows), capture_point=f"s-uav{i % sc.n_uav}",
                label=schema.class_name(f), label_source=LABEL_SOURCE,
            )
            for fam in schema.FAMILIES:
                row[f"label_{fam}"] = fam in f
            rows.append(row)
    df = pd.concat([pd.DataFrame(rows), _flow_table(seqs, src_ips, src_ports, sequences)], axis=1)

    truth = constructed_truth(df)  # every packet of an attack flow is an attack packet, by construction
    df = pd.concat([df, truth if sequences else truth.drop(columns=["seq_effect"])], axis=1)
    # Runs happen at different times; shift each flow by its run's start.
    shift = 1.7e9 + rng.uniform(0, 60, len(df))
    df["first_ts"] = df["first_ts"] + shift
    df["last_ts"] = df["last_ts"] + shift
    df["first_ts_ns"] = df["first_ts_ns"] + np.round(shift * 1e9).astype(np.int64)
    return df


def write_dataset(out_dir: str | Path, df: pd.DataFrame, run_meta: dict[str, dict] | None = None) -> Path:
    """Write `df` as a dataset directory: one shard per run, flows.parquet and dataset.json (the
    store's own card), built in a temporary directory beside `out_dir` and renamed onto it.
    `out_dir` must not exist, or be an empty directory. `run_meta`: run id -> more of its shard
    metadata (e.g. `fidelity`, `fidelity_failed`, as an extracted run records them)."""
    out = Path(out_dir)
    with atomic_dir(out) as tmp:
        for run_id, g in df.groupby("run_id", sort=True):
            meta = {"run_id": str(run_id), "config": str(g["config"].iloc[0]), "seed": int(g["seed"].iloc[0]),
                    "view": str(g["view"].iloc[0]), "labels": LABEL_SOURCE, "n_flows": len(g),
                    "class_counts": g["label"].value_counts().to_dict(), "features": DEFAULT_STANDARD,
                    **(run_meta or {}).get(str(run_id), {})}
            write_shard(g, meta, tmp / "shards" / f"{run_id}.parquet")  # flow_frame's default standard
        rebuild(tmp)
    return out

