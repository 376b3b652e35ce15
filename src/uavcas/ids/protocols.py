"""The four evaluation protocols, each repeated over seeds (a new grouped split and model seed
each time). A protocol is a `Task` built once from the flow table (targets, declared classes, the
rows split by run, extra test sets) and a scoring rule; `run_protocol` splits, fits every model
and scores it per seed, and returns long-format scores (protocol, seed, model, metric, class,
value; class "" for overall metrics), confusion counts, the splits, fit times and, for the tree
models, permutation importances.

- binary: Benign vs DoS (DoS classes of other datasets: 'DoS ...'), declared {Benign, DoS}.
- multiclass: every class of the dataset (15 on a full uavcas dataset).
- ood: attack-vs-benign trained on single-attack configurations; AUROC and PR-AUC per
  collaborative composition (all its flows + the benign test flows of the seed's split).
- cross-condition: every flow with AXIS=VALUE held out and tested on; multiclass on the rest,
  whose own grouped test split is scored too (metrics suffixed `_iid`).
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from sklearn.inspection import permutation_importance
from sklearn.metrics import f1_score
from sklearn.preprocessing import MinMaxScaler, RobustScaler, StandardScaler
from threadpoolctl import threadpool_limits

from uavcas import schema, seeding
from uavcas.vocabulary import families_of

from .base import fit_model
from .detectors import baselines, detector, make_model
from .features import context_columns, context_matrix, feature_matrix, resolve_features
from .metrics import STEALTH, auroc, class_scores, confusion, pr_auc, scores
from .prior import prior_ratio, reweight
from .splits import DegenerateSplitError, Split, cap_rows, check_declared, grouped_split, runs_per_class
from .torch_estimator import default_threads

PROTOCOLS = ("binary", "multiclass", "ood", "cross-condition")
SCALERS = {"standard": StandardScaler, "minmax": MinMaxScaler, "robust": RobustScaler}
DEFAULT_SEEDS = (0, 1, 2, 3, 4)
ATTACK = "Attack"
DOS = "DoS"
PRIOR_NOTE = ("--train-cap: scores at the uncapped training split's class prior (each model's posteriors "
              "reweighted by Bayes' rule, `uavcas.ids.prior`)")
_DOS = re.compile(r"^dos($|[ _\-])", re.IGNORECASE)  # DoS, 'DoS Hulk', 'DoS-UDP_Flood'; not 'DoS+Replay'


@dataclass
class BenchConfig:
    models: tuple[str, ...] = field(default_factory=lambda: tuple(s.name for s in baselines()))  # detector names
    scaler: str = "standard"
    epochs: int = 50
    seeds: tuple[int, ...] = DEFAULT_SEEDS
    holdout: tuple[tuple[str, str], ...] = ()
    features: str | tuple[str, ...] | None = None  # a feature-set name or columns; None: all schema features
    importance: bool = True
    importance_rows: int = 2000  # test flows permuted (a seeded subsample when there are more)
    importance_repeats: int = 5
    train_cap: int | None = None  # at most this many training/validation flows per run and class
    # classes held by fewer runs are left out (their flows dropped, named in the notes); 0: such a
    # class makes the split degenerate and is refused
    min_class_runs: int = 0
    n_threads: int | None = None
    device: str = "auto"  # the torch models' (TorchClassifier.device): auto = CUDA when torch sees a GPU
    progress: Callable[[str], None] | None = None  # told "<seed> <model>: <seconds>" after each fit


@dataclass(frozen=True)
class Score:
    protocol: str
    seed: int
    model: str
    metric: str
    cls: str
    value: float


@dataclass(frozen=True)
class SplitRow:
    seed: int
    run_id: str
    split: str


@dataclass(frozen=True)
class Fit:
    seed: int
    model: str
    seconds: float
    epochs: int | None
    device: str = "cpu"  # where the model trained (a torch model's resolved device, else the CPU)


@dataclass(frozen=True)
class Importance:
    seed: int
    model: str
    feature: str
    mean: float
    std: float


@dataclass
class ProtocolResult:
    protocol: str
    declared: list[str]
    features: list[str]
    scores: list[Score] = field(default_factory=list)
    confusion: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)  # (seed, model) -> counts
    splits: list[SplitRow] = field(default_factory=list)
    sizes: dict[int, dict[str, int]] = field(default_factory=dict)  # seed -> flows per part
    fits: list[Fit] = field(default_factory=list)
    importance: list[Importance] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def add(self, seed: int, model: str, rows) -> None:
        self.scores += [Score(self.protocol, seed, model, m, c, float(v)) for m, c, v in rows]


Predict = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # rows -> (proba, model classes)


@dataclass
class Task:
    """What a protocol fits and scores. `pool` rows are split by run each seed; `score` turns a
    fitted model's predictions into rows and returns them with the main test rows and their
    predicted classes (for the confusion matrix and the permutation importance)."""

    x: np.ndarray
    y: np.ndarray
    groups: np.ndarray
    strata: np.ndarray | None
    pool: np.ndarray
    declared: list[str]
    score: Callable[["Task", Split, Predict], tuple[list, np.ndarray, np.ndarray]]
    fixed: dict[str, np.ndarray] = field(default_factory=dict)  # label of extra test runs -> rows
    x_ctx: np.ndarray | None = None  # the context columns (`features.context_columns`), for the context models
    ctx_names: tuple[str, ...] = ()  # their names: flows' ctx_*, or the episode summaries of them
    natural_prior: bool = False  # scored at the uncapped training prior (`ids.prior`) under --train-cap

    def split(self, seed: int) -> Split:
        p = self.pool
        sp = grouped_split(self.y[p], self.groups[p], seed=seed, declared=self.declared,
                           strata=None if self.strata is None else self.strata[p])
        return Split(p[sp.train], p[sp.val], p[sp.test], sp.groups)


def is_dos(label: str) -> bool:
    return bool(_DOS.match(str(label)))


def class_order(labels) -> list[str]:
    present = set(map(str, labels))
    return [c for c in schema.CLASSES if c in present] + sorted(present - set(schema.CLASSES))


def _groups(df: pd.DataFrame, notes: list[str]) -> np.ndarray:
    if "run_id" in df.columns:
        return df["run_id"].astype(str).to_numpy()
    notes.append("no run_id column: every flow is its own group (flow-level stratified split)")
    return np.arange(len(df)).astype(str)


def _strata(df: pd.DataFrame) -> np.ndarray | None:
    # a run's composition: runs of one composition are dealt evenly between the splits
    return df["attacks"].astype(str).to_numpy() if "attacks" in df.columns else None


def _classify(task: Task, sp: Split, predict: Predict, positive: str | None = None):
    proba, classes = predict(sp.test)
    return scores(task.y[sp.test], proba, classes, task.declared, positive), sp.test, classes[proba.argmax(1)]


def _score_binary(task, sp, predict):
    return _classify(task, sp, predict, positive=DOS)


def _score_multiclass(task, sp, predict):
    return _classify(task, sp, predict)


def _score_ood(task, sp, predict):
    rows, main, pred = _classify(task, sp, predict, positive=ATTACK)
    test_benign = sp.test[task.y[sp.test] == schema.BENIGN]
    for comp, comp_rows in task.fixed.items():
        e = np.concatenate([comp_rows, test_benign])
        proba, classes = predict(e)
        score = class_scores(proba, classes, ATTACK)
        y_pos = task.y[e] == ATTACK
        rows += [("auroc", comp, auroc(y_pos, score)), ("pr_auc", comp, pr_auc(y_pos, score))]
    return rows, main, pred


def _score_cross(task, sp, predict):
    held = task.fixed["heldout"]
    proba, classes = predict(held)
    rows, pred = scores(task.y[held], proba, classes, task.declared), classes[proba.argmax(1)]
    if len(sp.test):
        proba, classes = predict(sp.test)
        rows += [(f"{m}_iid", c, v) for m, c, v in scores(task.y[sp.test], proba, classes, task.declared)
                 if c in ("", STEALTH)]
    return rows, held, pred


def prepare_binary(df: pd.DataFrame, x: np.ndarray, notes: list[str], cfg: BenchConfig) -> Task:
    keep = ((df["label"] == schema.BENIGN) | df["label"].map(is_dos)).to_numpy()
    y = np.where(df["label"] == schema.BENIGN, schema.BENIGN, DOS).astype(object)
    if not (keep & (y == DOS)).any() or not (keep & (y == schema.BENIGN)).any():
        raise ValueError("binary protocol needs Benign and DoS flows")
    return Task(x, y, _groups(df, notes), _strata(df), np.flatnonzero(keep), [schema.BENIGN, DOS], _score_binary,
                natural_prior=True)


def prepare_multiclass(df: pd.DataFrame, x: np.ndarray, notes: list[str], cfg: BenchConfig) -> Task:
    y = df["label"].astype(str).to_numpy()
    return Task(x, y, _groups(df, notes), _strata(df), np.arange(len(df)), class_order(y), _score_multiclass)


def prepare_ood(df: pd.DataFrame, x: np.ndarray, notes: list[str], cfg: BenchConfig) -> Task:
    if "attacks" not in df.columns:
        raise ValueError("ood protocol needs the 'attacks' axis column (a uavcas dataset)")
    comp = df["attacks"].map(families_of)
    single = (comp.map(len) <= 1).to_numpy()
    if single.all() or not single.any():
        raise ValueError("ood protocol needs both single-attack and collaborative configurations")
    y = np.where(df["label"] == schema.BENIGN, schema.BENIGN, ATTACK).astype(object)
    names = comp.map(schema.class_name).to_numpy()
    fixed = {c: np.flatnonzero(~single & (names == c)) for c in class_order(names[~single])}
    return Task(x, y, _groups(df, notes), _strata(df), np.flatnonzero(single), [schema.BENIGN, ATTACK],
                _score_ood, fixed, natural_prior=True)


def prepare_cross(df: pd.DataFrame, x: np.ndarray, notes: list[str], cfg: BenchConfig) -> Task:
    if not cfg.holdout:
        raise ValueError("cross-condition needs --holdout AXIS=VALUE (e.g. mission=random)")
    held = np.zeros(len(df), dtype=bool)
    for axis, value in cfg.holdout:
        if axis not in schema.AXIS_COLUMNS or axis not in df.columns:
            raise ValueError(f"--holdout: {axis!r} is not an axis column of this dataset "
                             f"({', '.join(schema.AXIS_COLUMNS)})")
        m = (df[axis].astype(str) == str(value)).to_numpy()
        if not m.any():
            raise ValueError(f"--holdout: no flow has {axis}={value} (values: {sorted(df[axis].astype(str).unique())})")
        held |= m
    if held.all():
        raise ValueError("--holdout leaves no flow to train on")
    where = " (held out: " + ", ".join(f"{a}={v}" for a, v in cfg.holdout) + ")"
    notes.append("held out: " + ", ".join(f"{a}={v}" for a, v in cfg.holdout))
    y = df["label"].astype(str).to_numpy()
    declared = class_order(y)
    missing = [c for c in declared if not (held & (y == c)).any()]
    if missing:
        raise DegenerateSplitError(f"degenerate split{where}: no held-out flow of {', '.join(missing)}")
    groups = _groups(df, notes)
    check_declared(y[~held], groups[~held], declared, where=" of the seen conditions")
    return Task(x, y, groups, _strata(df), np.flatnonzero(~held), declared, _score_cross,
                {"heldout": np.flatnonzero(held)})


PREPARE = {"binary": prepare_binary, "multiclass": prepare_multiclass, "ood": prepare_ood,
           "cross-condition": prepare_cross}


def _split_rows(task: Task, seed: int, sp: Split) -> list[SplitRow]:
    out = [SplitRow(seed, g, part) for part, gs in sp.groups.items() for g in gs]
    for name, rows in task.fixed.items():
        out += [SplitRow(seed, g, "heldout" if name == "heldout" else "ood-test")
                for g in sorted(set(task.groups[rows]))]
    return out


def _inputs(task: Task, name: str, features: list[str]) -> tuple[np.ndarray, list[str] | None]:
    """A model's matrix and, for the context models (which select their inputs by name), its
    column names: the flow features followed by the context columns."""
    if not detector(name).uses_context:
        return task.x, None
    return np.hstack([task.x, task.x_ctx]), features + list(task.ctx_names)


def _fit_one(res: ProtocolResult, task: Task, sp: Split, name: str, seed: int, cfg: BenchConfig,
             prior_from: np.ndarray | None = None) -> None:
    """Fit one model on `sp.train` and score it; with `prior_from` (the uncapped training rows),
    its posteriors are moved to their class prior before scoring (`ids.prior`)."""
    t0 = time.perf_counter()
    x, names = _inputs(task, name, res.features)
    scaler = SCALERS[cfg.scaler]().fit(x[sp.train])

    def tf(rows):
        z = np.clip(scaler.transform(x[rows]), -1e6, 1e6).astype(np.float32)
        return z if names is None else pd.DataFrame(z, columns=names)
    spec = detector(name)
    est = make_model(name, random_state=seed, epochs=cfg.epochs, n_threads=cfg.n_threads, device=cfg.device)
    model = spec.display
    # why: BLAS/OpenMP pools default to all cores and busy-wait; on a shared 2-core machine
    # oversubscription makes a 1-second fit take 10
    with threadpool_limits(limits=cfg.n_threads or default_threads()):
        fit_model(est, tf(sp.train), task.y[sp.train], tf(sp.val) if len(sp.val) else None,
                  task.y[sp.val] if len(sp.val) else None)
        ratio = None if prior_from is None else prior_ratio(task.y[prior_from], task.y[sp.train], est.classes_)

        def predict(r):
            proba = est.predict_proba(tf(r))
            return (proba if ratio is None else reweight(proba, ratio)), est.classes_
        rows, main, pred = task.score(task, sp, predict)
        seconds = time.perf_counter() - t0
        res.add(seed, model, rows)
        res.confusion[(seed, model)] = confusion(task.y[main], pred, task.declared)
        if cfg.importance and spec.tree:
            res.importance += _importance(est, tf, task, main, seed, model, cfg, names or res.features)
    epochs = getattr(est, "n_iter_", None) if spec.epoch_param else None
    res.fits.append(Fit(seed, model, seconds, None if epochs is None else int(epochs), getattr(est, "device_", "cpu")))
    res.add(seed, model, [("fit_s", "", seconds)] + ([("epochs", "", epochs)] if epochs is not None else []))
    if cfg.progress:
        cfg.progress(f"seed {seed} {model}: {seconds:.1f} s" + (f", {epochs} epochs" if epochs is not None else ""))


def _importance(est, tf, task: Task, rows: np.ndarray, seed: int, model: str, cfg: BenchConfig,
                features: list[str]) -> list[Importance]:
    """Drop in macro-F1 (declared classes) when one feature's test values are shuffled."""
    if len(rows) > cfg.importance_rows:
        rows = np.sort(seeding.generator(seed).choice(rows, cfg.importance_rows, replace=False))
    def scorer(model, x, y) -> float:  # a plain callable: make_scorer assumes pos_label=1 for two classes
        return f1_score(y, model.predict(x), average="macro", labels=task.declared, zero_division=0)

    r = permutation_importance(est, tf(rows), task.y[rows], scoring=scorer, n_repeats=cfg.importance_repeats,
                               random_state=seed, n_jobs=1)
    return [Importance(seed, model, f, float(m), float(s))
            for f, m, s in zip(features, r.importances_mean, r.importances_std)]


