"""The four evaluation protocols. Each returns long-format rows (protocol, model, metric, class,
value; class "" for overall metrics) plus confusion matrices, timings and notes."""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from sklearn.metrics import confusion_matrix, f1_score, roc_auc_score
from sklearn.preprocessing import MinMaxScaler, RobustScaler, StandardScaler
from threadpoolctl import threadpool_limits

from uavcas import schema
from uavcas.vocabulary import families_of

from .features import feature_matrix
from .models import DEEP, DISPLAY, MODELS, fit_model, make_model
from .splits import grouped_split
from .torch_estimator import default_threads

PROTOCOLS = ("binary", "multiclass", "ood", "cross-condition")
SCALERS = {"standard": StandardScaler, "minmax": MinMaxScaler, "robust": RobustScaler}
ATTACK = "Attack"
_DOS = re.compile(r"^dos($|[ _\-])", re.IGNORECASE)  # DoS, 'DoS Hulk', 'DoS-UDP_Flood'; not 'DoS+Replay'


@dataclass
class BenchConfig:
    models: tuple[str, ...] = MODELS
    scaler: str = "standard"
    epochs: int = 50
    seed: int = 0
    holdout: tuple[tuple[str, str], ...] = ()
    n_threads: int | None = None
    progress: Callable[[str], None] | None = None  # told "<model>: <seconds>" after each model


@dataclass
class ProtocolResult:
    protocol: str
    rows: list[dict] = field(default_factory=list)
    confusion: dict[str, tuple[list[str], np.ndarray]] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    epochs_run: dict[str, int] = field(default_factory=dict)  # neural models: epochs before early stop
    splits: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def add(self, model: str, metric: str, value: float, cls: str = "") -> None:
        self.rows.append({"protocol": self.protocol, "model": model, "metric": metric, "class": cls, "value": float(value)})


def is_dos(label: str) -> bool:
    return bool(_DOS.match(str(label)))


def _groups(df: pd.DataFrame, notes: list[str]) -> np.ndarray:
    if "run_id" in df.columns:
        return df["run_id"].astype(str).to_numpy()
    notes.append("no run_id column: every flow is its own group (flow-level stratified split)")
    return np.arange(len(df)).astype(str)


def _fit_predict(res: ProtocolResult, name: str, cfg: BenchConfig, xtr, ytr, xva, yva, xtests: list[np.ndarray]):
    """Scale on the training rows only, fit, return probabilities on each test matrix + classes;
    records the fit+predict time (and epochs run, for the neural models) in `res`."""
    if cfg.scaler not in SCALERS:
        raise ValueError(f"unknown scaler {cfg.scaler!r}; known: {', '.join(SCALERS)}")
    t0 = time.perf_counter()
    scaler = SCALERS[cfg.scaler]().fit(xtr)
    tf = lambda x: np.clip(scaler.transform(x), -1e6, 1e6).astype(np.float32)  # noqa: E731
    est = make_model(name, random_state=cfg.seed, epochs=cfg.epochs, n_threads=cfg.n_threads)
    # why: BLAS/OpenMP pools default to all cores and busy-wait; on a shared 2-core machine
    # oversubscription makes a 1-second fit take 10
    with threadpool_limits(limits=cfg.n_threads or default_threads()):
        fit_model(est, tf(xtr), ytr, tf(xva) if len(xva) else None, yva if len(xva) else None)
        probs = [est.predict_proba(tf(x)) if len(x) else np.empty((0, len(est.classes_))) for x in xtests]
    res.timings[DISPLAY[name]] = time.perf_counter() - t0
    n_ep = getattr(est, "n_epochs_", None) or getattr(est, "n_iter_", None)
    if isinstance(n_ep, (int, np.integer)) and name in ("mlp",) + DEEP:
        res.epochs_run[DISPLAY[name]] = int(n_ep)
    if cfg.progress:
        epochs = f", {n_ep} epochs" if name in ("mlp",) + DEEP else ""
        cfg.progress(f"{DISPLAY[name]}: {res.timings[DISPLAY[name]]:.1f} s{epochs}")
    return probs, est.classes_


