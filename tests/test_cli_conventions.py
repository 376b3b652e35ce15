"""CLI conventions of the ecosystem (issue 27): -h, -V/--version, python -m uavcas, completion."""

from __future__ import annotations

import subprocess
import sys

from typer.testing import CliRunner

from uavcas import __version__
from uavcas.cli import app

runner = CliRunner()


def test_python_dash_m_uavcas_prints_the_version():
    r = subprocess.run([sys.executable, "-m", "uavcas", "-V"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == f"uavcas {__version__}", r.stderr


def test_short_and_long_version_agree():
    assert runner.invoke(app, ["-V"]).output == runner.invoke(app, ["--version"]).output


def test_dash_h_is_help_on_the_root_and_on_every_sub_command():
    root = runner.invoke(app, ["-h"])
    assert root.exit_code == 0 and "Usage" in root.output
    names = [c.name for c in app.registered_commands] + [g.name for g in app.registered_groups]
    assert len(names) >= 10
    for name in names:
        r = runner.invoke(app, [name, "-h"])
        assert r.exit_code == 0 and "Usage" in r.output, (name, r.output[-300:])


def test_shell_completion_is_offered():
    r = runner.invoke(app, ["--help"])
    assert "--install-completion" in r.output and "--show-completion" in r.output
