"""IDS benchmark: ten baselines as scikit-learn estimators (`baseline(name, **params)`), grouped
splits repeated over seeds, four protocols, a leaderboard."""

from .models import DISPLAY, MODELS, baseline

__all__ = ["DISPLAY", "MODELS", "baseline"]
