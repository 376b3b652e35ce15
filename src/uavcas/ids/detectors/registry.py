"""The one registry of IDS detectors: name -> `DetectorSpec`, and the estimators built from it."""

from __future__ import annotations

from typing import TYPE_CHECKING

from uavcas.ids.torch_estimator import default_threads

from .spec import DetectorSpec

if TYPE_CHECKING:
    from sklearn.base import BaseEstimator

_REGISTRY: dict[str, DetectorSpec] = {}


def register(spec: DetectorSpec) -> DetectorSpec:
    """Make `spec` the detector of its name (one module of this package each)."""
    if spec.name in _REGISTRY:
        raise ValueError(f"detector {spec.name!r} registered twice")
    shown = {s.display: s.name for s in _REGISTRY.values()}
    if spec.display in shown:  # results and leaderboards key the models by display name
        raise ValueError(f"detector {spec.name!r}: display name {spec.display!r} is {shown[spec.display]!r}'s")
    _REGISTRY[spec.name] = spec
    return spec


def detectors() -> tuple[DetectorSpec, ...]:
    """Every detector, in listing order (`order`, then name)."""
    return tuple(sorted(_REGISTRY.values(), key=lambda s: (s.order, s.name)))


def names() -> tuple[str, ...]:
    return tuple(s.name for s in detectors())


def baselines() -> tuple[DetectorSpec, ...]:
    """The paper's ten baselines (`--models all`), in the paper's order."""
    return tuple(s for s in detectors() if s.paper_baseline)


def detector(name: str) -> DetectorSpec:
    """The spec of `name` (case and surrounding blanks ignored); ValueError naming every
    registered detector otherwise."""
    try:
        return _REGISTRY[name.strip().lower()]
    except (KeyError, AttributeError):
        raise ValueError(f"unknown detector {name!r}; known: {', '.join(names())}") from None


def baseline(name: str, **params) -> BaseEstimator:
    """A fresh, unfitted estimator for detector `name` with its settings, `params` overriding
    them (`set_params` names), e.g. `baseline("rf", n_estimators=50)`; unknown names or
    parameters raise ValueError."""
    return detector(name).factory().set_params(**params)


def make_model(name: str, random_state: int = 0, epochs: int = 50, n_threads: int | None = None,
               device: str = "auto") -> BaseEstimator:
    """`baseline(name)` with the benchmark's common knobs mapped to each detector's own parameter
    (`device` reaches the torch models only: the others run on the CPU)."""
    spec = detector(name)
    params: dict[str, object] = {}
    if spec.seed_param:
        params[spec.seed_param] = random_state
    if spec.needs_torch:
        params["device"] = device
    if spec.epoch_param:
        params[spec.epoch_param] = epochs
    if spec.thread_param:
        params[spec.thread_param] = n_threads or default_threads()
    return baseline(name, **params)
