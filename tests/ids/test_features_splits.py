"""No metadata column is ever a feature; splits are stratified and grouped by run."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas import schema
from uavcas.ids import protocols
from uavcas.ids.features import MetadataLeakError, check_feature_columns, feature_matrix
from uavcas.ids.protocols import BenchConfig, run_protocol
from uavcas.ids.splits import grouped_split


@pytest.mark.parametrize("col", schema.METADATA_COLUMNS + schema.SEQUENCE_COLUMNS + schema.COUNT_COLUMNS + ("config_idx",))
def test_metadata_is_refused(col):
    with pytest.raises(MetadataLeakError):
        check_feature_columns(list(schema.FEATURES[:3]) + [col])


def test_feature_matrix_uses_exactly_the_47_features(synth_df):
    df = synth_df.copy()
    df["config_idx"] = np.arange(len(df))  # the authors' leak: must be ignored
    x = feature_matrix(df)
    assert x.shape == (len(df), 47) and np.isfinite(x).all()
    np.testing.assert_allclose(x[:, 0], df[schema.FEATURES[0]].to_numpy(np.float32))


def test_protocol_models_only_ever_see_features(synth_df, monkeypatch):
    seen = []
    real = protocols.fit_model

    def spy(est, x, y, xv=None, yv=None):
        seen.append(x.shape[1])
        return real(est, x, y, xv, yv)

    monkeypatch.setattr(protocols, "fit_model", spy)
    leaky = synth_df.assign(config_idx=np.arange(len(synth_df)), leak=(synth_df["label"] != "Benign").astype(float))
    for p in ("binary", "multiclass", "ood"):
        run_protocol(leaky, p, BenchConfig(models=("lr",), n_threads=1))
    assert seen == [47, 47, 47]


def test_grouped_split_no_run_in_two_splits(synth_df):
    y, g = synth_df["label"].to_numpy(), synth_df["run_id"].to_numpy()
    sp = grouped_split(y, g, seed=0)
    tr, va, te = set(g[sp.train]), set(g[sp.val]), set(g[sp.test])
    assert not (tr & va or tr & te or va & te)
    assert len(sp.train) + len(sp.val) + len(sp.test) == len(y)
    n = len(y)
    assert abs(len(sp.test) / n - 0.2) < 0.07 and abs(len(sp.val) / n - 0.1) < 0.06
    # stratified: every class is trained on
    assert set(y[sp.train]) == set(y)
    assert grouped_split(y, g, seed=0).test.tolist() == sp.test.tolist()  # seeded


def test_grouped_split_needs_runs():
    with pytest.raises(ValueError, match="at least 2 runs"):
        grouped_split(np.array(["a", "b"] * 5), np.array(["r"] * 10))


def test_composition_parsing():
    from uavcas.vocabulary import families_of

    assert families_of("blackhole+dos=1000") == ("blackhole", "dos")
    assert families_of("dos=1000+blackhole") == ("blackhole", "dos")  # canonical order whatever the input's
    assert families_of("replay=50,200,10,5,inc") == ("replay",)
    assert families_of("benign") == ()
    assert protocols.is_dos("DoS") and protocols.is_dos("DoS Hulk") and not protocols.is_dos("DoS+Replay")
    assert not protocols.is_dos("DDoS")