def _per_class_f1(res: ProtocolResult, model: str, y, pred, labels: list[str]) -> None:
    """F1 of each class that has test flows (a class without any has no F1, not an F1 of 0)."""
    present = set(np.asarray(y).tolist())
    absent = [c for c in labels if c not in present]
    note = f"no test flow of: {', '.join(absent)} (no per-class F1 for them)"
    if absent and note not in res.notes:
        res.notes.append(note)
    labels = [c for c in labels if c in present]
    f1s = f1_score(y, pred, labels=labels, average=None, zero_division=0)
    for c, v in zip(labels, f1s):
        res.add(model, "f1", v, c)


def _overall(res: ProtocolResult, model: str, y, pred, suffix: str = "") -> None:
    res.add(model, "f1_weighted" + suffix, f1_score(y, pred, average="weighted", zero_division=0))
    res.add(model, "f1_macro" + suffix, f1_score(y, pred, average="macro", zero_division=0))
    res.add(model, "accuracy" + suffix, float(np.mean(np.asarray(y) == np.asarray(pred))))


def _auroc(y_pos: np.ndarray, score: np.ndarray) -> float:
    if len(np.unique(y_pos)) < 2:
        return float("nan")
    return float(roc_auc_score(y_pos, score))


def _class_order(labels) -> list[str]:
    present = set(map(str, labels))
    return [c for c in schema.CLASSES if c in present] + sorted(present - set(schema.CLASSES))


def _grouped_fits(res: ProtocolResult, df: pd.DataFrame, y: np.ndarray, cfg: BenchConfig):
    """70/10/20 split grouped by run; per model yield (name, y_test, proba, classes, pred).

    Overall weighted/macro F1 are recorded here; the protocol adds its own metrics.
    """
    x, g = feature_matrix(df), _groups(df, res.notes)
    sp = grouped_split(y, g, seed=cfg.seed)
    res.splits = {"train": len(sp.train), "val": len(sp.val), "test": len(sp.test)}
    for name in cfg.models:
        (p,), classes = _fit_predict(res, name, cfg, x[sp.train], y[sp.train], x[sp.val], y[sp.val], [x[sp.test]])
        pred = classes[p.argmax(1)]
        m = DISPLAY[name]
        _overall(res, m, y[sp.test], pred)
        yield m, y[sp.test], p, classes, pred


def run_binary(df: pd.DataFrame, cfg: BenchConfig) -> ProtocolResult:
    """Benign vs DoS (DoS classes of other datasets: 'DoS ...'); weighted and macro F1, AUROC."""
    res = ProtocolResult("binary")
    sub = df[(df["label"] == schema.BENIGN) | df["label"].map(is_dos)]
    y = np.where(sub["label"] == schema.BENIGN, schema.BENIGN, "DoS")
    if len(np.unique(y)) < 2:
        raise ValueError("binary protocol needs Benign and DoS flows")
    for m, y_test, p, classes, pred in _grouped_fits(res, sub, y, cfg):
        pos = list(classes).index("DoS") if "DoS" in classes else None
        res.add(m, "auroc", _auroc(y_test == "DoS", p[:, pos]) if pos is not None else np.nan)
        _per_class_f1(res, m, y_test, pred, [schema.BENIGN, "DoS"])
    return res


def run_multiclass(df: pd.DataFrame, cfg: BenchConfig) -> ProtocolResult:
    """All classes (15 on a full uavcas dataset): per-class F1, macro/weighted F1, confusion."""
    res = ProtocolResult("multiclass")
    y = df["label"].astype(str).to_numpy()
    labels = _class_order(y)
    for m, y_test, _p, _classes, pred in _grouped_fits(res, df, y, cfg):
        _per_class_f1(res, m, y_test, pred, labels)
        res.confusion[m] = (labels, confusion_matrix(y_test, pred, labels=labels))
    return res


