"""The context-aware detector: gradient boosting over a flow's own features and its context.

`baseline("context")` is a `ContextClassifier`: LightGBM (early-stopped on the protocol's grouped
validation split, like the LightGBM baseline) with class weights (below), on the 47 flow features
of the dataset's standard together with the `ctx_*` context columns (`schema.CONTEXT_FEATURES`,
computed at extraction from what the switches observed: `uavcas.flows.context`).

It learns in two stages (`residual`): a flow model first, then context trees boosted from the flow
model's raw scores, so that the context only corrects what the flow features get wrong. Learnt
jointly, the context columns that describe the scenario (a swarm partition that drops a flood
before it leaves the attacker's switch, a base station's share of the traffic) split a class
from the others as well as the flow features do on the training runs, and the model takes
whichever comes first; on runs of other scenarios that choice fails (on a 21-run subset of the
medium campaign, with one DoS run to train on: binary weighted F1 0.66 jointly, 0.999 for the
flow model and the two stages). The context
stage starts from out-of-fold flow scores on its training rows (in-sample ones are nearly
perfect and would leave it nothing to learn) and stops on the validation split like the first.
`reg_lambda` (L2 on leaf values) keeps a leaf of rows the flow model already scores with
confidence (tiny gradients and hessians) from taking a huge Newton step: without it two context
trees flipped every DoS flow of an unseen run to Benign on that subset.

The context stage's correction is bounded (`context_bound`, 3 in log-odds by default): it may move
each class's raw score by at most that much. Trees extrapolate their leaf values without limit
where a run's context columns lie outside the training runs', and in the 5-tuple view's binary
protocol the context stage turned the confident, right flow scores of every DoS flow of one unseen
run (`dos=1000+replay`, 43,252 flows, flow log-odds +4.8 on average, context -10.5) into Benign on
two of five seeds (weighted F1 0.93 and 0.94; 0.9998 for the flow model alone). Bounded at 3, the
context still decides where the flow model is unsure, which is where the stealth classes are
(their flows look like Benign ones, so the flow scores of the two sit close), and cannot
overturn a flow decision held at more than 3: binary weighted F1 0.9725 -> 0.9968 over the five
seeds (balanced weights; 0.9973 with the square-root weights below), stealth macro-F1 within
0.01 of unbounded on every seed of both views' multiclass protocol (docs/measurements.md, stop 27).

Class weights (`class_weight`) are the inverse square root of each class's frequency ('sqrt'),
not its inverse ('balanced'). The benchmark scores macro-F1, and a class's F1 is best at a
posterior threshold of about half the F1 it can reach (Lipton, Elkan and Naryanaswamy, "Optimal
thresholding of classifiers to maximize F1 measure", ECML PKDD 2014), not where 'balanced' puts
it: in the window-host view Wormhole holds 1.3 % of the rows and 'balanced' weighs it about 50
times a Benign row, so Benign episodes the context cannot tell apart from a detour were called
Wormhole (256 of the 5 seeds' predictions against 39 right: F1 0.14). The square root weighs it
about 7 times, nearer that threshold for the weak classes while the rare classes still count.
It does not make Wormhole easy (F1 0.18 over five seeds in that view). The episode route
columns that a detour moves (`flows.routes`: lonely route changes, path and delay shifts and
switches that send their own and passing traffic to one destination different ways, each also
as the largest over a node's peers) reach AUROC 0.80 against Benign episodes at best, and a
fifth of the Benign episodes carry some such evidence (a swarm re-plans its routes every window);
with them this detector's Wormhole F1 stays near 0.17 and the one-stage `context-joint` reaches
about 0.29 (docs/measurements.md, stop 28). Stop 30's columns (a detour's packets both on a lonely
route and off the way their switches send other traffic, toward any base station) raised it to
0.372 on the same 63 runs that gave 0.265 before them, and to 0.457 over five seeds of the
regenerated 100-run campaign.

The ablation uses the same learner and settings on other inputs (each variant is a detector
module of its own, `uavcas.ids.detectors.context*`):

| name | `inputs` | columns it learns from |
|---|---|---|
| `context` | `both` | the flow features, then the context columns on top (two stages) |
| `context-joint` | `both` | the flow features and the context columns in one model (`residual=False`) |
| `context-flow` | `flow` | the flow features only (what the ten baselines see) |
| `context-only` | `context` | the context columns only |

Column selection is by name: given a DataFrame, `inputs` keeps the `ctx_*` columns (`context`),
the others (`flow`) or all (`both`); an array without column names is taken to hold exactly the
chosen inputs (and, with no names to tell flow from context, is learnt in one stage). The
protocols give every context model the flow features and the context columns as a named frame
(`uavcas.ids.protocols`), so the variants differ in their inputs and stages only.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.special import expit, softmax
from sklearn.utils.validation import check_is_fitted

from uavcas.schema import CONTEXT_PREFIX

from .classical import LightGBMClassifier

INPUTS = ("both", "flow", "context")
CLASS_WEIGHTS = ("balanced", "sqrt")


def class_weights(yi: np.ndarray, kind: str | None) -> dict[int, float] | None:
    """Weight per integer class of `yi`: 'balanced' n_c ** -1, 'sqrt' n_c ** -0.5, scaled so the
    rows' weights sum to their number (None: every row weighs 1)."""
    if kind is None:
        return None
    if kind not in CLASS_WEIGHTS:
        raise ValueError(f"class_weight must be one of {CLASS_WEIGHTS} or None, got {kind!r}")
    classes, counts = np.unique(yi, return_counts=True)
    power = 1.0 if kind == "balanced" else 0.5
    w = counts.astype(np.float64) ** -power
    w *= len(yi) / float(np.sum(w * counts))
    return {int(c): float(v) for c, v in zip(classes, w)}


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
    """LightGBM over the inputs `inputs` names (module docstring); `class_weight` 'sqrt' weights
    each class by the inverse square root of its frequency, 'balanced' by its inverse (module
    docstring), a dict by class label, None not at all.
    `residual` (inputs 'both', named columns): boost the context on top of the flow model
    (module docstring), its training scores out of `residual_folds` folds; the context stage moves
    each raw score by at most `context_bound` (None: unbounded)."""

    def __init__(
        self, inputs: str = "both", n_estimators: int = 400, learning_rate: float = 0.05, num_leaves: int = 31,
        min_child_samples: int = 20, colsample_bytree: float = 0.8, reg_lambda: float = 1.0,
        class_weight: str | dict | None = "sqrt",
        early_stopping_rounds: int = 30, validation_fraction: float = 0.0, residual: bool = True,
        residual_folds: int = 3, context_bound: float | None = 3.0, random_state: int | None = 0,
        n_jobs: int | None = None,
    ) -> None:
        super().__init__(n_estimators=n_estimators, learning_rate=learning_rate, num_leaves=num_leaves,
                         early_stopping_rounds=early_stopping_rounds, validation_fraction=validation_fraction,
                         random_state=random_state, n_jobs=n_jobs)
        self.inputs = inputs
        self.min_child_samples = min_child_samples
        self.colsample_bytree = colsample_bytree
        self.reg_lambda = reg_lambda
        self.class_weight = class_weight
        self.residual = residual
        self.residual_folds = residual_folds
        self.context_bound = context_bound

    def fit(self, X, y, X_val=None, y_val=None):
        self.columns_ = select_columns(getattr(X, "columns", None), self.inputs)
        # positions of the flow columns among the inputs: the first stage's (None: one stage)
        self.flow_index_ = None
        if self.residual and self.inputs == "both" and self.columns_ is not None:
            flow = [i for i, c in enumerate(self.columns_) if not c.startswith(CONTEXT_PREFIX)]
            if 0 < len(flow) < len(self.columns_):
                self.flow_index_ = np.array(flow)
        return super().fit(_take(X, self.columns_), y, X_val=None if X_val is None else _take(X_val, self.columns_),
                           y_val=y_val)

    def predict_proba(self, X) -> np.ndarray:
        check_is_fitted(self, "classes_")
        return super().predict_proba(_take(X, self.columns_))

    def _fit_core(self, X, yi, X_val, yv, rng) -> None:
        self.flow_model_ = None
        cw = self.class_weight
        if isinstance(cw, dict):  # by class label (scikit-learn's convention); LightGBM sees codes
            self.class_weight_ = {i: float(cw.get(c, 1.0)) for i, c in enumerate(self.classes_)}
        else:  # 'balanced' goes to LightGBM as is (its own weights; the validation split's by its counts)
            self.class_weight_ = cw if cw in (None, "balanced") else class_weights(yi, cw)
        if self.flow_index_ is None:
            return super()._fit_core(X, yi, X_val, yv, rng)
        f = self.flow_index_
        fv = None if X_val is None else X_val[:, f]
        flow = self._boost(X[:, f], yi, fv, yv)
        init = self._out_of_fold(X[:, f], yi, fv, yv, flow, rng)
        model = self._boost(X, yi, X_val, yv, init_score=init,
                            val_init_score=None if fv is None else flow.predict(fv, raw_score=True))
        self.flow_model_, self.model_ = flow, model
        self.n_iter_ = (int(flow.best_iteration_ or flow.n_estimators_)
                        + int(model.best_iteration_ or model.n_estimators_))
        imp = model.feature_importances_.astype(np.float64)
        imp[f] += flow.feature_importances_
        self.feature_importances_ = imp

    def _out_of_fold(self, Xf, yi, fv, yv, flow, rng) -> np.ndarray:
        """The flow model's raw scores on its training rows, each from a model that did not see
        it (a class with fewer rows than folds is in every fold's training: `flow`'s scores);
        in-sample scores would leave the context stage nothing to correct."""
        raw = flow.predict(Xf, raw_score=True)
        k = self.residual_folds
        if k < 2:
            return raw
        fold = np.full(len(yi), -1)
        for c in np.unique(yi):
            rows = np.flatnonzero(yi == c)
            if len(rows) >= k:
                fold[rng.permutation(rows)] = np.arange(len(rows)) % k
        for j in range(k):
            out = fold == j
            if out.any():
                raw[out] = self._boost(Xf[~out], yi[~out], fv, yv).predict(Xf[out], raw_score=True)
        return raw

    def _proba_core(self, X) -> np.ndarray:
        if self.flow_model_ is None:
            return super()._proba_core(X)
        correction = self.model_.predict(X, raw_score=True)
        if self.context_bound is not None:
            correction = np.clip(correction, -self.context_bound, self.context_bound)
        z = self.flow_model_.predict(X[:, self.flow_index_], raw_score=True) + correction
        if z.ndim == 1:
            p = expit(z)
            return np.stack([1 - p, p], axis=1)
        return softmax(z, axis=1)

    def _lgbm_params(self) -> dict:
        return dict(super()._lgbm_params(), min_child_samples=self.min_child_samples,
                    colsample_bytree=self.colsample_bytree, reg_lambda=self.reg_lambda,
                    class_weight=self.class_weight_)
