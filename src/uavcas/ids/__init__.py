"""IDS benchmark: the registered detectors (`uavcas.ids.detectors`: the paper's ten baselines, the
context-aware detector and its ablation) as scikit-learn estimators (`baseline(name, **params)`),
grouped splits repeated over seeds, four protocols, a leaderboard."""

from .detectors import DetectorSpec, baseline, baselines, detector, detectors, names

__all__ = ["DetectorSpec", "baseline", "baselines", "detector", "detectors", "names"]
