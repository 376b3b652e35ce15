"""`uavcas.load_dataset`: X holds features only, aligned with y, groups and meta."""

from __future__ import annotations

import numpy as np
import pytest

import uavcas
from uavcas import schema
from uavcas.flows.standards.cic import FEATURES
from uavcas.ids.features import feature_sets


def test_features_labels_groups_meta_consistent(synth_dir, synth_df):
    X, y, groups, meta = uavcas.load_dataset(synth_dir)
    assert len(X) == len(y) == len(groups) == len(meta) == len(synth_df)
    assert list(X.columns) == list(FEATURES) and np.isfinite(X.to_numpy()).all()
    # no metadata among the features; nothing lost either
    never = set(schema.METADATA_COLUMNS) | set(schema.SEQUENCE_COLUMNS) | set(schema.COUNT_COLUMNS)
    assert not never & set(X.columns)
    assert not set(X.columns) & set(meta.columns) and set(X.columns) | set(meta.columns) == set(synth_df.columns)
    assert (X.index == meta.index).all() and (groups == meta["run_id"]).all() and (y == meta["label"]).all()
    assert groups.nunique() == synth_df["run_id"].nunique() and set(y) == set(synth_df["label"])
    # rows stay aligned: the flows of one run keep their features
    run = groups.iloc[0]
    a = X[groups == run]["Flow Duration"].to_numpy()
    b = synth_df[synth_df["run_id"] == run]["Flow Duration"].to_numpy()
    np.testing.assert_allclose(np.sort(a), np.sort(b))


def test_feature_selection_by_set_or_columns(synth_dir):
    name = next(iter(feature_sets()))
    assert list(uavcas.load_dataset(synth_dir, features=name).X.columns) == list(feature_sets()[name])
    d = uavcas.load_dataset(synth_dir, features=["SYN Flag Count", "Flow Duration"])
    assert list(d.X.columns) == ["SYN Flag Count", "Flow Duration"] and "Packet Length Mean" in d.meta.columns
    with pytest.raises(ValueError, match="not flow features"):
        uavcas.load_dataset(synth_dir, features=["Flow Duration", "config"])
    with pytest.raises(ValueError, match="unknown feature set"):
        uavcas.load_dataset(synth_dir, features="nope")


def test_trains_a_grouped_model(synth_dir):
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.model_selection import GroupKFold, cross_val_score

    X, y, groups, _ = uavcas.load_dataset(synth_dir)
    dos = y.isin(["Benign", "DoS"])
    s = cross_val_score(RandomForestClassifier(n_estimators=20, random_state=0), X[dos], y[dos], groups=groups[dos],
                        cv=GroupKFold(3), scoring="f1_weighted")
    assert s.min() > 0.95


@pytest.mark.shared
def test_external_sample_each_flow_its_own_group(shared_data):
    p = shared_data / "ids-samples" / "unsw-nb15-testing-head4528"
    if not p.is_dir():
        pytest.skip(f"{p} not found")
    X, y, groups, meta = uavcas.load_dataset(p)
    assert groups.is_unique and len(X) == len(y) and not set(X.columns) & set(meta.columns)


@pytest.mark.slow  # 6 s on 2 cores
def test_context_columns_on_request(synth_dir, synth_df, tmp_path):
    from uavcas.dataset.synthetic import write_dataset

    X = uavcas.load_dataset(synth_dir, context=True).X
    assert list(X.columns) == list(FEATURES) + list(schema.CONTEXT_FEATURES)
    assert not any(c.startswith("ctx_") for c in uavcas.load_dataset(synth_dir).X.columns)
    bare = write_dataset(tmp_path / "bare", synth_df.drop(columns=list(schema.CONTEXT_FEATURES)))
    with pytest.raises(ValueError, match="no context columns"):
        uavcas.load_dataset(bare, context=True)


def test_nonfinite_policy_is_applied_and_recorded(tmp_path):
    from uavcas.dataset.synthetic import make_flows, write_dataset

    df = make_flows(4, flows_per_run=20, seed=5)
    # what CICFlowMeter writes for a zero-duration flow: an infinite rate, no IAT
    df.loc[::7, "Flow Packets/s"] = np.inf
    df.loc[::5, "Flow IAT Mean"] = np.nan
    ds = write_dataset(tmp_path / "ds", df)
    raw = df[list(FEATURES)].to_numpy(dtype=float)
    bad_values, bad_rows = int((~np.isfinite(raw)).sum()), int((~np.isfinite(raw)).any(axis=1).sum())
    assert bad_values and bad_rows < len(df)
    zero = uavcas.load_dataset(ds)
    assert zero.X.attrs["nonfinite"] == {"policy": "zero", "values": bad_values, "rows": bad_rows, "rows_in": len(df)}
    assert np.isfinite(zero.X.to_numpy()).all() and len(zero.X) == len(df)
    nan = uavcas.load_dataset(ds, nonfinite="nan")
    assert nan.X.isna().to_numpy().sum() == bad_values and not np.isinf(nan.X.to_numpy()).any()
    drop = uavcas.load_dataset(ds, nonfinite="drop")
    assert len(drop.X) == len(drop.y) == len(drop.groups) == len(drop.meta) == len(df) - bad_rows
    assert np.isfinite(drop.X.to_numpy()).all() and drop.X.attrs["nonfinite"]["policy"] == "drop"
    assert (drop.y == drop.meta["label"]).all()
    with pytest.raises(ValueError, match="nonfinite"):
        uavcas.load_dataset(ds, nonfinite="mean")
