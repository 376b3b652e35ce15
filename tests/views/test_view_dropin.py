"""A dataset view is added by dropping one module into `uavcas.views` (issue 40).

A copy of the package gets a throwaway view, `window-pair`: one row per unordered pair of plan
nodes per plan window, the 5-tuple flows that start in the window between the two summed
(packets, bytes, flows, truth) and labelled from their packets' effects. In a fresh interpreter
that imports only the copy, the CLI offers it, `uavcas extract --view window-pair` writes its
rows with its own columns (described in the card, the Parquet field metadata and `info
--columns`), `uavcas info` and `uavcas publish` name its rows, a flow dataset refuses its rows,
and its numbers are the 5-tuple flows' of the same run.
"""

from __future__ import annotations

import json
import shutil

import pyarrow.parquet as pq
import pytest

from helpers.plugin import package_copy, run_on
from helpers.synth_run import IPS

THROWAWAY = '''"""Throwaway view for a test: one row per unordered plan-node pair per plan window."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa

from uavcas.attacks import family
from uavcas.labels.label import SOURCES, label_flows
from uavcas.schema import AXIS_COLUMNS, FAMILIES, META_LABEL_COLUMNS, class_name
from uavcas.vocabulary import ATTACK_PACKET_COLUMNS

from .base import IDENTITY_TYPES, RowNoun, ViewInput, ViewRows, ViewSpec, axis_fields, label_fields
from .registry import register

IDS = ("run_id", "config", "seed", "view", "host_a", "host_b", "window", "first_ts", "last_ts", "first_ts_ns")
FEATURES = ("pair_flows", "pair_packets_per_s", "pair_bytes_per_s")
OWN = {
    "host_a": ("-", "the pair's first plan node (plan order)"), "host_b": ("-", "the pair's second plan node"),
    "window": ("-", "plan window of the flows' first packets"), "pair_flows": ("flows", "5-tuple flows"),
    "pair_packets_per_s": ("packets/s", "packets per second of window"),
    "pair_bytes_per_s": ("bytes/s", "frame bytes per second of window"),
}
TYPES = {**IDENTITY_TYPES, "host_a": pa.string(), "host_b": pa.string(), "window": pa.int64()}


def fields(standard: str, context: bool) -> list[pa.Field]:
    out = [pa.field(c, TYPES[c]) for c in IDS] + axis_fields()
    out += [pa.field("packets", pa.int64()), pa.field("bytes", pa.int64()), pa.field("pair_flows", pa.int64())]
    return out + [pa.field(c, pa.float64()) for c in FEATURES[1:]] + label_fields()


def rows(inp: ViewInput) -> ViewRows:
    flows = label_flows(inp.flows, inp.frame, inp.log, inp.truth).frame
    node = {nd.ip: k for k, nd in enumerate(inp.plan.nodes)}
    a, b = flows["src_ip"].map(node), flows["dst_ip"].map(node)
    ns, win_ns = round(inp.t0_unix * 1e9), round(inp.plan.window_s * 1e9)
    flows["window"] = np.clip((flows["first_ts_ns"] - ns) // win_ns, 0, len(inp.plan.windows) - 1)
    flows["a"], flows["b"] = np.minimum(a, b), np.maximum(a, b)
    flows = flows[a.notna() & b.notna() & (a != b)]
    sums = {c: "sum" for c in ("packets", "bytes", "attack_packets", "provoked_packets", *ATTACK_PACKET_COLUMNS)}
    g = flows.groupby(["a", "b", "window"], sort=True).agg(
        pair_flows=("flow_id", "size"), first_ts=("first_ts", "min"), last_ts=("last_ts", "max"),
        first_ts_ns=("first_ts_ns", "min"), **{c: (c, f) for c, f in sums.items()}).reset_index()
    names = np.asarray([nd.name for nd in inp.plan.nodes], dtype=object)
    g["host_a"], g["host_b"] = names[g["a"].astype(int)], names[g["b"].astype(int)]
    g["pair_packets_per_s"] = g["packets"] / inp.plan.window_s
    g["pair_bytes_per_s"] = g["bytes"] / inp.plan.window_s
    g["attack_fraction"] = g["attack_packets"] / g["packets"]
    labels, sources = [], []
    for _, r in g.iterrows():
        fams = [f for f, c in zip(FAMILIES, ATTACK_PACKET_COLUMNS) if r[c] > 0]
        labels.append(class_name(fams))
        used = {family(f).label_source for f in fams}
        sources.append("+".join(s for s in SOURCES if s in used) or "none")
    for f, c in zip(FAMILIES, ATTACK_PACKET_COLUMNS):
        g[f"label_{f}"] = g[c] > 0
    g["label"], g["label_source"] = labels, sources
    return ViewRows(g.drop(columns=["a", "b"]).reset_index(drop=True), 0, "window-pair: a pair carries family F "
                    "when one of its flows' packets has an effect of F")


VIEW = register(ViewSpec(
    name="window-pair", row=RowNoun("pair-window row", "pair-window rows"), unit="pair-window",
    meaning="two plan nodes' flows in one plan window", card_rows="one per plan-node pair per plan window",
    record_set="pair_windows", help="one row per plan-node pair per plan window", key_columns=("host_a", "host_b",
    "window"), flow_key="5tuple", flow_labels=False, fields=fields, feature_columns=lambda standard: FEATURES,
    context_columns=(), metadata_columns=IDS + AXIS_COLUMNS + ("packets", "bytes") + META_LABEL_COLUMNS,
    describe=lambda name, standard: OWN.get(name),
    feature_card=lambda standard: {"standard": standard, "source": f"5-tuple flows ({standard}) per node pair",
                                   "units": {c: OWN[c][0] for c in FEATURES}},
    shown_features=("pair_packets_per_s", "pair_flows"), report_title="Pair-window features per class", rows=rows,
))
'''


