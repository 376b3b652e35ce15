"""IDS benchmark: ten baselines as scikit-learn estimators, grouped splits, four protocols."""
