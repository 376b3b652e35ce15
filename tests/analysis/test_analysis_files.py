"""The files of `uavcas analyze`, written by the analysis modules themselves (`write_diversity`,
`write_axes`, `write_separability`): names, JSON layout, NaN kept."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from uavcas.analysis.axes import CONFOUND_TV, write_axes
from uavcas.analysis.diversity import DiversityOptions, DiversityResult, write_diversity
from uavcas.analysis.separability import separability_stats, write_separability

pytestmark = pytest.mark.slow  # a module fixture takes 25 s on 2 cores: the whole file is the full suite's


def test_diversity_files_hold_every_dataset(tmp_path):
    a = DiversityResult(pd.DataFrame({"dataset": ["a"], "class": ["DoS"], "hellinger": [0.5]}),
                        bins={"a": [0.0, 1.0]}, info={"a": {"n": 3}})
    b = DiversityResult(pd.DataFrame({"dataset": ["b"], "class": ["DoS"], "hellinger": [float("nan")]}),
                        bins={"b": [0.0, 2.0]}, info={"b": {"n": 4}})
    table = pd.concat([a.table, b.table], ignore_index=True)
    opt = DiversityOptions(n_boot=7, seed=5)
    paths = write_diversity(tmp_path, table, opt, [a, b])
    assert [p.name for p in paths] == ["diversity.csv", "diversity.json"]
    payload = json.loads((tmp_path / "diversity.json").read_text())
    assert list(payload) == ["options", "bins", "info", "table"]
    assert payload["options"]["n_boot"] == 7 and payload["options"]["seed"] == 5
    assert payload["bins"] == {"a": [0.0, 1.0], "b": [0.0, 2.0]} and payload["info"] == {"a": {"n": 3}, "b": {"n": 4}}
    assert payload["table"][0] == {"dataset": "a", "class": "DoS", "hellinger": 0.5}
    assert payload["table"][1]["hellinger"] is None  # pandas' records write NaN as null
    assert pd.read_csv(tmp_path / "diversity.csv")["dataset"].tolist() == ["a", "b"]


def test_axes_files(tmp_path):
    table = pd.DataFrame({"axis": ["speed"], "low": [1], "high": [9], "hellinger": [0.2]})
    write_axes(tmp_path, table, [0.0, 0.5, math.inf], "flow-mean")
    payload = json.loads((tmp_path / "axes.json").read_text())
    assert payload["iat_source"] == "flow-mean" and payload["confound_tv"] == CONFOUND_TV
    assert payload["bins"][-1] == math.inf and payload["table"] == [{"axis": "speed", "low": 1, "high": 9,
                                                                     "hellinger": 0.2}]
    assert pd.read_csv(tmp_path / "axes.csv").equals(table)


def test_separability_files(synth_df, tmp_path):
    df = synth_df.groupby("label").head(20)
    stats = separability_stats(df)
    emb = pd.DataFrame({"x": [0.0, 1.0], "y": [1.0, 0.0], "label": ["Benign", "DoS"]})
    paths = write_separability(tmp_path, df, stats, emb)
    assert [p.name for p in paths] == ["separability.csv", "tsne.csv", "tsne.png", "distributions.png"]
    assert pd.read_csv(tmp_path / "tsne.csv").equals(emb)
    assert len(pd.read_csv(tmp_path / "separability.csv")) == len(stats)
    assert all((tmp_path / n).read_bytes()[:4] == b"\x89PNG" for n in ("tsne.png", "distributions.png"))
