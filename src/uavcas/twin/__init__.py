"""The pure digital twin: `twin.plan.plan(scenario, seed) -> Plan`, the plan's typed values
(`twin.model`, re-exported here) and `twin.load.read_plan` (plan.json -> Plan, each attack's spec
read by its family).

`plan` and `read_plan` are not re-exported: both load the attack families, and the families import
this package's modules (`model`, `interference`), so this `__init__`, which Python runs first, must
not lead back to them."""

from .model import Attack, Link, Node, Plan, Route, Site, Window, WormholeOverride

__all__ = ["Attack", "Link", "Node", "Plan", "Route", "Site", "Window", "WormholeOverride"]
