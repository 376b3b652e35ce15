"""Runner, attack executor and `uavcas run` CLI without root: schedule, routing of wormholes, errors."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

sys.path.insert(0, str(Path(__file__).parent / "apps"))
from runplans import attack, link, make_plan, nodes  # noqa: E402

from uavcas.cli import app  # noqa: E402
from uavcas.attacks.blackhole import switch_ports  # noqa: E402
from uavcas.emulation import preflight as preflight_mod  # noqa: E402
from uavcas.emulation.attacks import AttackExecutor  # noqa: E402
from uavcas.emulation.controller import Detour  # noqa: E402
from uavcas.emulation.naming import check_prefix  # noqa: E402
from uavcas.emulation.runner import prepare_out_dir, schedule  # noqa: E402

CONFIG = "dos=1000-5-2-image-logdist-adaptive-random-30-95"


def _plan():
    ns = nodes(3)
    links = [link("uav0", "bs0"), link("uav1", "bs0"), link("uav0", "uav1")]  # triangle
    return make_plan(ns, links, [attack("dos", ["uav1"], "uav0", 2.0, 6.0),
                                 attack("wormhole", ["uav1"], "uav0", 4.0, 8.0, k=1)],
                     n_windows=2, window_s=4.0, routes=[["uav0", "uav1", "bs0"], ["uav1", "bs0"]],
                     wormholes=[("uav0", "uav1", "bs0")])


def test_schedule_orders_stop_window_start_calibrate():
    ev = [(e.t_s, e.kind) for e in schedule(_plan())]
    assert ev == [(2.0, "start"), (3.0, "calibrate"), (4.0, "window"), (4.0, "start"), (5.0, "calibrate"), (6.0, "stop"),
                  (8.0, "stop"), (8.0, "end")]


class _FakeEmu:
    fabric_ns = "x-fab"


def test_wormhole_detour_only_while_active(tmp_path):
    p = _plan()
    ex = AttackExecutor(_FakeEmu(), p, tmp_path, p.duration_s)
    w = p.windows[0]
    assert ex.wormholes_for(w) == []  # idle: no detour
    ex.active["wormhole-1"] = p.attacks[1]
    assert ex.wormholes_for(w) == [Detour("uav0", "uav1", "bs0")]
    # a window where the plan has no detour (no usable one) gets none
    assert ex.wormholes_for(w.model_copy(update={"wormholes": []})) == []
    assert switch_ports(p.node("uav1").index) == ["h1", "l1-*"]


def test_prepare_out_dir_replaces_only_run_files(tmp_path):
    out = tmp_path / "r"
    (out / "pcap").mkdir(parents=True)
    (out / "pcap" / "s-uav0.pcap").write_bytes(b"old")
    (out / "run.json").write_text("{}")
    (out / "notes.txt").write_text("mine")
    prepare_out_dir(out)
    assert not (out / "run.json").exists() and list((out / "pcap").iterdir()) == []
    assert (out / "notes.txt").read_text() == "mine"


def test_cli_bad_config_is_one_line_exit_2(tmp_path):
    r = CliRunner().invoke(app, ["run", "dos=abc-5-2-image-logdist-adaptive-random-30-95", "--out", str(tmp_path / "r")])
    assert r.exit_code == 2 and "error" in r.output and not (tmp_path / "r").exists()


def test_cli_not_root_exit_2_before_anything(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    r = CliRunner().invoke(app, ["run", CONFIG, "--windows", "1", "--out", str(tmp_path / "r")])
    assert r.exit_code == 2 and "root" in r.output and not (tmp_path / "r").exists()


def test_cli_missing_tool_exit_2(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    real = preflight_mod.shutil.which
    monkeypatch.setattr(preflight_mod.shutil, "which", lambda t: None if t == "hping3" else real(t) or f"/bin/{t}")
    r = CliRunner().invoke(app, ["run", CONFIG, "--windows", "1", "--out", str(tmp_path / "r")])
    assert r.exit_code == 2 and "hping3" in r.output and not (tmp_path / "r").exists()


def test_cli_refuses_foreign_out_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    monkeypatch.setattr(preflight_mod.shutil, "which", lambda t: f"/bin/{t}")
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "thesis.tex").write_text("x")
    r = CliRunner().invoke(app, ["run", CONFIG, "--windows", "1", "--out", str(tmp_path / "r")])
    assert r.exit_code == 2 and "not empty" in r.output


def test_cli_bad_windows_exit_2(tmp_path):
    r = CliRunner().invoke(app, ["run", CONFIG, "--out", str(tmp_path / "r"), "--windows", "0"])
    assert r.exit_code == 2 and not (tmp_path / "r").exists()


@pytest.mark.parametrize("bad", ["UPPER", "has space", "", "x" * 40, "-lead"])
def test_prefix_validator_refuses(bad):
    # The validator itself: a CLI test could pass without it (the run would fail later) and,
    # as root, would start a real emulation.
    with pytest.raises(ValueError):
        check_prefix(bad)


def test_prefix_validator_accepts_and_cli_reports_it(tmp_path, monkeypatch):
    check_prefix("uc7")
    monkeypatch.setattr(os, "geteuid", lambda: 1000)  # were validation skipped, preflight stops here
    r = CliRunner().invoke(app, ["run", CONFIG, "--out", str(tmp_path / "r"), "--prefix", "UPPER"])
    assert r.exit_code == 2 and "--prefix" in r.output and "root" not in r.output
