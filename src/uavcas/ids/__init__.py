"""IDS benchmark: ten baselines and the context-aware detector (with its ablation) as scikit-learn
estimators (`baseline(name, **params)`), grouped splits repeated over seeds, four protocols, a
leaderboard."""

from .models import ALL_MODELS, CONTEXT_MODELS, DISPLAY, MODELS, baseline

__all__ = ["ALL_MODELS", "CONTEXT_MODELS", "DISPLAY", "MODELS", "baseline"]
