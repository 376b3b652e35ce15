"""A campaign run's shard records the feature standard it was extracted with (issue 40's latent
bug: the standard travelled in `DataFrame.attrs`, which `label_flows`' `pd.concat` drops, so the
campaign's writer fell back to `cic`). Without root: the campaign's own extraction and commit
(`task.extract_outcome`, `run._commit`, `rebuild`) on a synthetic run directory."""

from __future__ import annotations

import json

import pyarrow.parquet as pq
import pytest

from helpers.synth_run import build_run
from uavcas.campaign.layout import CampaignDir, CampaignError
from uavcas.campaign.run import _commit
from uavcas.campaign.task import Extraction, RunOutcome, extract_outcome
from uavcas.dataset.parquet import table_standard
from uavcas.dataset.publish import publish
from uavcas.dataset.store import rebuild
from uavcas.flows.standards import standard


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("run") / "run-synth")


@pytest.mark.parametrize("features", ["paper", "cic"])
def test_a_campaign_commit_records_the_feature_standard(run_dir, tmp_path, features):
    cdir = CampaignDir(tmp_path / "ds")
    out = extract_outcome(RunOutcome(index=0, ok=False, host="test", wall_s=0.0), run_dir,
                          Extraction(features=features))
    assert out.ok and out.n_flows > 0
    _commit(cdir, out)
    assert cdir.is_done(0) and table_standard(pq.read_schema(cdir.shard_path(0))) == features
    card = rebuild(cdir.root)
    assert card["features"]["standard"] == features and card["runs"][0]["features"] == features
    names = pq.read_schema(cdir.root / "flows.parquet").names
    assert set(standard(features).columns) <= set(names)  # the values are the standard's, under its names
    assert json.loads((cdir.root / "dataset.json").read_text())["features"]["standard"] == features
    pub = publish(cdir.root, tmp_path / "pub")
    assert f"feature standard: `{features}`" in (pub.out / "README.md").read_text()
    assert f"features: {features};" in json.loads((pub.out / "croissant.json").read_text())["description"]


def test_a_resumed_campaign_keeps_its_feature_standard(tmp_path):
    cdir = CampaignDir(tmp_path)
    cdir.bind_extraction(Extraction())
    assert json.loads(cdir.extraction_path.read_text()) == {"view": "5tuple", "termination": "connection"}
    with pytest.raises(CampaignError, match="not --view 5tuple --termination connection --features paper"):
        cdir.bind_extraction(Extraction(features="paper"))


def test_an_unknown_feature_standard_is_refused():
    with pytest.raises(ValueError, match="--features: 'nope' is not one of cic"):
        Extraction(features="nope")
