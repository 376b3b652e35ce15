"""Fixtures for analysis and IDS tests: small synthetic datasets with a known separable class (DoS) and a known
indistinguishable class (Wormhole = the benign generator). Built once per session, also across
pytest-xdist workers (`helpers.once`)."""

from __future__ import annotations

import pandas as pd
import pytest

from helpers.once import built_once
from uavcas.dataset.synthetic import make_flows, write_dataset


def _frame(d):
    make_flows(160, flows_per_run=15, seed=3).to_pickle(d / "flows.pkl")


@pytest.fixture(scope="session")
def synth_df(tmp_path_factory):
    return pd.read_pickle(built_once(tmp_path_factory, "synth-df", _frame) / "flows.pkl")


@pytest.fixture(scope="session")
def synth_dir(tmp_path_factory, synth_df):
    return built_once(tmp_path_factory, "synth-dir", lambda d: write_dataset(d / "ds", synth_df)) / "ds"
