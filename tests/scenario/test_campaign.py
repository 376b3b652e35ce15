import json
import subprocess
import sys

import pytest

from uavcas.scenario import PRESETS, ManifestEntry, manifest, parse, parse_shard, run_seed


def test_paper_preset_has_1024_distinct_round_tripping_configs():
    configs = PRESETS["paper"].configs
    assert len(configs) == 1024 == len(set(configs))
    for c in configs:
        assert parse(c).to_string() == c
    axes = [parse(c) for c in configs]
    assert {s.n_uav for s in axes} == {5, 10, 15, 20}
    assert {s.pathloss for s in axes} == {"logdist", "3gpp"}
    assert {s.mission for s in axes} == {"spiral", "grid", "hover_transit", "random"}
    assert {s.tx_dbm for s in axes} == {10, 30}
    assert len({s.axes()["attacks"] for s in axes}) == 16


@pytest.mark.slow  # 5 s on 2 cores
def test_medium_preset_every_composition_in_four_channel_settings(tmp_path):
    """100 runs of 12 windows: the paper's 16 compositions and the new families' 9 (each alone and
    in two compositions) x 4 settings covering path loss, mission, TX power and swarm size (path
    loss x TX power as a full 2 x 2), on payload mixed, via the CLI's manifest."""
    from collections import Counter

    out = tmp_path / "m.jsonl"
    r = subprocess.run([sys.executable, "-m", "uavcas.cli", "campaign", "manifest", "--preset", "medium",
                        "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    entries = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(entries) == 100 and {(e["windows"], e["window_s"]) for e in entries} == {(12, 5.0)}
    scen = [parse(e["config"]) for e in entries]
    assert {s.payload for s in scen} == {"mixed"}
    comps = Counter(s.axes()["attacks"] for s in scen)
    assert len(comps) == 25 and min(comps.values()) >= 4
    for new in ("jamming", "gps_spoof", "mavlink_inject"):  # alone and in two compositions with the paper's
        with_it = [c for c in comps if new in {t.split("=")[0] for t in c.split("+")}]
        assert len(with_it) == 3 and sum("+" in c for c in with_it) == 2, (new, with_it)
    settings = {(s.n_uav, s.pathloss, s.mission, s.tx_dbm) for s in scen}
    assert len(settings) == 4
    assert {s.pathloss for s in scen} == {"logdist", "3gpp"} and {s.tx_dbm for s in scen} == {10, 30}
    assert {s.mission for s in scen} == {"spiral", "grid", "hover_transit",
                                         "random"} and len({s.n_uav for s in scen}) == 4
    assert len({(s.pathloss, s.tx_dbm) for s in scen}) == 4
    # every composition in every setting: holding one setting out leaves each composition in 3
    assert Counter((s.axes()["attacks"], s.mission) for s in scen) == Counter({k: 1 for k in
                                                                                {(c, m) for c in comps
                                                                                 for m in {s.mission for s in scen}}})


def test_permutation_is_seeded_and_shards_partition_it():
    a, b, c = manifest("paper", seed=7), manifest("paper", seed=7), manifest("paper", seed=8)
    assert [e.index for e in a] == [e.index for e in b] != [e.index for e in c]
    assert sorted(e.index for e in a) == list(range(1024))
    shards = [manifest("paper", seed=7, shard=(k, 4)) for k in range(4)]
    assert [len(s) for s in shards] == [256] * 4
    assert [e for s in shards for e in s] == a
    # run seeds depend on (campaign seed, index) only, not on order or sharding
    assert {e.index: e.seed for e in a}[5] == run_seed(7, 5)


def test_first_quarter_covers_every_axis_value():
    q = [parse(e.config) for e in manifest("paper", seed=0, shard=(0, 4))]
    assert {s.mission for s in q} == {"spiral", "grid", "hover_transit", "random"}
    assert len({s.axes()["attacks"] for s in q}) == 16


@pytest.mark.parametrize("bad", ["4/4", "a/b", "1", "-1/4", "1/0"])
def test_bad_shards_are_refused(bad):
    with pytest.raises(ValueError):
        parse_shard(bad)


@pytest.mark.slow  # 14 s on 2 cores
def test_cli_manifest(tmp_path):
    out = tmp_path / "m.jsonl"
    r = subprocess.run([sys.executable, "-m", "uavcas.cli", "campaign", "manifest", "--preset", "paper",
                        "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(rows) == 1024 and {"index", "position", "config", "seed"} <= set(rows[0])
    assert len({r["config"] for r in rows}) == 1024
    r = subprocess.run([sys.executable, "-m", "uavcas.cli", "campaign", "manifest", "--shard", "0/4",
                        "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0 and len(out.read_text().splitlines()) == 256
    bad = tmp_path / "bad.jsonl"
    r = subprocess.run([sys.executable, "-m", "uavcas.cli", "campaign", "manifest", "--shard", "9/4",
                        "--out", str(bad)], capture_output=True, text=True)
    assert r.returncode == 2 and "shard" in r.stderr and not bad.exists()


def test_every_quick_attack_has_something_to_act_on():
    """The main job must show every family: with the seeds the quick campaign gives its runs,
    each wormhole has a planned detour in some window and every attack has victims in its window
    (a wormhole without a usable detour is planned as a no-op: the quick run then had no
    Wormhole flow at all)."""
    from uavcas.twin.plan import plan

    for e in manifest("quick"):
        p = plan(e.config, seed=e.seed, windows=e.windows, window_s=e.window_s)
        for a in p.attacks:
            assert a.victims and a.attackers, (e.config, a)
            if a.family == "wormhole":
                assert any(o.victim in a.victims for w in p.windows for o in w.wormholes), e.config


def test_every_medium_composition_is_a_declared_class_and_repeats_on_fresh_victims():
    """The medium preset's compositions are classes of the vocabulary (pairs included), and its
    three rounds per run attack three different victims, never overlapping."""
    from uavcas.scenario.campaign import PRESETS
    from uavcas.twin.plan import plan
    from uavcas.twin.schedule import ROUND_GAP_S
    from uavcas.vocabulary import CLASSES, class_name

    medium = PRESETS["medium"]
    assert medium.rounds == 3
    for config in medium.configs:
        assert class_name(parse(config).families) in CLASSES, config
    p = plan("blackhole+dos=1000-6-2-mixed-3gpp-adaptive-grid-10-95", seed=3, rounds=medium.rounds)
    by_round = sorted({(a.start_s, a.stop_s, a.victims[0]) for a in p.attacks})
    assert len(by_round) == 3 and len({v for *_, v in by_round}) == 3
    for (_, stop, _), (start, _, _) in zip(by_round, by_round[1:]):
        assert start - stop >= ROUND_GAP_S
    assert all(10.0 <= b - a <= 20.0 for a, b, _ in by_round) and p.rounds == 3


def test_a_plan_stores_its_attack_rounds_under_their_old_name():
    """plan.json keeps the key "episodes" for `Plan.rounds`: plans stay byte-identical, and a plan
    written before the rename loads with its rounds."""
    import json

    from uavcas.twin.load import read_plan
    from uavcas.twin.plan import plan

    p = plan("blackhole+dos=1000-6-2-mixed-3gpp-adaptive-grid-10-95", seed=3, rounds=2)
    stored = json.loads(p.to_json())
    assert stored["episodes"] == 2 and "rounds" not in stored
    back = read_plan(p.to_json())
    assert back.rounds == 2 and back.to_json() == p.to_json()
    del stored["episodes"]  # a plan from before attack rounds: one round
    assert read_plan(json.dumps(stored)).rounds == 1



def test_an_entry_survives_its_dict_as_a_dask_task_carries_it():
    # a Dask task carries `to_dict()` (stored key `episodes`); the worker rebuilds the entry from it
    for e in manifest("medium", 0)[:3]:
        assert ManifestEntry.from_dict(e.to_dict()) == e and e.rounds == 3
