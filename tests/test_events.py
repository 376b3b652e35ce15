"""Attack-log records: one type per event, exact lines, loud failures on unknown or missing fields."""

from __future__ import annotations

import json

import pytest

from uavcas.events import (
    AttackRate,
    AttackStart,
    AttackStop,
    Inject,
    RecordError,
    attack_log_text,
    parse_attack_record,
    read_attack_records,
)

START = AttackStart(attack_id="dos-0", family="dos", attackers=["uav1"], attacker_ips=["10.77.1.2"], victims=["uav0"],
                    victim_ips=["10.77.1.1"], t_unix=1.5, params={"interval_us": 1000, "nominal_pps": 1000.0},
                    planned_start_s=1.0, planned_stop_s=9.0, hping_interval_us=[995])
RECORDS = [
    START,
    AttackRate(attack_id="dos-0", family="dos", attacker="uav1", measured_pps=998.1, nominal_pps=1000.0,
               hping_interval_us=995, syn_count=7987, seconds=8.0, restarts=0, intervals_us=[1000, 995],
               victim_ip="10.77.1.1", t_unix=9.4),
    AttackStop(attack_id="dos-0", family="dos", t_unix=9.5, syn_count=7987),
    Inject(attack_id="replay-1", family="replay", t_unix=3.25, src_ip="10.77.1.1", dst_ip="10.77.0.1", src_port=None,
           dst_port=None, protocol=17, ip_id=4, ttl=59, seq=None, orig_seq=None, orig_ttl=64),
]


def test_lines_round_trip_and_keep_only_what_was_set(tmp_path):
    text = attack_log_text(RECORDS)
    (tmp_path / "a.jsonl").write_text(text)
    assert read_attack_records(tmp_path / "a.jsonl") == RECORDS
    first = json.loads(text.splitlines()[0])
    assert first["event"] == "start" and "switch" not in first and first["hping_interval_us"] == [995]
    last = json.loads(text.splitlines()[-1])
    assert last["seq"] is None  # set to None: written (UDP has no sequence number)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: {**d, "colour": 1}, "unknown field 'colour'"),
        (lambda d: {k: x for k, x in d.items() if k != "victim_ips"}, "record has no 'victim_ips'"),
        (lambda d: {**d, "event": "pause"}, "unknown or missing event"),
        (lambda d: {k: x for k, x in d.items() if k != "event"}, "unknown or missing event"),
        (lambda d: {**d, "family": "teleport"}, "bad field value 'family'"),
        (lambda d: {**d, "t_unix": "soon"}, "bad field value 't_unix'"),
    ],
)
def test_bad_records_fail_loudly_naming_the_field(change, message):
    d = json.loads(START.to_line())
    with pytest.raises(RecordError, match=rf"^a.jsonl:3: {message}"):
        parse_attack_record(json.dumps(change(d)), "a.jsonl:3")


def test_not_json_is_one_line():
    with pytest.raises(RecordError, match=r"^x:1: not JSON") as e:
        parse_attack_record("{nope", "x:1")
    assert "\n" not in str(e.value)
