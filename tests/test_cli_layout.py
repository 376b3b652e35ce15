"""The CLI's layout (issue 26 item 4): each top-level command or group in the module of its name,
the options several commands share declared once (`uavcas.cli.common`), no file writer in `cli/`."""

from __future__ import annotations

import keyword
import re
from pathlib import Path

import uavcas.cli as cli
from uavcas.cli import app

CLI_DIR = Path(cli.__file__).parent
SHARED_OPTIONS = ("--seed", "--windows", "--window-s", "--episodes", "--profile", "--prefix", "--termination",
                  "--allow-truncated", "--min-attack-fraction")


def _module_of(name: str) -> str:
    stem = name.replace("-", "_")
    return f"uavcas.cli.{stem}_" if keyword.iskeyword(stem) else f"uavcas.cli.{stem}"


def _callbacks(group) -> list:
    out = [c.callback for c in group.registered_commands]
    for g in group.registered_groups:
        out += _callbacks(g.typer_instance)
    return out


def test_every_command_and_group_lives_in_the_module_of_its_name():
    names = []
    for c in app.registered_commands:
        name = c.name or c.callback.__name__
        names.append(name)
        assert c.callback.__module__ == _module_of(name), (name, c.callback.__module__)
    for g in app.registered_groups:
        names.append(g.name)
        modules = {cb.__module__ for cb in _callbacks(g.typer_instance)}
        assert modules == {_module_of(g.name)}, (g.name, modules)
    assert {"flows", "extract", "export", "import", "info", "doctor", "clean", "channel", "bench"} <= set(names)
    # every command module holds commands: no module left behind by a move
    helpers = {"__init__", "__main__", "common"}
    holders = {cb.__module__.rsplit(".", 1)[1] for cb in _callbacks(app)}
    assert {p.stem for p in CLI_DIR.glob("*.py")} - helpers == holders


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

