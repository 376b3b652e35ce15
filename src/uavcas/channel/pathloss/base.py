"""What a path-loss model is (`PathLossModel`), what the registry records about it (`PathLossSpec`)
and the options a scenario name is built with (`PathLossOptions`).

A model turns per-link geometry into a median loss and the shadowing spread to apply on top
(`evaluate`). A model with a LOS state (`samples_los`) also gives P_LOS per link; `Channel` then
draws the state from a correlated uniform (`channel.model`), any other model ignores it.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np
from pydantic import BaseModel

from ..geometry import LinkGeometry, PathLossResult

DEFAULT_FC_GHZ = 3.51  # AERPAW measurement carrier (Maeng et al.): the default of every model


@runtime_checkable
class PathLossModel(Protocol):
    """Every registered model. `loss_db` is the median loss without shadowing (for a model with a
    LOS state: the P_LOS-weighted mean), equal to ``evaluate(geom).loss_db``."""

    samples_los: ClassVar[bool]

    def loss_db(self, geom: LinkGeometry) -> np.ndarray: ...

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult: ...


@runtime_checkable
class LosPathLossModel(PathLossModel, Protocol):
    """A model with a LOS state (samples_los = True): P_LOS per link and the distance over which
    the state stays correlated; `evaluate(geom, u)` is LOS where u < P_LOS."""

    los_corr_m: float

    def p_los(self, geom: LinkGeometry) -> np.ndarray: ...


@dataclass(frozen=True)
class PathLossOptions:
    """What `make_pathloss` passes a model's `build`; each model uses the options it has.

    profile: log-distance parameters (a `logdist.PathLossProfile`, a name of `logdist.PROFILES`, or
    None: paper-anchored). Typed as its base class: the profile is the log-distance model's own
    record, and naming it here would make this module, which every model imports, import one.
    fc_ghz: carrier (None: the model's default, 3.51 GHz, or the log-distance profile's own).
    h_bs_m: BS antenna height where a model must assume one (None: the model's default).
    """

    profile: BaseModel | str | None = None
    fc_ghz: float | None = None
    h_bs_m: float | None = None

    @property
    def carrier_ghz(self) -> float:
        return DEFAULT_FC_GHZ if self.fc_ghz is None else float(self.fc_ghz)


@dataclass(frozen=True)
class PathLossSpec:
    """One registered scenario name.

    name: the scenario string's token (lower-case letters, digits, '_'; no '-', the field separator).
    model: the class `build` returns (its `samples_los` says whether `Channel` draws a LOS state).
    standard: where the formula comes from, with its version, as the code implements it.
    summary: one line for the CLI help and the data dictionary.
    build: options -> model instance.
    fit: the calibration fit of this model as "module:function" (None: calibration does not fit
        it); a path, not an import, because calibration sits above the channel.
    """

    name: str
    model: type
    standard: str
    summary: str
    build: Callable[[PathLossOptions], PathLossModel]
    fit: str | None = None

    @property
    def samples_los(self) -> bool:
        return bool(self.model.samples_los)

    def fit_hook(self) -> Callable | None:
        """The calibration fit function named by `fit` (imported now), or None."""
        if self.fit is None:
            return None
        module, _, func = self.fit.partition(":")
        return getattr(importlib.import_module(module), func)
