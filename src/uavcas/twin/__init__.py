"""The pure digital twin: `plan(scenario, seed) -> Plan` and the plan's typed values."""

from .model import Attack, Link, Node, Plan, Route, Site, Window, WormholeOverride
from .plan import plan

__all__ = ["Attack", "Link", "Node", "Plan", "Route", "Site", "Window", "WormholeOverride", "plan"]
