"""Fixtures for analysis and IDS tests: small synthetic datasets with a known separable class (DoS) and a known
indistinguishable class (Wormhole = the benign generator)."""

from __future__ import annotations

import pytest

from uavcas.dataset.synthetic import make_flows, write_dataset


@pytest.fixture(scope="session")
def synth_df():
    return make_flows(160, flows_per_run=15, seed=3)


@pytest.fixture(scope="session")
def synth_dir(tmp_path_factory, synth_df):
    return write_dataset(tmp_path_factory.mktemp("synth") / "ds", synth_df)
