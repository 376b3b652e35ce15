"""No metadata column is ever a feature; splits are grouped by run, change with the seed, and
refuse to leave a declared class out of training or test."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from uavcas import schema
from uavcas.flows.standards import names, standards
from uavcas.flows.standards.cic import FEATURES
from uavcas.ids import protocols
from uavcas.ids.features import MetadataLeakError, check_feature_columns, feature_matrix, feature_sets, resolve_features
from uavcas.ids.protocols import BenchConfig, run_protocol
from uavcas.ids.splits import DegenerateSplitError, grouped_split, runs_per_class


@pytest.mark.parametrize("col",
                         schema.METADATA_COLUMNS + schema.SEQUENCE_COLUMNS + schema.COUNT_COLUMNS + ("config_idx",))
def test_metadata_is_refused(col):
    with pytest.raises(MetadataLeakError):
        check_feature_columns(list(FEATURES[:3]) + [col])


def test_feature_matrix_uses_exactly_the_47_features(synth_df):
    df = synth_df.copy()
    df["config_idx"] = np.arange(len(df))  # the authors' leak: must be ignored
    x = feature_matrix(df)
    assert x.shape == (len(df), 47) and np.isfinite(x).all()
    np.testing.assert_allclose(x[:, 0], df[FEATURES[0]].to_numpy(np.float32))


def test_feature_sets_come_from_the_standards_registry(synth_df):
    sets = feature_sets()
    assert {n: sets[n] for n in names()} == {s.name: s.columns for s in standards()}
    assert {n: sets[f"{schema.EPISODE_VIEW}-{n}"] for n in names()} == {s.name: s.episode_columns for s in standards()}
    assert len(sets) == 2 * len(names())
    name = next(n for n, cols in sets.items() if set(cols) <= set(synth_df.columns))
    assert resolve_features(synth_df, name) == list(sets[name])
    assert resolve_features(synth_df, ["Flow Duration", "SYN Flag Count"]) == ["Flow Duration", "SYN Flag Count"]
    with pytest.raises(ValueError, match="unknown feature set"):
        resolve_features(synth_df, "nope")
    with pytest.raises(MetadataLeakError):
        resolve_features(synth_df, ["Flow Duration", "run_id"])


def test_protocol_models_only_ever_see_features(synth_df, monkeypatch):
    seen = []
    real = protocols.fit_model

    def spy(est, x, y, xv=None, yv=None):
        seen.append(x.shape[1])
        return real(est, x, y, xv, yv)

    monkeypatch.setattr(protocols, "fit_model", spy)
    leaky = synth_df.assign(config_idx=np.arange(len(synth_df)), leak=(synth_df["label"] != "Benign").astype(float))
    for p in ("binary", "multiclass", "ood"):
        run_protocol(leaky, p, BenchConfig(models=("lr",), seeds=(0, 1), importance=False, n_threads=1))
    assert seen == [47] * 6


def _yg(df):
    return df["label"].to_numpy(), df["run_id"].to_numpy(), df["attacks"].to_numpy()


def test_grouped_split_no_run_in_two_splits_every_class_both_sides(synth_df):
    y, g, s = _yg(synth_df)
    sp = grouped_split(y, g, seed=0, strata=s)
    tr, va, te = set(g[sp.train]), set(g[sp.val]), set(g[sp.test])
    assert not (tr & va or tr & te or va & te)
    assert len(sp.train) + len(sp.val) + len(sp.test) == len(y)
    assert set(y[sp.train]) == set(y) == set(y[sp.test])
    assert (set(sp.groups["train"]), set(sp.groups["val"]), set(sp.groups["test"])) == (tr, va, te)
    # fractions of runs, per composition (10 runs each here): 2 of 10 to test, ~10 % to val
    assert len(te) == 2 * synth_df["attacks"].nunique() and abs(len(va) / len(set(g)) - 0.1) < 0.02
    assert grouped_split(y, g, seed=0, strata=s).test.tolist() == sp.test.tolist()  # seeded


@pytest.mark.slow  # 10 s on 2 cores
def test_seeds_change_the_partition_on_48_runs():
    from uavcas.dataset.synthetic import make_flows

    df = make_flows(48, flows_per_run=20, seed=0, sequences=False)
    y, g, s = _yg(df)
    tests = {grouped_split(y, g, seed=k, strata=s).groups["test"] for k in range(5)}
    assert len(tests) >= 4


def test_degenerate_split_names_the_class_and_its_runs(synth_df):
    # one run per composition, like the quick campaign: every attack class is in a single run
    first = synth_df.groupby("attacks")["run_id"].min()
    sub = synth_df[synth_df["run_id"].isin(first)]
    y, g, s = _yg(sub)
    with pytest.raises(DegenerateSplitError, match=r"DoS is in 1 run.*>= 2 runs"):
        grouped_split(y, g, seed=0, strata=s)
    # the same data is fine once only Benign is declared... but a missing declared class is named with 0 runs
    with pytest.raises(DegenerateSplitError, match="Nope is in 0 runs"):
        grouped_split(y, g, seed=0, declared=["Benign", "Nope"])


def test_classes_spanning_compositions_are_repaired_into_both_sides():
    # class X sits in runs of two different compositions (one run each): stratifying by
    # composition alone could put both in training; the split moves one to test
    runs = [f"r{i}" for i in range(8)]
    comp = ["a", "a", "a", "b", "b", "b", "c", "d"]
    labels = [["B"], ["B"], ["B"], ["B"], ["B"], ["B"], ["B", "X"], ["B", "X"]]
    rows = [(r, c, lab) for r, c, ls in zip(runs, comp, labels) for lab in ls for _ in range(3)]
    df = pd.DataFrame(rows, columns=["run_id", "attacks", "label"])
    for seed in range(10):
        sp = grouped_split(df["label"], df["run_id"], seed=seed, strata=df["attacks"])
        assert "X" in set(df["label"].to_numpy()[sp.train]) and "X" in set(df["label"].to_numpy()[sp.test])


def test_runs_per_class(synth_df):
    counts = runs_per_class(synth_df["label"], synth_df["run_id"])
    assert counts["Benign"] == synth_df["run_id"].nunique() and counts["Wormhole"] >= 10


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


def test_train_cap_per_run_and_class(synth_df):
    from uavcas.ids.splits import cap_rows

    y, g = synth_df["label"].to_numpy(), synth_df["run_id"].to_numpy()
    rows = np.arange(len(y))
    kept = cap_rows(rows, y, g, 3, seed=0)
    per = pd.DataFrame({"g": g[kept], "y": y[kept]}).value_counts()
    full = pd.DataFrame({"g": g, "y": y}).value_counts()
    assert per.max() == 3 and len(per) == len(full)  # every (run, class) kept, none above the cap
    assert (per == full.clip(upper=3).loc[per.index]).all()
    assert cap_rows(rows, y, g, 3, seed=0).tolist() == kept.tolist() != cap_rows(rows, y, g, 3, seed=1).tolist()
