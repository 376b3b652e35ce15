"""Node, port and namespace names of a run, derived from its prefix (no root)."""

from __future__ import annotations

import pytest

from uavcas.network import naming
from uavcas.network.naming import Naming


def test_names_fit_ifnamsiz_and_carry_prefix():
    n = Naming("uc1a2b3c")
    assert n.fabric_ns == "uc1a2b3c-fab" and n.node_ns("uav7") == "uc1a2b3c-uav7"
    assert max(len(Naming.link_port(i, j)) for i, j in [(0, 1), (9999, 9998)]) <= naming.IFNAMSIZ
    assert Naming.link_port(3, 7) == "l3-7" and Naming.bridge(3) == "s3" and Naming.host_port(3) == "h3"


@pytest.mark.parametrize("bad", ["", "A1", "1ab", "a", "ab-c", "abcdefghijklm"])
def test_bad_prefix_rejected(bad):
    with pytest.raises(ValueError):
        Naming(bad)


def test_fabric_is_not_a_node_name():
    with pytest.raises(ValueError):
        Naming("uc1").node_ns("fab")
