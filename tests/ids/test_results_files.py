"""`uavcas.ids.results`: the leaderboard files, and the results of several `bench ids` outputs read
back for one leaderboard (what `uavcas bench leaderboard` calls)."""

from __future__ import annotations

import pandas as pd
import pytest

from uavcas.ids.leaderboard import COLUMNS
from uavcas.ids.results import RESULT_COLUMNS, ResultsError, collect_results, write_leaderboard


def _results(protocol: str, seeds=(0, 1)) -> pd.DataFrame:
    rows = [(protocol, s, "Random Forest", "f1_macro", "", 0.5 + 0.1 * s) for s in seeds]
    rows += [(protocol, s, "Random Forest", "f1", "Benign", 0.9) for s in seeds]
    return pd.DataFrame(rows, columns=list(RESULT_COLUMNS))


def _output(root, protocol: str) -> None:
    root.mkdir(parents=True)
    _results(protocol).to_csv(root / "results.csv", index=False)


def test_results_of_several_outputs_are_read_into_one_frame(tmp_path):
    _output(tmp_path / "a" / "binary", "binary")
    _output(tmp_path / "a" / "multiclass", "multiclass")
    _output(tmp_path / "b", "ood")
    allr, files = collect_results([tmp_path / "a", tmp_path / "b" / "results.csv"])
    assert files == [tmp_path / "a" / "binary" / "results.csv", tmp_path / "a" / "multiclass" / "results.csv",
                     tmp_path / "b" / "results.csv"]
    assert list(allr.columns) == list(RESULT_COLUMNS) and len(allr) == 12
    assert set(allr.loc[allr.metric == "f1_macro", "class"]) == {""}  # overall metrics: class "", not NaN
    write_leaderboard(tmp_path / "lb", allr, [f"from {f}" for f in files])
    lb = pd.read_csv(tmp_path / "lb" / "leaderboard.csv", keep_default_na=False)
    assert list(lb.columns) == list(COLUMNS) and set(lb.protocol) == {"binary", "multiclass", "ood"}
    macro = lb[(lb.protocol == "binary") & (lb.metric == "f1_macro")]
    assert float(macro["mean"].iloc[0]) == pytest.approx(0.55)
    assert "from " + str(files[0]) in (tmp_path / "lb" / "leaderboard.md").read_text()


def test_a_directory_without_results_a_foreign_csv_and_a_protocol_twice_are_refused(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(ResultsError, match=r"empty: no results.csv \(expected a `bench ids` output directory\)"):
        collect_results([tmp_path / "empty"])
    (tmp_path / "foreign").mkdir()
    pd.DataFrame({"x": [1]}).to_csv(tmp_path / "foreign" / "results.csv", index=False)
    with pytest.raises(ResultsError, match=r"not a `bench ids` results.csv \(columns \['x'\]\)"):
        collect_results([tmp_path / "foreign"])
    _output(tmp_path / "one", "binary")
    _output(tmp_path / "two", "binary")
    with pytest.raises(ResultsError, match="protocol 'binary' appears in more than one results.csv"):
        collect_results([tmp_path / "one", tmp_path / "two"])
