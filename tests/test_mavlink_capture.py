"""MAVLink capture reader: real pymavlink frames in the synthetic run's captures -> one row per message."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from helpers.synth_run import IPS, MAV_BLACKHOLED_T, MAV_LAT, MAV_LON, T0, add_mavlink, build_run, mavlink_datagrams
from uavcas.mavlink_capture import (
    ALL_COLUMNS,
    MavlinkError,
    decode_datagrams,
    mavlink_table,
    message_counts,
    problems,
    write_table,
)

UAVCAS = str(Path(sys.executable).parent / "uavcas")


@pytest.fixture(scope="module")
def mav_run(tmp_path_factory):
    return add_mavlink(build_run(tmp_path_factory.mktemp("mav") / "run-mav"))


@pytest.fixture(scope="module")
def table(mav_run):
    return mavlink_table(mav_run)


def test_columns_and_types(table):
    assert list(table.columns) == list(ALL_COLUMNS)
    assert table["ts_ns"].dtype == "int64" and table["sysid"].dtype == "UInt8" and table["crc_ok"].dtype == "boolean"
    assert table["lat_degE7"].dtype == "Int64" and table["vx_m_s"].dtype == "float64"
    # every datagram on port 14550 and nothing else (the RTP datagram to 5600 is left out)
    assert ((table["src_port"] == 14550) | (table["dst_port"] == 14550)).all()


def test_counts_per_message_at_one_capture_point(table, mav_run):
    at_bs = table[table["point"] == "s-bs0"]
    names = at_bs["msg_name"].fillna("none").value_counts().to_dict()
    # heartbeat x2 (one alone, one with a position), position x2 good + 1 bad CRC, command x2, garbage x1
    assert names == {"HEARTBEAT": 2, "GLOBAL_POSITION_INT": 3, "COMMAND_LONG": 2, "none": 1}
    ok = at_bs[at_bs["crc_ok"].fillna(False).astype(bool)]
    assert ok.groupby("msg_name").size().to_dict() == {"HEARTBEAT": 2, "GLOBAL_POSITION_INT": 2, "COMMAND_LONG": 2}
    # 7 messages to or from uav0, each captured at s-bs0 and at s-uav0: one row per observation
    uav0 = table[(table["src_ip"] == IPS["uav0"]) | (table["dst_ip"] == IPS["uav0"])]
    assert uav0.groupby("point").size().to_dict() == {"s-bs0": 7, "s-uav0": 7}
    one = mavlink_table(mav_run, point="s-uav0")
    assert len(one) == 7 and set(one["point"]) == {"s-uav0"}


def test_decoded_fields_and_two_messages_in_one_datagram(table):
    pos = table[(table["msg_name"] == "GLOBAL_POSITION_INT") & table["crc_ok"].fillna(False).astype(bool)]
    assert (pos["lat_degE7"] == MAV_LAT).all() and (pos["lon_degE7"] == MAV_LON).all()
    assert (pos["alt_mm"] == 584000).all() and (pos["vy_cm_s"] == -50).all() and (pos["hdg_cdeg"] == 9000).all()
    assert json.loads(pos["fields_json"].iloc[0])["relative_alt"] == 50000
    assert (pos["sysid"] == 1).all() and (pos["compid"] == 1).all() and (pos["mavlink_version"] == 2).all()
    cmd = table[table["msg_name"] == "COMMAND_LONG"]
    assert (cmd["sysid"] == 255).all() and (json.loads(cmd["fields_json"].iloc[0])["command"] == 400)
    assert cmd["lat_degE7"].isna().all()  # a message without position fields leaves them missing
    # the datagram at 3.3 s: heartbeat then position, same packet row, msg_index 0 and 1
    both = table[(table["point"] == "s-bs0") & ((table["ts_s"] - (T0 + 3.3)).abs() < 1e-3)]
    assert both["msg_name"].tolist() == ["HEARTBEAT", "GLOBAL_POSITION_INT"]
    assert both["msg_index"].tolist() == [0, 1] and both["packet_row"].nunique() == 1


def test_bad_crc_and_garbage_rows(table):
    at_bs = table[table["point"] == "s-bs0"]
    bad = at_bs[(at_bs["ts_s"] - (T0 + 3.4)).abs() < 1e-3]
    assert len(bad) == 1 and bad["crc_ok"].iloc[0] == False  # noqa: E712
    assert bad["msg_name"].iloc[0] == "GLOBAL_POSITION_INT" and "CRC" in bad["error"].iloc[0]
    assert pd.isna(bad["fields_json"].iloc[0]) and pd.isna(bad["lat_degE7"].iloc[0])  # nothing trusted
    junk = at_bs[(at_bs["ts_s"] - (T0 + 3.5)).abs() < 1e-3]
    assert len(junk) == 1 and pd.isna(junk["msg_name"].iloc[0]) and junk["crc_ok"].iloc[0] == False  # noqa: E712
    lines = problems(table)
    assert any("hold no MAVLink frame" in x and x.startswith("2 row(s)") for x in lines)
    assert any("2 message(s) failed their CRC" in x for x in lines)


def test_truth_per_observation(table):
    untouched = table[(table["ts_s"] - T0) < 10]
    assert (untouched["effect"] == "benign").all() and untouched["family"].isna().all()
    dropped = table[(table["ts_s"] - (T0 + MAV_BLACKHOLED_T)).abs() < 1e-3]
    assert sorted(dropped["point"]) == ["s-bs0", "s-uav3"]  # both observations of the blackholed command
    assert (dropped["effect"] == "blackhole").all() and (dropped["family"] == "blackhole").all()


def test_rows_line_up_with_the_extraction(table, mav_run):
    from uavcas.extract import extract_detailed

    ex = extract_detailed(mav_run)
    r = table["packet_row"].to_numpy()
    assert (ex.packets["ts_ns"][r] == table["ts_ns"].to_numpy()).all()
    assert (ex.packets["frame_index"][r] == table["frame_index"].to_numpy()).all()
    assert (ex.truth.effect_names(r) == table["effect"].to_numpy()).all()


def test_message_counts_per_sysid_name_and_second(table):
    c = message_counts(table, point="s-bs0")
    row = c[(c["sysid"] == 1) & (c["msg_name"] == "HEARTBEAT")]
    assert row[["second", "messages"]].values.tolist() == [[int(T0) + 3, 2]]
    assert c["messages"].sum() == 6  # good messages only: the bad CRC and the garbage are left out


def test_decode_datagrams_keeps_the_order_and_flags_a_cut_frame():
    payloads = [p for *_, p in mavlink_datagrams()]
    df = decode_datagrams([payloads[0][:-3], payloads[1]])
    assert df["datagram"].tolist() == [0, 1]
    assert df["crc_ok"].tolist() == [False, True] and "cut" in df["error"].iloc[0]


def test_the_table_is_written_as_parquet_or_csv_by_suffix(table, tmp_path):
    assert write_table(table, tmp_path / "m.PARQUET") == tmp_path / "m.PARQUET"
    back = pd.read_parquet(tmp_path / "m.PARQUET")
    assert list(back.columns) == list(ALL_COLUMNS) and len(back) == len(table)
    assert back["fields_json"].fillna("-").tolist() == table["fields_json"].fillna("-").tolist()
    write_table(table, tmp_path / "m.csv")
    csv = pd.read_csv(tmp_path / "m.csv")
    assert list(csv.columns) == list(ALL_COLUMNS) and csv["ts_ns"].tolist() == table["ts_ns"].tolist()
    with pytest.raises(MavlinkError, match=r"m.json must end in .parquet or .csv"):
        write_table(table, tmp_path / "m.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.PARQUET", "m.csv"]  # nothing else, no temporary


@pytest.mark.slow  # 19 s on 2 cores
def test_cli_writes_parquet_and_refuses_a_bad_run_dir(mav_run, tmp_path):
    out = tmp_path / "mav.parquet"
    r = subprocess.run([UAVCAS, "mavlink", str(mav_run), "--out", str(out), "--point", "s-bs0"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    back = pd.read_parquet(out)
    assert list(back.columns) == list(ALL_COLUMNS) and len(back) == 8 and set(back["point"]) == {"s-bs0"}
    assert "warning:" in r.stderr  # the unparsed datagram and the bad CRC are reported
    csv = tmp_path / "mav.csv"
    assert subprocess.run([UAVCAS, "mavlink", str(mav_run), "--out", str(csv)], capture_output=True,
                          timeout=120).returncode == 0
    assert len(pd.read_csv(csv)) == 16
    shown = subprocess.run([UAVCAS, "mavlink", str(mav_run)], capture_output=True, text=True, timeout=120)
    assert shown.returncode == 0 and "GLOBAL_POSITION_INT" in shown.stdout and "messages per name" in shown.stdout
    empty = tmp_path / "not-a-run"
    empty.mkdir()
    bad = subprocess.run([UAVCAS, "mavlink", str(empty), "--out", str(tmp_path / "x.parquet")], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode != 0 and bad.stderr.count("\n") == 1 and bad.stderr.startswith("error:")
    assert not (tmp_path / "x.parquet").exists()
    wrong = subprocess.run([UAVCAS, "mavlink", str(mav_run), "--point", "s-nowhere"], capture_output=True,
                           text=True, timeout=120)
    assert wrong.returncode != 0 and wrong.stderr.count("\n") == 1 and "s-nowhere" in wrong.stderr


def test_a_copy_of_the_run_without_captures_is_refused(mav_run, tmp_path):
    from uavcas.rundir import RunDirError

    bare = tmp_path / "bare"
    shutil.copytree(mav_run, bare)
    shutil.rmtree(bare / "pcap")
    (bare / "pcap").mkdir()
    with pytest.raises(RunDirError, match="no captures"):
        mavlink_table(bare)
