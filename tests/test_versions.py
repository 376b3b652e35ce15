"""One record of the versions behind an output (run.json, dataset.json)."""

from __future__ import annotations

import platform

import numpy

from uavcas import __version__
from uavcas.versions import package_versions


def test_versions_name_uavcas_python_and_each_module_asked_for():
    v = package_versions("numpy", "uavcas_no_such_module")
    assert v == {"uavcas": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
                 "uavcas_no_such_module": None}