def run_ood(df: pd.DataFrame, cfg: BenchConfig) -> ProtocolResult:
    """Train attack-vs-benign on single-attack configurations; AUROC per collaborative one.

    Each composition's test set: all flows of its runs (attack and benign ones) plus the benign
    flows of the held-out single-configuration test runs, so both classes are always present.
    """
    res = ProtocolResult("ood")
    if "attacks" not in df.columns:
        raise ValueError("ood protocol needs the 'attacks' axis column (a uavcas dataset)")
    comp = df["attacks"].map(families_of)
    single = (comp.map(len) <= 1).to_numpy()
    multi = ~single
    if not multi.any() or not single.any():
        raise ValueError("ood protocol needs both single-attack and collaborative configurations")
    y = np.where(df["label"] == schema.BENIGN, schema.BENIGN, ATTACK)
    x, g = feature_matrix(df), _groups(df, res.notes)
    si = np.flatnonzero(single)
    sp = grouped_split(y[si], g[si], seed=cfg.seed)
    tr, va, te = si[sp.train], si[sp.val], si[sp.test]
    names = comp.map(lambda f: schema.class_name(f)).to_numpy()
    comps = _class_order(names[multi])
    test_benign = te[y[te] == schema.BENIGN]
    evals = [te] + [np.concatenate([np.flatnonzero(multi & (names == c)), test_benign]) for c in comps]
    res.splits = {"train": len(tr), "val": len(va), "test_single": len(te), "compositions": len(comps)}
    for name in cfg.models:
        probs, classes = _fit_predict(res, name, cfg, x[tr], y[tr], x[va], y[va], [x[e] for e in evals])
        k = list(classes).index(ATTACK)
        m = DISPLAY[name]
        res.add(m, "auroc_in_distribution", _auroc(y[te] == ATTACK, probs[0][:, k]))
        for c, e, p in zip(comps, evals[1:], probs[1:]):
            res.add(m, "auroc", _auroc(y[e] == ATTACK, p[:, k]), c)
    return res


def run_cross_condition(df: pd.DataFrame, cfg: BenchConfig) -> ProtocolResult:
    """Hold out every flow whose axis has the given value; multiclass on the rest; F1 on the
    held-out condition beside F1 on a grouped test split of the seen conditions (`_iid`)."""
    res = ProtocolResult("cross-condition")
    if not cfg.holdout:
        raise ValueError("cross-condition needs --holdout AXIS=VALUE (e.g. mission=random)")
    held = np.zeros(len(df), dtype=bool)
    for axis, value in cfg.holdout:
        if axis not in schema.AXIS_COLUMNS or axis not in df.columns:
            raise ValueError(f"--holdout: {axis!r} is not an axis column of this dataset ({', '.join(schema.AXIS_COLUMNS)})")
        m = (df[axis].astype(str) == str(value)).to_numpy()
        if not m.any():
            raise ValueError(f"--holdout: no flow has {axis}={value} (values: {sorted(df[axis].astype(str).unique())})")
        held |= m
    if held.all():
        raise ValueError("--holdout leaves no flow to train on")
    res.notes.append("held out: " + ", ".join(f"{a}={v}" for a, v in cfg.holdout))
    y = df["label"].astype(str).to_numpy()
    labels = _class_order(y)
    x, g = feature_matrix(df), _groups(df, res.notes)
    rest, ho = np.flatnonzero(~held), np.flatnonzero(held)
    sp = grouped_split(y[rest], g[rest], seed=cfg.seed)
    tr, va, te = rest[sp.train], rest[sp.val], rest[sp.test]
    res.splits = {"train": len(tr), "val": len(va), "test_seen": len(te), "test_heldout": len(ho)}
    for name in cfg.models:
        (p_ho, p_te), classes = _fit_predict(res, name, cfg, x[tr], y[tr], x[va], y[va], [x[ho], x[te]])
        m = DISPLAY[name]
        pred = classes[p_ho.argmax(1)]
        _overall(res, m, y[ho], pred)
        _overall(res, m, y[te], classes[p_te.argmax(1)], suffix="_iid")
        _per_class_f1(res, m, y[ho], pred, labels)
        res.confusion[m] = (labels, confusion_matrix(y[ho], pred, labels=labels))
    return res


RUNNERS = {"binary": run_binary, "multiclass": run_multiclass, "ood": run_ood, "cross-condition": run_cross_condition}


def run_protocol(df: pd.DataFrame, protocol: str, cfg: BenchConfig) -> ProtocolResult:
    if protocol not in RUNNERS:
        raise ValueError(f"unknown protocol {protocol!r}; known: {', '.join(PROTOCOLS)}")
    if "label" not in df.columns:
        raise ValueError("the dataset has no 'label' column")
    source = df.attrs.get("source")
    res = RUNNERS[protocol](df.reset_index(drop=True), cfg)
    if source:
        res.notes.append(f"external dataset ({source}): no runs, each flow is its own group, so the "
                         "split is a stratified flow-level one")
    absent = df.attrs.get("absent_features") or []
    if absent:
        res.notes.append(f"{len(absent)} features absent from this dataset (set to 0): {', '.join(absent)}")
    return res
