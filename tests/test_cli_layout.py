"""The CLI's layout (issue 26 item 4): each top-level command or group in the module of its name,
the options several commands share declared once (`uavcas.cli.common`), no file writer in `cli/`."""

from __future__ import annotations

import importlib
import inspect
import keyword
import os
import re
import subprocess
import sys
from pathlib import Path

import typer
import typer.main as typer_main

import uavcas.cli as cli
from uavcas.cli import app

CLI_DIR = Path(cli.__file__).parent
SHARED_OPTIONS = ("--seed", "--windows", "--window-s", "--rounds", "--profile", "--prefix", "--termination",
                  "--allow-truncated", "--min-attack-fraction")


def _module_of(name: str) -> str:
    stem = name.replace("-", "_")
    return f"uavcas.cli.{stem}_" if keyword.iskeyword(stem) else f"uavcas.cli.{stem}"


def _callbacks(group) -> list:
    out = [c.callback for c in group.registered_commands]
    for g in group.registered_groups:
        out += _callbacks(g.typer_instance)
    return out


def _registered(entry: cli.Registered) -> typer.Typer:
    """A Typer holding what `entry`'s module registers."""
    holder = typer.Typer()
    importlib.import_module(f"uavcas.cli.{entry.module}").register(holder)
    return holder


def test_every_command_and_group_lives_in_the_module_of_its_name():
    names = []
    holders = set()
    for entry in cli.COMMANDS:
        names.append(entry.name)
        assert f"uavcas.cli.{entry.module}" == _module_of(entry.name), entry
        holder = _registered(entry)
        registered = [c.name or c.callback.__name__ for c in holder.registered_commands] + \
            [g.name for g in holder.registered_groups]
        assert registered == [entry.name], (entry, registered)  # one command or group per module
        modules = {cb.__module__ for cb in _callbacks(holder)}
        assert modules == {_module_of(entry.name)}, (entry.name, modules)
        holders |= {m.rsplit(".", 1)[1] for m in modules}
    assert {"flows", "extract", "export", "import", "info", "doctor", "clean", "channel", "bench"} <= set(names)
    # every command module holds commands: no module left behind by a move
    helpers = {"__init__", "__main__", "common", "console"}
    assert {p.stem for p in CLI_DIR.glob("*.py")} - helpers == holders


def test_the_root_lists_each_commands_own_help_line_in_the_registered_order():
    root = typer_main.get_command(app)
    assert root.list_commands(None) == [e.name for e in cli.COMMANDS]
    for entry in cli.COMMANDS:
        cmd = cli.load(entry)
        # what typer's command table shows of a command: the first paragraph of its help
        assert inspect.cleandoc(cmd.short_help or cmd.help or "").split("\n\n")[0] == entry.help, entry.name
        panel = getattr(cmd.rich_help_panel, "value", cmd.rich_help_panel)  # typer's DefaultPlaceholder or a name
        assert not cmd.hidden and not cmd.deprecated and panel is None, entry.name  # as the unloaded entry shows
        assert root.get_command(None, entry.name).name == entry.name


def test_the_root_help_imports_no_command_module():
    code = ("import sys\nfrom uavcas.cli import main\nsys.argv = ['uavcas', '--help']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print('loaded:', sorted(m for m in sys.modules if m.startswith('uavcas.cli.')))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(CLI_DIR.parents[1])})
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == "loaded: ['uavcas.cli.console']", r.stdout[-500:]
    assert "Commands" in r.stdout and all(e.name in r.stdout for e in cli.COMMANDS)


def test_the_shared_options_are_declared_once_in_common():
    for path in sorted(CLI_DIR.glob("*.py")):
        if path.name == "common.py":
            continue
        text = path.read_text()
        for opt in SHARED_OPTIONS:
            assert f'"{opt}"' not in text, f"{path.name} declares {opt}: use the helper in cli/common.py"
        assert "check_target(" not in text and "check_out_dir(" not in text, \
            f"{path.name}: output checks go through cli.common.check_output"


def test_no_file_writer_in_the_cli():
    writers = re.compile(r"ParquetWriter|CSVWriter|\bpq\.write_table|\bpacsv\.|\.to_parquet\(|\.to_csv\(")
    for path in sorted(CLI_DIR.glob("*.py")):
        found = writers.findall(path.read_text())
        assert not found, f"{path.name} writes files itself ({found}): move the writer into the library"


def test_a_command_whose_dependency_is_missing_fails_in_one_line():
    code = ("import sys\nsys.modules['mlcroissant'] = None  # import mlcroissant -> ImportError\n"
            "from uavcas.cli import main\nsys.argv = ['uavcas', 'publish', '-h']\nmain()")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(CLI_DIR.parents[1])})
    assert r.returncode == 1 and r.stderr.count("\n") == 1, r.stderr[-500:]
    assert r.stderr.startswith("error: publish cannot load: ") and "mlcroissant" in r.stderr