@dataclass
class Prepared:
    """A protocol ready to run: its task and every seed's split, all accepted."""

    protocol: str
    task: Task
    splits: dict[int, Split]
    features: list[str]
    notes: list[str]


def _drop_rare_classes(df: pd.DataFrame, min_runs: int, notes: list[str]) -> pd.DataFrame:
    """The rows of the classes held by at least `min_runs` runs (all rows when 0)."""
    if min_runs <= 0:
        return df
    groups = _groups(df, [])
    per_class = runs_per_class(df["label"].astype(str).to_numpy(), groups)
    rare = sorted(c for c, n in per_class.items() if n < min_runs)
    if not rare:
        return df
    label = df["label"].astype(str)
    def plural(n: int, word: str) -> str:
        return f"{n} {word}{'' if n == 1 else 's'}"

    listed = ", ".join(f"{c} ({plural(int(per_class[c]), 'run')}, {plural(int((label == c).sum()), 'flow')})"
                       for c in rare)
    notes.append(f"left out, held by fewer than {min_runs} runs (--min-class-runs): {listed}")
    return df[~label.isin(rare).to_numpy()]


def prepare(df: pd.DataFrame, protocol: str, cfg: BenchConfig) -> Prepared:
    """Build the task and every seed's split; raises (ValueError, DegenerateSplitError) before
    anything is fitted."""
    if protocol not in PREPARE:
        raise ValueError(f"unknown protocol {protocol!r}; known: {', '.join(PROTOCOLS)}")
    if cfg.scaler not in SCALERS:
        raise ValueError(f"unknown scaler {cfg.scaler!r}; known: {', '.join(SCALERS)}")
    if "label" not in df.columns:
        raise ValueError("the dataset has no 'label' column")
    if not cfg.seeds:
        raise ValueError("no seed given")
    notes: list[str] = []
    df = _drop_rare_classes(df, cfg.min_class_runs, notes).reset_index(drop=True)
    features = resolve_features(df, cfg.features)
    task = PREPARE[protocol](df, feature_matrix(df, features), notes, cfg)
    if any(detector(m).uses_context for m in cfg.models):
        task.x_ctx, task.ctx_names = context_matrix(df), context_columns(df)
    splits = {seed: task.split(seed) for seed in cfg.seeds}
    source = df.attrs.get("source")
    if source and source not in ("uavcas", "uavcas-csv"):
        notes.append(f"external dataset ({source}): no runs, each flow is its own group, so the "
                     "split is a stratified flow-level one")
    absent = df.attrs.get("absent_features") or []
    if absent:
        notes.append(f"{len(absent)} features absent from this dataset (set to 0): {', '.join(absent)}")
    return Prepared(protocol, task, splits, features, notes)


def execute(prep: Prepared, cfg: BenchConfig) -> ProtocolResult:
    """Fit and score every model on every seed's split."""
    task = prep.task
    res = ProtocolResult(prep.protocol, task.declared, prep.features, notes=list(prep.notes))
    for seed, sp in prep.splits.items():
        res.splits += _split_rows(task, seed, sp)
        uncapped = sp.train
        if cfg.train_cap:
            sp = Split(cap_rows(sp.train, task.y, task.groups, cfg.train_cap, seed),
                       cap_rows(sp.val, task.y, task.groups, cfg.train_cap, seed + 1), sp.test, sp.groups)
        res.sizes[seed] = {"train": len(sp.train), "val": len(sp.val), "test": len(sp.test),
                           **{k: len(v) for k, v in task.fixed.items()}}
        prior_from = uncapped if cfg.train_cap and task.natural_prior else None
        if prior_from is not None and PRIOR_NOTE not in res.notes:
            res.notes.append(PRIOR_NOTE)
        for name in cfg.models:
            _fit_one(res, task, sp, name, seed, cfg, prior_from)
    return res


def run_protocol(df: pd.DataFrame, protocol: str, cfg: BenchConfig) -> ProtocolResult:
    return execute(prepare(df, protocol, cfg), cfg)
