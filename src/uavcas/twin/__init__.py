"""The pure digital twin: `plan(scenario, seed) -> Plan`, the plan's typed values and
`read_plan` (plan.json -> Plan, each attack's spec read by its family)."""

from .load import read_plan
from .model import Attack, Link, Node, Plan, Route, Site, Window, WormholeOverride
from .plan import plan

__all__ = ["Attack", "Link", "Node", "Plan", "Route", "Site", "Window", "WormholeOverride", "plan", "read_plan"]
