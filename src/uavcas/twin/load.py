"""Reading a plan: `plan.json` -> `Plan`, each attack's spec read by its own family.

The plan records (`twin.model`) sit below the attack families and cannot know their spec
classes; this layer above them hands the registry in (pydantic's validation context, key
`uavcas.scenario_model.SPEC_READER`), so that every family validates its own parameters when a
plan is read.
"""

from __future__ import annotations

from typing import Any

from uavcas.attacks import family
from uavcas.scenario.codec import parse
from uavcas.scenario_model import SPEC_READER, Scenario, ScenarioError, SpecBase

from .model import Plan


class _FamilySpecs:
    """`uavcas.scenario_model.SpecReader` through the family registry."""

    def spec(self, name: str, data: Any) -> SpecBase:
        return family(name).read_spec(data)

    def spec_from_params(self, name: str, params: dict[str, Any]) -> SpecBase:
        return family(name).spec_from_params(params)

    def scenario(self, config: str) -> Scenario | None:
        try:
            return parse(config)
        except ScenarioError:  # a hand-made plan's config ("test") is no scenario
            return None


CONTEXT = {SPEC_READER: _FamilySpecs()}  # the validation context of every plan read


def read_plan(text: str) -> Plan:
    """The plan of a `plan.json` text (`Plan.to_json` gives it back byte for byte)."""
    return Plan.model_validate_json(text, context=CONTEXT)


def plan_from_data(data: dict[str, Any]) -> Plan:
    """The plan of its JSON form already parsed (a dict)."""
    return Plan.model_validate(data, context=CONTEXT)
