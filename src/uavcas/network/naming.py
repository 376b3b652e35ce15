"""Names of everything one emulation run creates, derived from a per-run prefix.

Every kernel object of a run is findable from its prefix alone, so two runs coexist and
`uavcas clean --prefix P` can remove exactly what a crashed run left:

* namespaces ``<prefix>-fab`` (all switches) and ``<prefix>-<node>`` (one per node);
* interfaces live *inside* those namespaces only, so their short names (``s3``, ``h3``,
  ``l3-7``) never collide with another run and always fit IFNAMSIZ (15 characters);
* cgroups ``.../uavcas.<prefix>/<node>`` and the run directory ``/run/uavcas/<prefix>``.
"""

from __future__ import annotations

import os
import re
import secrets
from dataclasses import dataclass
from pathlib import Path

IFNAMSIZ = 15  # usable characters of a Linux interface name
PREFIX_RE = re.compile(r"^[a-z][a-z0-9]{1,11}$")
NODE_RE = re.compile(r"^[a-z][a-z0-9_]{0,30}$")
RUN_ROOT = Path(os.environ.get("UAVCAS_RUN_ROOT", "/run/uavcas"))
FABRIC_SUFFIX = "fab"
LINK_PORT_RE = re.compile(r"l(\d+)-(\d+)")


def new_prefix() -> str:
    """A fresh prefix: 'uc' + 6 hex digits (collision odds 1 in 16M per pair of live runs)."""
    return "uc" + secrets.token_hex(3)


def check_prefix(prefix: str) -> str:
    if not PREFIX_RE.match(prefix):
        raise ValueError(f"bad prefix {prefix!r}: want [a-z][a-z0-9]{{1,11}}")
    return prefix


@dataclass(frozen=True)
class Naming:
    prefix: str

    def __post_init__(self) -> None:
        check_prefix(self.prefix)

    # namespaces ---------------------------------------------------------------------------
    @property
    def fabric_ns(self) -> str:
        return f"{self.prefix}-{FABRIC_SUFFIX}"

    def node_ns(self, node: str) -> str:
        if not NODE_RE.match(node) or node == FABRIC_SUFFIX:
            raise ValueError(f"bad node name {node!r}")
        return f"{self.prefix}-{node}"

    def owns_ns(self, ns: str) -> bool:
        return ns.startswith(self.prefix + "-")

    # interfaces inside the fabric namespace (indices are Plan.nodes positions) ---------------
    @staticmethod
    def bridge(i: int) -> str:
        return _ifname(f"s{i}")

    @staticmethod
    def host_port(i: int) -> str:
        """The switch-side end of node i's host link (the node side is `eth0` in its namespace)."""
        return _ifname(f"h{i}")

    @staticmethod
    def link_port(i: int, j: int) -> str:
        """Port on switch i towards switch j. Its egress carries (and shapes) direction i -> j."""
        return _ifname(f"l{i}-{j}")

    @staticmethod
    def link_peer(port: str) -> int | None:
        """The switch a link port leads to (`link_port(i, j)` -> j); None for any other port."""
        m = LINK_PORT_RE.fullmatch(port)
        return int(m.group(2)) if m else None

    HOST_IF = "eth0"

    # files --------------------------------------------------------------------------------
    @property
    def run_dir(self) -> Path:
        return RUN_ROOT / self.prefix

    @property
    def cgroup_dir_name(self) -> str:
        return f"uavcas.{self.prefix}"


def _ifname(name: str) -> str:
    if len(name) > IFNAMSIZ:
        raise ValueError(f"interface name {name!r} exceeds {IFNAMSIZ} characters")
    return name
