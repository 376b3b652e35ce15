"""Run calibration layers on a data folder and write their outputs (JSON, markdown, PNG).

Dependencies between layers are computed, not read from earlier runs: link and fidelity use the
path-loss profile fitted here (layer 1 is cheap), fidelity uses the link replay. Only the layers
asked for are *written*. With `write_profile` (a name for the profile directory, or a path
ending in .json), a `TwinProfile` is saved: the fitted path loss (with the carrier anchor),
K(h), shadowing decorrelation distance and BS mast height of layer 1, the fitted missions of
layer 2, the built-in paper values for a layer that did not run. The area's lowest altitude
becomes the lowest altitude the path loss was calibrated at (the paper's band starts at 30 m
to avoid extrapolating its fit; the Maeng 30 m file flies at a median 26.7 m, and AFAR grid
flights at 27.5 m, which the twin then flies as flown). Its `provenance` lists every
data file the run read with its SHA-256, the fit date (UTC), the uavcas version and the seed.
The profile shipped with uavcas (``uavcas/twin/profiles/calibrated.json``) is written this way
(`uavcas calibrate all --data DIR --out DIR --write-profile src/uavcas/twin/profiles/calibrated.json`).
"""

from __future__ import annotations

import datetime as _dt
import time
from dataclasses import dataclass, field
from pathlib import Path

from uavcas import __version__
from uavcas.twin.profile import PAPER_PROFILE, DataFile, Provenance, TwinProfile, save_profile
from uavcas.versions import file_sha256

from . import figures, report
from .layer1_pathloss import Layer1Result, layer1_json, run_layer1
from .layer2_mobility import MISSIONS, Layer2Result, layer2_json, run_layer2
from .layer3_link import Layer3Result, layer3_json, run_layer3
from .layer4_fidelity import layer4_json, run_layer4
from .loaders import load_afar, load_maeng, load_multibw, load_pattern

LAYERS = ("pathloss", "mobility", "link", "fidelity")


@dataclass
class RunOutput:
    results: dict = field(default_factory=dict)  # layer -> JSON dict
    files: list[Path] = field(default_factory=list)
    profile_path: Path | None = None
    runtime_s: float = 0.0
    inputs: list[Path] = field(default_factory=list)  # data files read


def provenance(inputs: list[Path], data: Path, seed: int, tool: str) -> Provenance:
    files = []
    for p in sorted(set(inputs)):
        try:
            rel = str(p.resolve().relative_to(data.resolve()))
        except ValueError:
            rel = str(p)
        files.append(DataFile(path=rel, sha256=file_sha256(p), size_bytes=p.stat().st_size))
    return Provenance(tool=tool, uavcas_version=__version__, seed=seed, data_files=files,
                      fit_date_utc=_dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat())


def build_profile(name: str, l1: Layer1Result | None, l2: Layer2Result | None, data: Path | str, seed: int,
                  prov: Provenance | None = None) -> TwinProfile:
    parts = []
    update: dict = {"name": name, "provenance": prov}
    if l1 is not None:
        update["pathloss"] = l1.profile.model_copy(update={"name": f"{name}-pathloss"})
        update["bs_mast_m"] = round(l1.tx_height_m, 2)
        update["area"] = PAPER_PROFILE.area.model_copy(update={"z_min_m": round(min(l1.profile.altitude_m), 1)})
        channel = PAPER_PROFILE.channel.model_copy(update={"fading": l1.k_factor,
                                                           "d_corr_m": round(l1.decorrelation_m, 1)})
        update["channel"] = channel
        parts.append("path loss, K(h), shadowing decorrelation and mast height (layer 1)")
    if l2 is not None:
        update["mobility"] = l2.profile.model_copy(update={"name": f"{name}-mobility"})
        parts.append("mobility (layer 2)")
    update["source"] = (f"uavcas calibrate on {Path(str(data)).name} (seed {seed}): fitted "
                        f"{' and '.join(parts) or 'nothing'}; other parts built in (paper)")
    return PAPER_PROFILE.model_copy(update=update)


