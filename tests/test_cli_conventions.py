"""CLI conventions of the ecosystem (issue 27): -h, -V/--version, python -m uavcas, completion."""

from __future__ import annotations

import subprocess
import sys

import pytest
import typer.main as typer_main
from typer.testing import CliRunner

from uavcas import __version__
from uavcas.cli import COMMANDS, app

runner = CliRunner()


def test_python_dash_m_uavcas_prints_the_version():
    r = subprocess.run([sys.executable, "-m", "uavcas", "-V"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == f"uavcas {__version__}", r.stderr


def test_short_and_long_version_agree():
    assert runner.invoke(app, ["-V"]).output == runner.invoke(app, ["--version"]).output


def test_dash_h_is_help_on_the_root_and_on_every_sub_command():
    root = runner.invoke(app, ["-h"])
    assert root.exit_code == 0 and "Usage" in root.output
    names = [e.name for e in COMMANDS]
    assert len(names) >= 10
    for name in names:
        r = runner.invoke(app, [name, "-h"])
        assert r.exit_code == 0 and "Usage" in r.output, (name, r.output[-300:])


def test_shell_completion_is_offered():
    r = runner.invoke(app, ["--help"])
    assert "--install-completion" in r.output and "--show-completion" in r.output


def _one_line_error(r, *needles):
    assert r.exit_code == 2, r.output
    assert r.output.startswith("error: ") and r.output.count("\n") == 1, r.output
    for n in needles:
        assert n in r.output, (n, r.output)


def test_a_bad_choice_a_bound_or_a_missing_argument_is_one_line():
    _one_line_error(runner.invoke(app, ["extract", "x", "--out", "y", "--view", "bogus"]), "--view", "'bogus'",
                    "window-host")
    _one_line_error(runner.invoke(app, ["plan", "x", "--window-s", "0.1"]), "--window-s", "0.5")
    _one_line_error(runner.invoke(app, ["plan"]), "CONFIG")
    _one_line_error(runner.invoke(app, ["nope"]), "No such command")
    _one_line_error(runner.invoke(app, ["run", "x", "--out", "y", "--bogus"]), "--bogus")
    _one_line_error(runner.invoke(app, ["channel", "predict", "--in", "x", "--out", "y"]), "--model", "freespace")


def test_choices_are_listed_in_the_help():
    out = runner.invoke(app, ["extract", "-h"]).output
    assert "5tuple|hostpair" in out.replace("\n", "").replace(" ", "").replace("│", "")
    assert "connection|cic|timeout" in runner.invoke(app,
                                                     ["flows",
                                                      "-h"]).output.replace(" ", "").replace("\n", "").replace("│", "")


def test_the_same_option_has_the_same_bounds_everywhere():
    cmd = typer_main.get_command(app)
    seen: dict[str, set] = {}

    def walk(c, path):
        for p in getattr(c, "params", []):
            if p.opts and p.opts[0].startswith("--") and p.opts[0] in ("--seed", "--windows", "--window-s",
                                                                       "--profile"):
                seen.setdefault(p.opts[0], set()).add((p.min, p.max, p.default))
        for name in c.list_commands(None) if hasattr(c, "list_commands") else ():
            walk(c.get_command(None, name), f"{path} {name}")  # the root loads each command as it is asked

    walk(cmd, "uavcas")
    assert {"--seed", "--windows", "--window-s", "--profile"} <= set(seen)
    for opt, kinds in seen.items():
        assert len(kinds) == 1, (opt, kinds)


def test_no_folder_is_created_that_the_user_did_not_name(tmp_path):
    target = tmp_path / "a" / "b" / "plan.json"
    _one_line_error(runner.invoke(app, ["plan", "benign-5-2-image-logdist-adaptive-random-30-95", "--windows", "1",
                                        "--out", str(target)]), "does not exist")
    assert not (tmp_path / "a").exists()
    r = runner.invoke(app, ["plan", "benign-5-2-image-logdist-adaptive-random-30-95", "--windows", "1",
                            "--out", str(tmp_path)])
    _one_line_error(r, "it is a directory")  # refused before the plan is printed
    # a file's folder must exist; an output directory named as one is created only once there is
    # work to write: bad input leaves nothing behind
    r = runner.invoke(app, ["campaign", "manifest", "--out", str(tmp_path / "x" / "m.jsonl")])
    _one_line_error(r, "does not exist")
    for argv in (["report", str(tmp_path), "--out", str(tmp_path / "x" / "r")],
                 ["bench", "ids", str(tmp_path), "--out", str(tmp_path / "x" / "b")],
                 ["extract", str(tmp_path), "--out", str(tmp_path / "x" / "ds")],
                 ["publish", str(tmp_path), "--out", str(tmp_path / "x" / "pub")],
                 ["export", str(tmp_path), "--format", "csv", "--out", str(tmp_path / "x" / "f.csv")]):
        r = runner.invoke(app, argv)
        assert r.exit_code == 2 and r.output.count("\n") == 1 and not (tmp_path / "x").exists(), (argv, r.output)


@pytest.mark.slow  # 6 s on 2 cores
def test_output_to_a_pipe_is_not_cut_to_a_terminals_width():
    r = subprocess.run([sys.executable, "-m", "uavcas", "plan", "benign-20-2-image-logdist-adaptive-random-10-95",
                        "--windows", "2"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "…" not in r.stdout and "..." not in r.stdout
    assert "disconnected" in r.stdout


def test_each_bad_input_of_the_review_names_the_argument(tmp_path):
    """Issue 27's list: each exits 2 with one line naming what is wrong with the user's argument."""
    (tmp_path / "notrun").mkdir()
    (tmp_path / "existing.txt").write_text("mine")
    _one_line_error(runner.invoke(app, ["extract", str(tmp_path / "notrun"), "--out", str(tmp_path / "ds")]),
                    "not a run directory")
    _one_line_error(runner.invoke(app, ["info", str(tmp_path / "missing")]), f"{tmp_path / 'missing'} does not exist")
    _one_line_error(runner.invoke(app, ["report", str(tmp_path), "--out", str(tmp_path / "existing.txt")]),
                    "--out", "it is a regular file")
    r = runner.invoke(app, ["bench", "ids", str(tmp_path / "nope"), "--out", str(tmp_path / "b")])
    _one_line_error(r, "nope does not exist")
    assert r.output.count(str(tmp_path / "nope")) == 1  # named once
    assert (tmp_path / "existing.txt").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing.txt", "notrun"]
