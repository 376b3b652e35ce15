"""The detector registry (`uavcas.ids.detectors`): one module per detector is the only list of
names; the CLI, the benchmark and the leaderboard read it; a new module is a new detector."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import uavcas
from uavcas.ids import baseline, baselines, detector, detectors, names
from uavcas.ids.detectors import DetectorSpec, register
from uavcas.ids.leaderboard import MODEL_ORDER

PAPER_TEN = ("lr", "sgd", "rf", "mlp", "lightgbm", "cnn1d", "lstm", "convnet", "tinyml", "cnn_bilstm")


def test_the_paper_baselines_in_the_paper_order_then_the_context_detectors():
    assert tuple(s.name for s in baselines()) == PAPER_TEN
    assert names() == PAPER_TEN + ("context", "context-joint", "context-flow", "context-only")
    assert MODEL_ORDER == [s.display for s in detectors()]
    assert len({s.display for s in detectors()}) == len(detectors())
    assert {s.name for s in detectors() if s.tree} == {"rf", "lightgbm", "context", "context-joint", "context-flow",
                                                        "context-only"}
    # one module per detector: the module a spec was registered from is named after it
    for s in detectors():
        assert s.factory.__module__ == f"uavcas.ids.detectors.{s.name.replace('-', '_')}"


def test_each_spec_describes_its_estimator():
    has_torch = importlib.util.find_spec("torch") is not None
    for s in detectors():
        if s.needs_torch and not has_torch:
            continue  # building a deep detector imports torch (the optional `dl` extra)
        params = baseline(s.name).get_params()
        for p in (s.seed_param, s.epoch_param, s.thread_param):
            assert p is None or p in params, (s.name, p)
        assert s.seed_param == "random_state" and ("device" in params) == s.needs_torch


def test_unknown_names_are_one_line_errors_listing_the_registered_ones():
    with pytest.raises(ValueError) as e:
        detector("knn")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("unknown detector 'knn'; known: ") and all(n in msg for n in names())
    with pytest.raises(ValueError, match="unknown detector"):
        baseline("xgboost")
    assert detector(" RF ") is detector("rf")


def test_register_refuses_a_second_name_or_display_and_bad_specs():
    def factory():
        raise AssertionError("never built")

    with pytest.raises(ValueError, match="registered twice"):
        register(DetectorSpec(name="rf", display="Other", kind="classical", factory=factory))
    with pytest.raises(ValueError, match="display name 'RF'"):
        register(DetectorSpec(name="rf2", display="RF", kind="classical", factory=factory))
    with pytest.raises(ValueError, match="kind"):
        DetectorSpec(name="x", display="X", kind="quantum", factory=factory)
    with pytest.raises(ValueError, match="lower-case"):
        DetectorSpec(name="Bad Name", display="X", kind="classical", factory=factory)
    assert "rf2" not in names()


def _src_env(pythonpath: Path) -> dict[str, str]:
    # COLUMNS: rich wraps the help to the terminal's width; wide enough that no name is cut
    return {**os.environ, "PYTHONPATH": str(pythonpath), "COLUMNS": "250", "NO_COLOR": "1"}


def _imported(statement: str) -> str:
    """Which estimator libraries a fresh interpreter holds after `statement`."""
    code = f"import sys; {statement}; print(sorted(m for m in ('torch', 'sklearn', 'lightgbm') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env=_src_env(Path(uavcas.__file__).parents[1]))
    return out.stdout.strip() + out.stderr


def test_importing_the_registry_imports_no_torch():
    # the classical detectors import their libraries at module level; torch (the `dl` extra) waits
    # for a deep detector to be built
    assert "torch" not in _imported("import uavcas.ids.detectors")


def test_importing_the_cli_imports_no_estimator_library():
    # the root command loads a command's module only when that command runs or shows its help
    assert _imported("import uavcas.cli") == "[]"


ARCHITECTURE = Path(__file__).parents[2] / "docs" / "architecture.md"


def _worked_example() -> str:
    """The module of docs/architecture.md's "a detector" example (the test runs what the docs show)."""
    text = ARCHITECTURE.read_text()
    section = text[text.index("### a detector"):]
    start = section.index("```python\n") + len("```python\n")
    return section[start:section.index("```\n", start)]


@pytest.mark.slow
def test_a_new_detector_is_one_new_module(tmp_path):
    """A copy of the package with one module added to `uavcas/ids/detectors/` (the docs' worked
    example): the registry, the CLI's help and `bench ids` (40 synthetic runs: 3 hold DoS, enough
    for a grouped split) all have the new detector; nothing else was edited."""
    shutil.copytree(Path(uavcas.__file__).parent, tmp_path / "uavcas", ignore=shutil.ignore_patterns("__pycache__"))
    example = _worked_example()
    assert 'name="knn"' in example
    (tmp_path / "uavcas" / "ids" / "detectors" / "knn.py").write_text(example)
    env = _src_env(tmp_path)

    def run(*args: str) -> str:
        p = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=tmp_path)
        assert p.returncode == 0, p.stdout + p.stderr
        return p.stdout

    where, listed = run("-c", "import uavcas.ids as i; print(i.__file__); print(','.join(i.names()))").split()
    assert Path(where).is_relative_to(tmp_path)
    assert listed.split(",")[-1] == "knn" and "knn" not in {s.name for s in baselines()}
    helptext = run("-m", "uavcas", "bench", "ids", "--help")
    assert "knn" in helptext and "context-only" in helptext
    run("-m", "uavcas", "dataset", "synth", "--out", str(tmp_path / "ds"), "--runs", "40", "--flows-per-run", "100")
    run("-m", "uavcas", "bench", "ids", str(tmp_path / "ds"), "--protocol", "binary", "--seeds", "0",
        "--models", "knn,lr", "--threads", "1", "--out", str(tmp_path / "out"))
    res = pd.read_csv(tmp_path / "out" / "results.csv", keep_default_na=False)
    assert set(res["model"]) == {"KNN", "LR"}
    f1 = res[(res["model"] == "KNN") & (res["metric"] == "f1_weighted") & (res["class"] == "")]["value"]
    assert len(f1) == 1 and 0.5 < float(f1.iloc[0]) <= 1.0  # DoS floods are separable in the synthetic data
    assert "| KNN |" in (tmp_path / "out" / "leaderboard.md").read_text()
    # unknown names are refused in one line that lists the new one too
    p = subprocess.run([sys.executable, "-m", "uavcas", "bench", "ids", str(tmp_path / "ds"), "--models", "svm",
                        "--out", str(tmp_path / "bad")], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert p.returncode != 0 and "knn" in p.stdout + p.stderr
