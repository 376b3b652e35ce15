"""`uavcas.cli.common`: the helpers several commands share behave the same for each of them."""

from __future__ import annotations

import pytest
import typer

from uavcas.cli.common import prefix_or_fail, warn


def test_a_prefix_is_checked_once_for_every_command_that_takes_one(capsys):
    assert prefix_or_fail(None) is None and prefix_or_fail("uc0001") == "uc0001"
    with pytest.raises(typer.Exit) as exc:
        prefix_or_fail("BAD")
    assert exc.value.exit_code == 2
    assert "--prefix: bad prefix 'BAD'" in capsys.readouterr().err


def test_warnings_are_one_line_each(capsys):
    warn(["a [b] c", "d"])
    assert capsys.readouterr().err.splitlines() == ["warning: a [b] c", "warning: d"]

