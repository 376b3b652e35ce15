"""The context-aware detector: gradient boosting over a flow's own features and its context.

`baseline("context")` is a `ContextClassifier`: LightGBM (early-stopped on the protocol's grouped
validation split, like the LightGBM baseline) with balanced class weights, trained on the 47 flow
features of the dataset's standard together with the `ctx_*` context columns
(`schema.CONTEXT_FEATURES`, computed at extraction from what the switches observed:
`uavcas.flows.context`). The ablation uses the same learner and settings on other inputs:

| name | `inputs` | columns it learns from |
|---|---|---|
| `context` | `both` | the flow features and the context columns |
| `context-flow` | `flow` | the flow features only (what the ten baselines see) |
| `context-only` | `context` | the context columns only |

Column selection is by name: given a DataFrame, `inputs` keeps the `ctx_*` columns (`context`),
the others (`flow`) or all (`both`); an array without column names is taken to hold exactly the
chosen inputs. The protocols give every context model the flow features and the context columns
as a named frame (`uavcas.ids.protocols`), so the three differ in their inputs only.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils.validation import check_is_fitted

from uavcas.schema import CONTEXT_PREFIX

from .classical import LightGBMClassifier

INPUTS = ("both", "flow", "context")
VARIANTS: dict[str, str] = {"context": "both", "context-flow": "flow", "context-only": "context"}


def select_columns(columns, inputs: str) -> list | None:
    """The column names `inputs` keeps of `columns` (None: no names, keep everything)."""
    if inputs not in INPUTS:
        raise ValueError(f"inputs must be one of {INPUTS}, got {inputs!r}")
    if columns is None:
        return None
    names = [c for c in columns if isinstance(c, str)]
    if len(names) != len(columns):  # integer or mixed column labels carry no names to select by
        return None
    keep = [c for c in names if inputs == "both" or (c.startswith(CONTEXT_PREFIX) == (inputs == "context"))]
    if not keep:
        raise ValueError(f"inputs={inputs!r}: X has no such column ({'ctx_*' if inputs == 'context' else 'non-ctx_*'})")
    return keep


def _take(X, cols: list | None):
    if cols is None or not isinstance(X, pd.DataFrame):
        return X
    missing = [c for c in cols if c not in X.columns]
    if missing:
        raise ValueError(f"X lacks the columns the model was fitted on: {missing[:5]}")
    return X.loc[:, cols]


class ContextClassifier(LightGBMClassifier):
    """LightGBM over the inputs `inputs` names (module docstring); `class_weight` 'balanced'
    weights each class by the inverse of its frequency (the stealth classes hold few flows)."""

    def __init__(
        self, inputs: str = "both", n_estimators: int = 400, learning_rate: float = 0.05, num_leaves: int = 31,
        min_child_samples: int = 20, colsample_bytree: float = 0.8, class_weight: str | None = "balanced",
        early_stopping_rounds: int = 30, validation_fraction: float = 0.0, random_state: int | None = 0,
        n_jobs: int | None = None,
    ) -> None:
        super().__init__(n_estimators=n_estimators, learning_rate=learning_rate, num_leaves=num_leaves,
                         early_stopping_rounds=early_stopping_rounds, validation_fraction=validation_fraction,
                         random_state=random_state, n_jobs=n_jobs)
        self.inputs = inputs
        self.min_child_samples = min_child_samples
        self.colsample_bytree = colsample_bytree
        self.class_weight = class_weight

    def fit(self, X, y, X_val=None, y_val=None):
        self.columns_ = select_columns(getattr(X, "columns", None), self.inputs)
        return super().fit(_take(X, self.columns_), y, X_val=None if X_val is None else _take(X_val, self.columns_),
                           y_val=y_val)

    def predict_proba(self, X) -> np.ndarray:
        check_is_fitted(self, "classes_")
        return super().predict_proba(_take(X, self.columns_))

    def _lgbm_params(self) -> dict:
        return dict(super()._lgbm_params(), min_child_samples=self.min_child_samples,
                    colsample_bytree=self.colsample_bytree, class_weight=self.class_weight)
