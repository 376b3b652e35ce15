"""Every attack tool's process starts by its file's path (`uavcas.attacks.tools.tool_path`) and
loads no family: `uavcas.attacks` would load every family before t0, per attacker."""

from __future__ import annotations

import subprocess
import sys

import pytest

from uavcas.attacks.tools import tool_path


@pytest.mark.parametrize("tool", ["pacer", "replayer", "mavinject"])
def test_a_tool_runs_by_its_path_without_the_families(tool, tmp_path):
    r = subprocess.run([sys.executable, "-X", "importtime", str(tool_path(tool)), "--help"], capture_output=True,
                       text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.startswith(f"usage: {tool}.py")
    imported = {line.rsplit("|", 1)[-1].strip() for line in r.stderr.splitlines() if line.startswith("import time:")}
    assert not {m for m in imported if m == "uavcas.attacks" or m.startswith("uavcas.attacks.")}


def test_an_unknown_tool_is_refused():
    with pytest.raises(ValueError, match="no attack tool 'nope'"):
        tool_path("nope")
    with pytest.raises(ValueError, match="no attack tool '__init__'"):
        tool_path("__init__")
