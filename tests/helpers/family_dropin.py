"""The throwaway attack family of the family drop-in tests (tests/attacks/test_family_dropin.py,
and its real run in test_family_dropin_root.py): one vocabulary row and one module."""

from __future__ import annotations

from pathlib import Path

from helpers.plugin import package_copy

ROW = '''    # a test's throwaway family: a SYN flood of its own, made packets ranked between replay and flood
    FamilyRow(token="synflood", class_name="SYNFlood", effect="synflood", precedence=15,
              label_source="synflood-packets"),
'''

THROWAWAY = '''"""Throwaway family for a test: a SYN flood of its own, on the flood's tool, executor and rules."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from uavcas.scenario_model import ScenarioError, SpecBase, int_field

from .flood import _Flood
from .registry import register


class SynFloodSpec(SpecBase):
    family: Literal["synflood"]
    interval_us: int = Field(gt=0)

    @property
    def nominal_pps(self) -> float:
        return 1e6 / self.interval_us

    def token(self) -> str:
        return f"{self.family}={self.interval_us}"


@register
class SynFlood(_Flood):
    name = "synflood"
    spec = SynFloodSpec
    exclusive_group = None  # combinable with the floods: its own attack

    def parse(self, arg: str | None, tok: str) -> SynFloodSpec:
        if arg is None:
            raise ScenarioError(f"field 'attacks': synflood needs an interval in us, got {tok!r}")
        return SynFloodSpec(family=self.name, interval_us=int_field("attacks.synflood", arg, 1, 10_000_000))

    def spec_from_params(self, params: dict[str, Any]) -> SynFloodSpec:
        return SynFloodSpec(family=self.name, interval_us=int(params.get("interval_us", 1000)))
'''

CONFIG = "synflood=1000-4-1-image-logdist-adaptive-grid-30-95"


def copy_with_throwaway(tmp: Path) -> Path:
    dst = package_copy(tmp, {"attacks/synflood.py": THROWAWAY})
    vocab = dst / "uavcas" / "vocabulary.py"
    text = vocab.read_text()
    end = "\n)\nFAMILY_ROWS"  # the table's last line: one row appended before it
    assert text.count(end) == 1
    vocab.write_text(text.replace(end, "\n" + ROW.rstrip("\n") + end))
    return dst
