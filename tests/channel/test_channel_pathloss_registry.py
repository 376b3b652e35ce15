"""The path-loss registry: every name builds a model of the protocol, an unknown name is a one-line
error listing the registered ones, and a model is added by dropping one module into the package
(shown on a temporary copy of uavcas: registry, codec, plan, Channel's LOS state, CLI, data dictionary)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers.plugin import check_ok, package_with
from uavcas.channel.geometry import LinkGeometry
from uavcas.channel.pathloss import (
    LosPathLossModel,
    PathLossModel,
    PathLossSpec,
    check_name,
    make_pathloss,
    names,
    register,
    spec,
    specs,
)

GEOM = LinkGeometry(d3d_m=np.array([80.0, 600.0, 150.0]), d2d_m=np.array([60.0, 599.0, 20.0]),
                    h_ground_m=np.array([25.0, 25.0, 40.0]), h_air_m=np.array([80.0, 60.0, 110.0]),
                    air_to_air=np.array([False, False, True]))


def test_every_registered_name_builds_a_model_of_the_protocol():
    assert len(set(names())) == len(names()) == len(specs())
    for s in specs():
        m = make_pathloss(s.name)
        assert type(m) is s.model and isinstance(m, PathLossModel), s.name
        assert s.standard and s.summary
        np.testing.assert_array_equal(m.loss_db(GEOM), m.evaluate(GEOM).loss_db)
        if s.samples_los:  # a LOS model: P_LOS per link, air-to-air links LOS, a correlation distance
            assert isinstance(m, LosPathLossModel) and m.los_corr_m > 0
            p = m.p_los(GEOM)
            assert np.all((p > 0) & (p <= 1)) and p[2] == 1.0
            assert m.evaluate(GEOM, np.zeros(3)).los.all()
        else:
            assert m.evaluate(GEOM, np.zeros(3)).los is None


def test_the_three_tr36777_scenarios_and_the_papers_alias_carry_their_standard():
    for n in ("3gpp", "uma", "rma", "umi"):
        assert "3GPP TR 36.777 V15.0.0" in spec(n).standard and spec(n).samples_los
    assert spec("3gpp").model is spec("uma").model
    assert make_pathloss("umi", h_bs_m=12.0).h_bs_m == 12.0


def test_channel_models_lists_every_registered_model_with_its_standard():
    from typer.testing import CliRunner

    from uavcas.cli import app

    r = CliRunner().invoke(app, ["channel", "models"], env={"COLUMNS": "400"})
    assert r.exit_code == 0, r.output
    rows = [ln for ln in r.output.splitlines() if "│" in ln]
    for s in specs():
        row = next(ln for ln in rows if ln.split("│")[1].strip() == s.name)
        assert s.standard in row and ("sampled" in row) == s.samples_los and (s.fit or "-") in row


def test_fit_hooks_resolve_to_the_calibration_functions():
    from uavcas.calibration import layer1_fit

    hooks = {s.name: s.fit_hook() for s in specs()}
    assert hooks["logdist"] is layer1_fit.fit_logdistance and hooks["tworay"] is layer1_fit.fit_two_ray
    assert all(h is None or callable(h) for h in hooks.values())


def test_unknown_names_and_bad_registrations_are_refused_in_one_line():
    for bad in (lambda: make_pathloss("okumura"), lambda: check_name("okumura")):
        with pytest.raises(ValueError) as e:
            bad()
        msg = str(e.value)
        assert "\n" not in msg and msg.startswith("unknown path-loss model 'okumura'; registered: ")
        assert msg.endswith(", ".join(names()))
    dup = spec("freespace")
    with pytest.raises(ValueError, match="registered twice"):
        register(dup)
    with pytest.raises(ValueError, match="must match"):  # '-' separates the scenario's fields
        register(PathLossSpec(name="free-space", model=dup.model, standard="x", summary="x", build=dup.build))
    assert "free-space" not in names()


# A model nobody ships: LOS with probability 0.5 everywhere, NLOS 20 dB above free space.
PLUGIN = '''
"""Throwaway test model."""
from dataclasses import dataclass

import numpy as np

from ..geometry import PathLossResult
from .base import PathLossSpec
from .freespace import free_space_loss_db
from .registry import register


@dataclass(frozen=True)
class HalfSplit:
    fc_ghz: float = 3.51
    samples_los = True
    los_corr_m = 40.0

    def p_los(self, geom):
        return np.full(len(geom), 0.5)

    def loss_db(self, geom):
        return self.evaluate(geom).loss_db

    def evaluate(self, geom, los_uniform=None):
        fs = free_space_loss_db(geom.d3d_m, self.fc_ghz)
        if los_uniform is None:
            return PathLossResult(fs + 10.0, np.full(len(geom), 2.0), None)
        los = np.asarray(los_uniform) < self.p_los(geom)
        return PathLossResult(np.where(los, fs, fs + 20.0), np.full(len(geom), 2.0), los)


register(PathLossSpec(name="halfsplit", model=HalfSplit, standard="test only", summary="half LOS, half NLOS",
                      build=lambda o: HalfSplit(fc_ghz=o.carrier_ghz)))
'''

CHECK = '''
import sys
import numpy as np
import uavcas
from uavcas.channel import Channel
from uavcas.channel.pathloss import names, spec
from uavcas.dataset.dictionary import describe
from uavcas.views import view
from uavcas.scenario import parse
from uavcas.twin.plan import plan

assert uavcas.__file__.startswith(sys.argv[1]), uavcas.__file__
assert "halfsplit" in names() and spec("halfsplit").samples_los
text = "benign-3-1-image-halfsplit-adaptive-random-30-95"
assert parse(text).pathloss == "halfsplit"
p = plan(text, windows=1)
assert p.scenario.pathloss == "halfsplit" and p.windows and p.windows[0].links
ch = Channel(n_nodes=3, pathloss="halfsplit")
pos = np.array([[0.0, 0.0, 25.0], [300.0, 0.0, 60.0], [0.0, 400.0, 80.0]])
la = ch.evaluate(pos, np.array([[0, 1], [0, 2], [1, 2]]), np.array([True, False, False]))
assert la.los is not None and la.los.dtype == bool  # the LOS state is drawn for any model that has one
assert "halfsplit" in describe("pathloss", "cic", view("5tuple"))[1]
print("ok")
'''


@pytest.fixture(scope="module")
def plugged(tmp_path_factory) -> tuple[Path, dict]:
    root = tmp_path_factory.mktemp("plug")
    return root, package_with(root, "channel/pathloss/halfsplit.py", PLUGIN)


def test_a_dropped_in_module_is_found_by_the_registry_codec_plan_channel_and_dictionary(plugged):
    check_ok(CHECK, *plugged)


@pytest.mark.slow  # 10 s on 2 cores
def test_a_dropped_in_module_is_offered_and_evaluated_by_channel_predict(plugged):
    root, env = plugged
    r = subprocess.run([sys.executable, "-m", "uavcas", "channel", "predict", "--help"], capture_output=True,
                       text=True, env=env, timeout=120)
    assert r.returncode == 0 and "halfsplit" in r.stdout and "half LOS, half NLOS" in r.stdout, r.stdout
    r = subprocess.run([sys.executable, "-m", "uavcas", "channel", "models"], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0 and "halfsplit" in r.stdout and "test only" in r.stdout, r.stdout
    (root / "g.csv").write_text("d3d_m,d2d_m,h_uav_m,h_bs_m\n1000,999,60,25\n")
    r = subprocess.run([sys.executable, "-m", "uavcas", "channel", "predict", "--model", "halfsplit", "--profile",
                        "paper", "--in", str(root / "g.csv"), "--out", str(root / "o.csv")],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    row = (root / "o.csv").read_text().splitlines()[1].split(",")
    # the LOS-weighted mean: free space at 1 km, 3.51 GHz (103.354 dB, hand-computed) + 0.5 x 20 dB
    assert float(row[4]) == pytest.approx(113.354, abs=1e-3)
