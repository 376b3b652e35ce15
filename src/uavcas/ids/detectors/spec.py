"""`DetectorSpec`: what the benchmark needs to know about one detector, in one frozen record.

A detector module of this package registers one spec (`registry.register`). The spec says how to
build the estimator (`factory`: a fresh, unfitted scikit-learn classifier with its settings) and
how the benchmark drives it: which of its parameters is the seed, which the epoch budget and
which the thread count (the benchmark's seeds and the CLI's `--epochs` and `--threads` reach
every model through them), whether its
permutation importance is computed, whether it is one of the paper's ten baselines (`--models
all`), and its kind, which decides what it is given and needs:

- `classical`: the flow features; scikit-learn or LightGBM on the CPU;
- `deep`: the flow features; a `TorchClassifier`, so it needs PyTorch (the `dl` extra) and trains
  on the CLI's `--device`;
- `context`: the flow features and the dataset's `ctx_*` context columns, as a frame with named
  columns (the estimator selects its inputs by name).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

if TYPE_CHECKING:
    from sklearn.base import BaseEstimator

Kind = Literal["classical", "deep", "context"]
KINDS: tuple[str, ...] = get_args(Kind)
# what each kind needs, for the CLI's help (empty: nothing beyond the flow features)
KIND_NEEDS: dict[str, str] = {"classical": "", "deep": "need PyTorch", "context": "need the dataset's ctx_* columns"}
_NAME = re.compile(r"^[a-z0-9][a-z0-9_-]*$")  # lower case: names are matched case-insensitively
LAST = 1000  # `order` of a detector that does not choose one: after the paper's and ours


@dataclass(frozen=True)
class DetectorSpec:
    """One detector. `name`: what `--models` and `baseline(name)` take; `display`: its name in
    results, leaderboards and figures; `factory()`: a fresh, unfitted estimator (heavy imports,
    torch above all, inside it: importing the registry stays cheap and torch stays optional);
    `order`: its position in listings and tables (the paper's order first); `seed_param`,
    `epoch_param` and `thread_param`: the estimator's parameter for the seed, the epoch budget
    and the thread count (None: it has none, e.g. no seed for a deterministic estimator);
    `tree`: permutation importance is computed for it; `paper_baseline`: one of the paper's ten
    baselines (`--models all`)."""

    name: str
    display: str
    kind: Kind
    factory: Callable[[], BaseEstimator]
    order: int = LAST
    seed_param: str | None = "random_state"
    epoch_param: str | None = None
    thread_param: str | None = None
    tree: bool = False
    paper_baseline: bool = False

    def __post_init__(self) -> None:
        if not _NAME.match(self.name):
            raise ValueError(f"detector name {self.name!r}: lower-case letters, digits, '-' and '_' only")
        if self.kind not in KINDS:
            raise ValueError(f"detector {self.name!r}: kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if not self.display.strip():
            raise ValueError(f"detector {self.name!r}: empty display name")

    @property
    def needs_torch(self) -> bool:
        return self.kind == "deep"

    @property
    def uses_context(self) -> bool:
        """Whether the protocols give it the context columns (as a frame with named columns)."""
        return self.kind == "context"
