"""Labels of flows holding provoked packets (hand-built tables: tests/helpers/hand_truth.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from helpers.hand_truth import ACK, SYN, context, pkt, window
from uavcas.flows import FlowConfig
from uavcas.flows.assemble import assemble
from uavcas.labels.effects import packet_truth
from uavcas.labels.label import constructed_truth, label_flows, rule_text
from uavcas.schema import TRUTH_COLUMNS
from uavcas.vocabulary import EFFECT_PRECEDENCE, FAMILIES


def test_a_flow_of_only_provoked_packets_carries_the_provoking_family():
    """The flood SYN is seen at the attacker's switch only (lost on the way), its SYN-ACKs and
    their retransmission at the victim's: the flows at uav0's switch hold only provoked packets."""
    syn = pkt(21.0, "uav1", "uav0", 1500, 80, SYN, seq=1000, ip_id=1, at=["uav1"])
    answers = [pkt(21.001 + dt, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=2 + k, at=["uav0"])
               for k, dt in enumerate((0.0, 1.0, 3.0))]
    benign = [pkt(22.0, "uav0", "uav1", 80, 3000, SYN | ACK, seq=1, ack=2, ip_id=9, at=["uav0"])]
    ctx = context([syn, *answers, *benign], [window("ddos", "uav1", "uav0", 20.0, 30.0)])
    truth = packet_truth(ctx)
    fl = assemble(ctx.packets, FlowConfig(view="5tuple"))
    df = label_flows(fl, pd.DataFrame({"flow_id": np.arange(fl.n_flows)}), ctx.log, truth).frame
    at_victim = df[fl.point[df.flow_id] == ctx.packets.points.index("s-uav0")]
    prov = at_victim[at_victim.provoked_packets > 0]
    assert len(prov) == 1 and prov.iloc[0].label == "DDoS" and prov.iloc[0].label_source == "flood-packets"
    assert len(prov.iloc[0].seq_effect) == prov.iloc[0].provoked_packets == prov.iloc[0].attack_packets == 3
    assert prov.iloc[0].attack_packets_ddos == 3 and prov.iloc[0].attack_fraction == 1.0
    assert list(prov.iloc[0].seq_effect) == ["provoked"] * 3
    other = at_victim[at_victim.provoked_packets == 0]
    assert len(other) == 1 and other.iloc[0].label == "Benign" and other.iloc[0].attack_packets == 0
    assert {"provoked_packets"} <= set(TRUTH_COLUMNS) and set(TRUTH_COLUMNS) <= set(df.columns)


def test_constructed_truth_has_no_provoked_packets_and_the_rule_names_them():
    frame = pd.DataFrame({"packets": [3, 2], **{f"label_{f}": [f == "dos", False]
                                                for f in FAMILIES}})
    out = constructed_truth(frame)
    assert list(out.provoked_packets) == [0, 0] and list(out.attack_packets) == [3, 0]
    text = rule_text("ours")
    assert "provoked" in text and " > ".join(EFFECT_PRECEDENCE) in text
    assert text.count("provoked: ") == len(FAMILIES)  # one provoked rule per family