def parse_assignment(text: str | None) -> dict[int, str] | None:
    """'301=spiral,309=spiral,328=grid' -> {301: 'spiral', ...}; None -> the paper's."""
    if not text:
        return None
    out = {}
    for item in text.split(","):
        team, _, kind = item.partition("=")
        if not team.strip().isdigit() or kind.strip() not in MISSIONS:
            raise ValueError(f"bad mission assignment {item!r}: expected TEAM=<{'|'.join(MISSIONS)}>")
        out[int(team)] = kind.strip()
    return out


def run(layers: tuple[str, ...], data: Path, out: Path, seed: int = 0, write_profile: str | None = None,
        log=print, assignment: dict[int, str] | None = None) -> RunOutput:
    t0 = time.monotonic()
    res = RunOutput()
    need1 = any(x in layers for x in ("pathloss", "link", "fidelity"))
    need3 = any(x in layers for x in ("link", "fidelity"))
    l1 = l2 = None
    l3: Layer3Result | None = None
    afar = load_afar(data) if (need3 or "mobility" in layers) else None
    if afar is not None:
        res.inputs += [f.source for f in afar] + [f.processed for f in afar if f.processed is not None]
    if need1:
        maeng, multibw, pattern = load_maeng(data), load_multibw(data), load_pattern(data)
        res.inputs += [s.source for s in maeng + multibw] + ([pattern.source] if pattern is not None else [])
        l1 = run_layer1(maeng, multibw, pattern, seed=seed)
        log(f"layer 1 fitted ({time.monotonic() - t0:.1f} s)")
    if "pathloss" in layers:
        j = layer1_json(l1)
        res.results["pathloss"] = j
        res.files += [report.write_json(out / "pathloss.json", j),
                      report.write_md(out / "pathloss.md", report.pathloss_md(j)),
                      figures.pathloss_figure(l1, out / "pathloss_vs_distance.png", seed),
                      figures.crossval_figure(l1, out / "pathloss_crossval.png")]
    if "mobility" in layers:
        l2 = run_layer2(afar, seed=seed, assignment=assignment)
        j = layer2_json(l2)
        res.results["mobility"] = j
        res.files += [report.write_json(out / "mobility.json", j),
                      report.write_md(out / "mobility.md", report.mobility_md(j))]
        res.files += figures.mobility_figures(l2, out, seed)
        log(f"layer 2 done ({time.monotonic() - t0:.1f} s)")
    if need3:
        l3 = run_layer3(afar, l1.profile, seed=seed, fading=l1.k_factor, d_corr_m=l1.decorrelation_m)
        log(f"layer 3 replayed ({time.monotonic() - t0:.1f} s)")
    if "link" in layers:
        j = layer3_json(l3)
        res.results["link"] = j
        res.files += [report.write_json(out / "link.json", j), report.write_md(out / "link.md", report.link_md(j)),
                      figures.link_figure(l3, out / "link_representative_flight.png")]
    if "fidelity" in layers:
        l4 = run_layer4(l1.groups, l1.crossval_groups, l3, l1.profile, l1.k_factor, l1.decorrelation_m, seed=seed)
        j = layer4_json(l4)
        res.results["fidelity"] = j
        res.files += [report.write_json(out / "fidelity.json", j),
                      report.write_md(out / "fidelity.md", report.fidelity_md(j)),
                      figures.fidelity_figure(l4, out / "fidelity_rss_pdf.png")]
        log(f"layer 4 done ({time.monotonic() - t0:.1f} s)")
    if write_profile:
        tool = f"uavcas calibrate {'all' if set(layers) == set(LAYERS) else ','.join(layers)} --seed {seed}"
        prof = build_profile(Path(write_profile).stem if write_profile.endswith(".json") else write_profile,
                             l1, l2, data, seed, provenance(res.inputs, data, seed, tool))
        res.profile_path = save_profile(prof, write_profile)
    res.runtime_s = time.monotonic() - t0
    res.files.append(report.write_md(out / "summary.md", report.summary_md(res.results, res.runtime_s)))
    return res
