"""Runner, attack executor and `uavcas run` CLI without root: schedule, routing of wormholes, errors."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from helpers.runplans import attack, link, make_plan, nodes
from uavcas.attacks.blackhole import switch_ports
from uavcas.cli import app
from uavcas.emulation import preflight as preflight_mod
from uavcas.emulation.attacks import AttackExecutor
from uavcas.emulation.preflight import prepare_out_dir
from uavcas.emulation.runner import schedule
from uavcas.network.forwarding import Detour
from uavcas.network.naming import check_prefix

CONFIG = "dos=1000-5-2-image-logdist-adaptive-random-30-95"


def _plan():
    ns = nodes(3)
    links = [link("uav0", "bs0"), link("uav1", "bs0"), link("uav0", "uav1")]  # triangle
    return make_plan(ns, links, [attack("dos", ["uav1"], "uav0", 2.0, 6.0),
                                 attack("wormhole", ["uav1"], "uav0", 4.0, 8.0, k=1)],
                     n_windows=2, window_s=4.0, routes=[["uav0", "uav1", "bs0"], ["uav1", "bs0"]],
                     wormholes=[("uav0", "uav1", "bs0")])


def test_schedule_orders_stop_window_start():
    ev = [(e.t_s, e.kind) for e in schedule(_plan())]  # floods are paced, never recalibrated
    assert ev == [(2.0, "start"), (4.0, "window"), (4.0, "start"), (6.0, "stop"), (8.0, "stop"), (8.0, "end")]


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


def _old_run(out: Path, prefix: str = "uc0001", finished: bool = True) -> None:
    """A directory an earlier run wrote: the marker, its files, a capture and a tool log."""
    (out / "pcap").mkdir(parents=True)
    (out / "logs").mkdir()
    (out / ".uavcas-run").write_text(f'{{"prefix": "{prefix}", "pid": 1, "started_unix": 1.0}}')
    (out / "plan.json").write_text("{}")
    (out / "pcap" / "s-uav0.pcap").write_bytes(b"old")
    (out / "logs" / "curl-bs0.err").write_text("old")
    if finished:
        (out / "attacks.jsonl").write_text("")


def test_out_dir_of_an_old_run_is_reused_removing_only_what_a_run_writes(tmp_path):
    out = tmp_path / "r"
    _old_run(out, finished=False)  # killed: no run.json, the marker says whose it was
    (out / "notes.txt").write_text("mine")
    (out / "pcap" / "README").write_text("mine too")
    prepare_out_dir(out, "uc0002")
    assert sorted(p.name for p in out.iterdir()) == [".uavcas-run", "notes.txt", "pcap"]
    assert [p.name for p in (out / "pcap").iterdir()] == ["README"]
    assert (out / "notes.txt").read_text() == "mine" and '"uc0002"' in (out / ".uavcas-run").read_text()


@pytest.mark.parametrize("files", [{"plan.json": "{}"}, {"run.json": "{}"}, {"plan.json": "{}", "notes": "x"}])
def test_out_dir_that_merely_holds_a_run_file_name_is_refused_and_untouched(tmp_path, files):
    out = tmp_path / "r"
    (out / "pcap").mkdir(parents=True)
    (out / "pcap" / "mine.pcap").write_bytes(b"precious")
    (out / "logs").mkdir()
    (out / "logs" / "mine.log").write_text("precious")
    for name, text in files.items():
        (out / name).write_text(text)
    before = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert "holds no" in preflight_mod.out_dir_problem(out)
    with pytest.raises(ValueError, match="holds no"):
        prepare_out_dir(out, "uc0002")
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == before
    assert (out / "pcap" / "mine.pcap").read_bytes() == b"precious"


def test_out_dir_of_a_live_run_or_of_two_runs_is_refused(tmp_path, monkeypatch):
    from uavcas.emulation import cleanup
    from uavcas.network import naming

    monkeypatch.setattr(naming, "RUN_ROOT", tmp_path / "registry")
    out = tmp_path / "r"
    _old_run(out, "uc0003")
    lock = cleanup.RunLock(cleanup.RunRecord("uc0003", os.getpid(), []))
    try:
        assert "live run (prefix uc0003)" in preflight_mod.out_dir_problem(out)
    finally:
        lock.release()
    assert preflight_mod.out_dir_problem(out) is None
    (out / ".uavcas-run").write_text('{"prefix": "uc0004", "pid": 1, "started_unix": 1.0}')
    (out / "run.json").write_text((Path(__file__).parent / "apps").as_posix())  # not a run.json
    assert "no readable uavcas run" in preflight_mod.out_dir_problem(out)


def test_cli_run_into_a_foreign_dir_is_one_line_exit_2(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    out = tmp_path / "r"
    out.mkdir()
    (out / "plan.json").write_text("my own plan")
    r = CliRunner().invoke(app, ["run", CONFIG, "--windows", "1", "--out", str(out)])
    assert r.exit_code == 2 and "holds no uavcas run" in r.output
    assert (out / "plan.json").read_text() == "my own plan"


def test_cli_bad_config_is_one_line_exit_2(tmp_path):
    r = CliRunner().invoke(app,
                           ["run", "dos=abc-5-2-image-logdist-adaptive-random-30-95", "--out", str(tmp_path / "r")])
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