@pytest.mark.slow  # 31 s on 2 cores
def test_a_dropped_in_view_is_offered_extracted_described_and_published(synth_run_dir, tmp_path):
    pkg = package_copy(tmp_path, {"views/window_pair.py": THROWAWAY})
    probe = run_on(pkg, "-c", "import uavcas, uavcas.views as v; print(uavcas.__file__); print(' '.join(v.names()))")
    assert probe.returncode == 0, probe.stderr
    where, names = probe.stdout.splitlines()
    assert where.startswith(str(pkg)) and "window-pair" in names.split() and "5tuple" in names.split()
    helped = run_on(pkg, "-m", "uavcas", "extract", "--help")
    assert helped.returncode == 0, helped.stderr
    helptext = " ".join(helped.stdout.replace("│", " ").split())  # help wrapped in a rich panel
    assert "window-pair (one row per plan-node pair per plan window)" in helptext

    ds = tmp_path / "ds"
    made = run_on(pkg, "-m", "uavcas", "extract", str(synth_run_dir), "--out", str(ds), "--view", "window-pair")
    assert made.returncode == 0, made.stderr
    assert "pair-window rows from" in made.stdout
    card = json.loads((ds / "dataset.json").read_text())
    assert card["unit"] == "pair-window" and card["views"] == ["window-pair"] and card["context"] is None
    assert card["columns"]["pair_flows"]["unit"] == "flows" and card["columns"]["host_a"]["dtype"] == "string"
    assert card["features"]["units"] == {"pair_flows": "flows", "pair_packets_per_s": "packets/s",
                                         "pair_bytes_per_s": "bytes/s"}
    assert pq.read_schema(ds / "flows.parquet").field("pair_bytes_per_s").metadata[b"unit"] == b"bytes/s"

    # its numbers are the 5-tuple flows' between plan nodes, by the window of their first packet
    ref = tmp_path / "ref"
    assert run_on(pkg, "-m", "uavcas", "extract", str(synth_run_dir), "--out", str(ref)).returncode == 0
    rows, flows = pq.read_table(ds / "flows.parquet").to_pandas(), pq.read_table(ref / "flows.parquet").to_pandas()
    assert len(rows) > 0 and rows["pair_flows"].sum() <= len(flows)
    assert rows[["host_a", "host_b", "window"]].duplicated().sum() == 0
    pair = rows.set_index(["host_a", "host_b"]).groupby(level=[0, 1])[["packets", "attack_packets"]].sum()
    node = {ip: name for name, ip in IPS.items()}
    f = flows[flows["src_ip"].isin(node) & flows["dst_ip"].isin(node)]
    ends = f[["src_ip", "dst_ip"]].apply(lambda r: tuple(sorted((node[r.src_ip], node[r.dst_ip]))), axis=1)
    want = f.groupby(ends)[["packets", "attack_packets"]].sum()
    assert {frozenset(k): tuple(v) for k, v in pair.iterrows()} == {frozenset(k): tuple(v) for k, v in want.iterrows()}
    assert set(rows["label"]) == set(f["label"])  # the run's classes, here one family per pair

    listed = run_on(pkg, "-m", "uavcas", "info", str(ds))
    assert listed.returncode == 0, listed.stderr
    said = " ".join(listed.stdout.split())  # rich wraps a long dataset path (pytest-xdist's are longer)
    assert f"{len(rows)} pair-window rows" in said and "views: window-pair" in said
    cols = run_on(pkg, "-m", "uavcas", "info", str(ds), "--columns")
    assert cols.returncode == 0, cols.stderr
    assert "pair_packets_per_s\tdouble\tpackets/s\tpackets per second of window" in cols.stdout

    pub = tmp_path / "pub"
    published = run_on(pkg, "-m", "uavcas", "publish", str(ds), "--out", str(pub))
    assert published.returncode == 0, published.stderr
    readme = (pub / "README.md").read_text()
    assert "(one per plan-node pair per plan window)" in readme and 'records("pair_windows")' in readme
    croissant = json.loads((pub / "croissant.json").read_text())
    assert croissant["recordSet"][0]["@id"] == "pair_windows"
    assert "pair-window rows" in croissant["description"]

    # a dataset holds one kind of row: flows refuse the view's rows, in one line, before any write
    other = tmp_path / "run-other"  # the same run under another id: another shard
    shutil.copytree(synth_run_dir, other)
    info = json.loads((other / "run.json").read_text())
    (other / "run.json").write_text(json.dumps({**info, "run_id": "other"}))
    refused = run_on(pkg, "-m", "uavcas", "extract", str(other), "--out", str(ref), "--view", "window-pair")
    assert refused.returncode != 0 and "pair-window rows" in refused.stderr and "another --out" in refused.stderr
    assert len(list((ref / "shards").glob("*.parquet"))) == 1

