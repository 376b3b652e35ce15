"""The runs of a dataset, one row each: configuration, seed, rows per class and the fidelity verdict
with the checks that failed; and the dataset's rows per class and view (`class_table`).
`uavcas info`, the campaign's final summary, the report and the published card read them.

The card (`dataset.json: runs`) gives the verdict and, for runs extracted since it was recorded,
the failed checks' names (`fidelity_failed`); a campaign keeps each run's fidelity.json under
DATASET_DIR/runs/<id>/, which adds the measured value and the limit of every failed check.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from uavcas.fidelity.model import Fidelity
from uavcas.schema import CLASSES

UNAUDITED = "unaudited"


@dataclass(frozen=True)
class RunRow:
    run_id: str
    config: str
    seed: int | None
    rows: int
    classes: dict[str, int]  # class -> rows, in vocabulary order, zero counts left out
    verdict: str  # pass, fail, error or unaudited
    failed: tuple[str, ...]  # each failed check: "name value > limit", or why the audit failed

    @property
    def flagged(self) -> bool:
        """Kept in the dataset although its audit did not pass."""
        return self.verdict in ("fail", "error")


def _check_text(name: str, checks: dict) -> str:
    ch = checks.get(name)
    if ch is None or ch.value is None:
        return name
    op = ">=" if name == "delay_early_p1_ms" else "<="  # delay_early's limit is a floor (negative)
    shown = abs(ch.value) if name in ("delay_error_p50_ms", "loss_sigma", "throughput_rel") else ch.value
    return f"{name} {shown:.4g} (limit {op} {ch.limit:g})"


def dataset_runs(dataset_dir: str | Path, card: dict) -> list[RunRow]:
    """One row per run of the card, by run id (numerically where ids are numbers)."""
    root = Path(dataset_dir)
    rows = []
    for r in card.get("runs", []):
        rid = str(r.get("run_id", "?"))
        failed = list(r.get("fidelity_failed") or [])
        path = root / "runs" / rid / "fidelity.json"
        checks = {}
        if path.is_file():
            try:
                fid = Fidelity.model_validate_json(path.read_text())
                checks = {c.name: c for c in fid.checks}
                failed = failed or list(fid.failed)
            except ValueError:
                pass  # an unreadable audit: the card's names alone
        counts = r.get("class_counts") or {}
        rows.append(RunRow(
            run_id=rid, config=str(r.get("config", "")), seed=r.get("seed"),
            rows=int(r.get("n_flows", sum(counts.values()))),
            classes={c: int(counts[c]) for c in CLASSES if counts.get(c)} | {
                c: int(n) for c, n in counts.items() if c not in CLASSES and n},
            verdict=r.get("fidelity") or UNAUDITED,
            failed=tuple(_check_text(n, checks) for n in failed)))
    return sorted(rows, key=lambda x: (not x.run_id.isdigit(), int(x.run_id) if x.run_id.isdigit() else 0, x.run_id))


def class_table(df: pd.DataFrame) -> pd.DataFrame:
    """Rows per class (vocabulary order, then any other label) of a frame with `label` (and
    `view`): a `class` column, one count column per view (`rows` without a view column), and
    `all views` when there are several."""
    tab = pd.crosstab(df["label"], df["view"]) if "view" in df.columns else df["label"].value_counts().to_frame("rows")
    order = [c for c in CLASSES if c in tab.index] + sorted(c for c in tab.index if c not in CLASSES)
    tab = tab.loc[order]
    if tab.shape[1] > 1:
        tab["all views"] = tab.sum(axis=1)
    return tab.rename_axis(None, axis=1).reset_index().rename(columns={"label": "class"})


def percent(n: int, total: int) -> str:
    """A share for people: never "0.0%" for a count above zero (13 of 27,851 is "<0.1%")."""
    if total <= 0:
        return "-"
    p = 100.0 * n / total
    if n and p < 0.1:
        return "<0.1%"
    if n != total and p > 99.9:
        return ">99.9%"
    return f"{p:.1f}%"


def flagged_lines(runs: list[RunRow]) -> list[str]:
    """One line per run kept although its audit did not pass: id, scenario, verdict, failed checks."""
    return [f"run {r.run_id} ({r.config}): {r.verdict}" + (f": {'; '.join(r.failed)}" if r.failed else "")
            for r in runs if r.flagged]
