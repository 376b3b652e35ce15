"""A Benign class that is benign, on real runs (issue 22): 6 UAVs, 4 windows each.

- In a DoS, a replay and every composition run, no Benign flow shares its run and 5-tuple with a
  flow holding an attack packet: what an attack provoked (the victim's SYN-ACKs, the RSTs that
  answer them, answers to replayed packets) carries the attack's family, and one TCP connection is
  one flow (no appendix pieces).
- In a benign run every HTTP connection curl made (its log names the client port of each fetch)
  is exactly one flow.
- In a blackhole+dos, a blackhole+ddos and a dos+replay run the shared victim has a row of the
  composite class in the window-host view.

The runs are played three at a time by the real `uavcas run` (each is a real-time emulation that
mostly waits), then extracted.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from uavcas.extract import extract
from uavcas.rundir import RunDir
from uavcas.traffic.image.client import parse_log

pytestmark = [pytest.mark.root, pytest.mark.slow]
SEED = 14
TAIL = "6-2-image-logdist-adaptive-random-30-95"
REPLAY = "replay=50,200,10,5,inc"
CONFIGS = {
    "benign": f"benign-{TAIL}",
    "dos": f"dos=1000-{TAIL}",
    "replay": f"{REPLAY}-{TAIL}",
    "blackhole+dos": f"blackhole+dos=1000-{TAIL}",
    "blackhole+ddos": f"blackhole+ddos=1000-{TAIL}",
    "dos+replay": f"dos=1000+{REPLAY}-{TAIL}",
}
COMPOSITE = {"blackhole+dos": "Blackhole+DoS", "blackhole+ddos": "Blackhole+DDoS", "dos+replay": "DoS+Replay"}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    base = tmp_path_factory.mktemp("benign")
    names = list(CONFIGS)
    for batch in (names[:3], names[3:]):
        procs = {
            name: subprocess.Popen([sys.executable, "-m", "uavcas.cli", "run", CONFIGS[name], "--seed", str(SEED),
                                    "--windows", "4", "--out", str(base / name.replace("+", "_"))],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            for name in batch
        }
        for name, p in procs.items():
            out, _ = p.communicate(timeout=240)
            assert p.returncode == 0, f"{name}: {out[-2000:]}"
    return {name: base / name.replace("+", "_") for name in names}


@pytest.fixture(scope="module")
def flows(runs) -> dict[str, pd.DataFrame]:
    return {name: extract(d).frame for name, d in runs.items()}


def _keys(df: pd.DataFrame) -> pd.Series:
    """The unordered 5-tuple of each flow."""
    a = list(zip(df.src_ip, df.src_port))
    b = list(zip(df.dst_ip, df.dst_port))
    return pd.Series([(p,) + tuple(sorted((x, y))) for p, x, y in zip(df.protocol, a, b)], index=df.index)


@pytest.mark.parametrize("name", [n for n in CONFIGS if n != "benign"])
def test_no_benign_flow_shares_a_5tuple_with_an_attack_flow(flows, name):
    df = flows[name]
    keys = _keys(df)
    attack = df.attack_packets > 0
    assert attack.any(), f"{name}: no attack packet at all"
    benign = df[(df.label == "Benign") & keys.isin(set(keys[attack]))]
    # The one exception, by construction of a replay: the replayer copies a connection's packets
    # and sends them after that connection closed; its copied SYN opens a new connection attempt on
    # the same 5-tuple. The earlier connection is untouched (Benign); the attempt is its own flow,
    # opened by the copy. Nothing an attack made or provoked is in a Benign flow.
    for i, b in benign.iterrows():
        later = df[attack & (keys == keys[i])]
        opened_by_copy = later.seq_effect.map(lambda e: e[0] == "replay")
        assert (later.first_ts > b.last_ts).all() and opened_by_copy.all(), (
            f"{name}: Benign flow {b.src_ip}:{b.src_port} -> {b.dst_ip}:{b.dst_port} ({b.packets} packets) "
            f"shares its 5-tuple with {later.label.tolist()} flows")
    if "replay" not in name:
        assert benign.empty
    assert (df.attack_packets >= df.provoked_packets).all()


def test_flood_answers_are_provoked(flows):
    df = flows["dos"]
    dos = df[df.label == "DoS"]
    # the victim answers most flood SYNs; its SYN-ACKs and the attacker's RSTs are provoked
    assert dos.provoked_packets.sum() > 0
    assert (df[df.label == "Benign"].attack_packets == 0).all()


def test_each_http_connection_is_one_flow(runs, flows):
    rd = RunDir(runs["benign"])
    plan = rd.read_plan()
    ip = {n.name: n.ip for n in plan.nodes}
    df = flows["benign"]
    http = df[(df.protocol == 6) & (df.dst_port == 80)]
    assert (http.label == "Benign").all()
    logs = sorted(rd.logs_dir.glob("http-*.tsv"))
    assert logs
    matched = 0
    for log in logs:
        bs, uav = log.stem.split("-")[1:]
        fetches = [f for f in parse_log(log.read_text()) if f.local_port]
        assert fetches, f"{log.name}: no fetch"
        mine = http[(http.src_ip == ip[bs]) & (http.dst_ip == ip[uav])]
        per_port = mine.groupby("src_port").size()
        for port, n in pd.Series([f.local_port for f in fetches]).value_counts().items():
            # a port curl used k times is k connections: k flows, never pieces of one
            assert per_port.get(port, 0) == n, f"{log.name}: port {port}: {per_port.get(port, 0)} flows, {n} fetches"
            matched += n
        # flows without a logged fetch: the fetch the stop interrupted (at most one per client)
        # and failed connects (curl logs port 0 for them)
        unlogged = len(mine) - int(per_port.reindex(sorted({f.local_port for f in fetches})).fillna(0).sum())
        failed = sum(1 for f in parse_log(log.read_text()) if not f.local_port)
        assert unlogged <= failed + 1, log.name
    assert matched >= 20
    # whole connections: a handshake, an image and a close each
    assert np.median(http.packets) >= 10 and (http["SYN Flag Count"] >= 1).all()


@pytest.mark.parametrize("name", list(COMPOSITE))
def test_collaborative_class_in_the_window_host_view(runs, name):
    rd = RunDir(runs[name])
    plan = rd.read_plan()
    victims = {v for a in plan.attacks for v in a.victims}
    assert len(victims) == 1
    (victim,) = victims
    ep = extract(runs[name], view="window-host").frame
    rows = ep[ep.host == victim]
    assert (rows.label == COMPOSITE[name]).any(), f"{name}: victim rows {rows.label.value_counts().to_dict()}"
    # the composite rows lie inside the attack window
    (a, *_) = plan.attacks
    hit = rows[rows.label == COMPOSITE[name]].window
    starts = np.asarray(hit) * plan.window_s
    assert ((starts + plan.window_s > a.start_s) & (starts < a.stop_s)).all()
