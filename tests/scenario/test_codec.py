import pytest
from hypothesis import given
from hypothesis import strategies as st

from uavcas.channel.pathloss import names as pathloss_names
from uavcas.scenario import Scenario, ScenarioError, canonical, parse
from uavcas.twin.load import CONTEXT
from uavcas.vocabulary import MISSIONS


def test_paper_example_round_trips_and_is_typed():
    text = "dos=1000-20-2-image-logdist-adaptive-random-30-95"
    sc = parse(text)
    assert sc.to_string() == text
    assert sc.families == ("dos",)
    assert sc.attacks[0].nominal_pps == pytest.approx(1000.0)
    assert (sc.n_uav, sc.n_bs, sc.tx_dbm, sc.noise_dbm) == (20, 2, 30, -95.0)


def test_replay_and_pairs_round_trip():
    for text in (
        "blackhole+replay=50,200,10,5,inc-10-2-image-3gpp-adaptive-spiral-10-95",
        "replay=100,100,20,3,rand+wormhole-5-2-image-logdist-mcs3-grid-30-90",
        "benign-5-2-image-logdist-adaptive-hover_transit-30-95",
    ):
        assert parse(text).to_string() == text
    r = parse("replay=100,100,20,3,rand-5-2-image-logdist-adaptive-grid-30-95").attacks[0]
    assert (r.buffer_pkts, r.delay_ms, r.rate_pps, r.ttl_dec, r.seq_mode) == (100, 100, 20, 3, "rand")


@pytest.mark.parametrize(
    "text, field",
    [
        ("dos=1000-20-2-image-logdist-adaptive-random-30", "expected 9"),
        ("dos=abc-20-2-image-logdist-adaptive-random-30-95", "attacks.dos"),
        ("flood=1-20-2-image-logdist-adaptive-random-30-95", "field 'attacks'"),
        ("replay=1,2,3-20-2-image-logdist-adaptive-random-30-95", "replay needs 5"),
        ("replay=1,2,3,4,up-20-2-image-logdist-adaptive-random-30-95", "seq_mode"),
        ("dos=1000+dos=500-20-2-image-logdist-adaptive-random-30-95", "twice"),
        ("benign+dos=1000-20-2-image-logdist-adaptive-random-30-95", "benign"),
        ("dos=1000-020-2-image-logdist-adaptive-random-30-95", "field 'n_uav'"),
        ("dos=1000-0-2-image-logdist-adaptive-random-30-95", "field 'n_uav'"),
        ("ddos=1000-2-2-image-logdist-adaptive-random-30-95", "field 'n_uav'"),
        ("dos=1000-20-2-audio-logdist-adaptive-random-30-95", "field 'payload'"),
        ("dos=1000-20-2-image-cost231-adaptive-random-30-95", "field 'pathloss'"),
        ("dos=1000-20-2-image-logdist-mcs9-random-30-95", "field 'modulation'"),
        ("dos=1000-20-2-image-logdist-adaptive-circle-30-95", "field 'mission'"),
        ("dos=1000-20-2-image-logdist-adaptive-random-x-95", "field 'tx_dbm'"),
        ("dos=1000-20-2-image-logdist-adaptive-random-30-", "field 'noise'"),
        ("blackhole=3-20-2-image-logdist-adaptive-random-30-95", "takes no value"),
        ("dos=01000-20-2-image-logdist-adaptive-random-30-95", "attacks.dos"),
        ("dos=1000+ddos=10-20-2-image-logdist-adaptive-random-30-95", "cannot be combined"),
        ("", "empty"),
    ],
)
def test_malformed_strings_name_the_bad_field(text, field):
    with pytest.raises(ScenarioError) as e:
        parse(text)
    msg = str(e.value)
    assert field in msg and "\n" not in msg


_attack = st.sampled_from(["dos", "ddos", "blackhole", "wormhole", "replay"])


@st.composite
def scenario_strings(draw):
    fams = draw(st.lists(_attack, unique=True, max_size=3).filter(lambda f: not {"dos", "ddos"} <= set(f)))
    toks = []
    for f in fams:
        if f in ("dos", "ddos"):
            toks.append(f"{f}={draw(st.integers(1, 10**6))}")
        elif f == "replay":
            b, d, p, t = (draw(st.integers(lo, hi)) for lo, hi in ((1, 999), (0, 5000), (1, 999), (0, 254)))
            toks.append(f"replay={b},{d},{p},{t},{draw(st.sampled_from(['inc', 'rand', 'zero']))}")
        else:
            toks.append(f)
    attacks = "+".join(toks) or "benign"
    n_uav = draw(st.integers(3, 250))
    mod = draw(st.sampled_from(["adaptive"] + [f"mcs{i}" for i in range(7)]))
    return "-".join(
        map(str, (attacks, n_uav, draw(st.integers(1, 16)), draw(st.sampled_from(["image", "telemetry", "mixed"])),
                  draw(st.sampled_from(pathloss_names())), mod, draw(st.sampled_from(MISSIONS)),
                  draw(st.integers(0, 60)), draw(st.integers(30, 200))))
    )


@given(scenario_strings())
def test_round_trip_gives_the_canonical_form(text):
    sc = parse(text)
    fields = text.split("-")
    toks = fields[0].split("+")
    expected = "-".join(["+".join(sorted(toks, key=lambda t: t.split("=")[0]))] + fields[1:])
    assert sc.to_string() == expected == canonical(text)
    assert parse(expected) == sc  # out of order or not: the same scenario
    # its JSON is read back with the families' specs (the plan reader's context), not without
    assert Scenario.model_validate_json(sc.model_dump_json(), context=CONTEXT) == sc
    if sc.attacks:
        with pytest.raises(ValueError, match="attack specs are read by their families"):
            Scenario.model_validate_json(sc.model_dump_json())


def test_out_of_order_attacks_are_normalised():
    sc = parse("wormhole+dos=1000+blackhole-5-2-image-logdist-adaptive-grid-30-95")
    assert sc.families == ("blackhole", "dos", "wormhole")
    assert sc.to_string() == "blackhole+dos=1000+wormhole-5-2-image-logdist-adaptive-grid-30-95"
    assert sc.axes()["attacks"] == "blackhole+dos=1000+wormhole"
    # a Scenario built directly is canonical too
    assert Scenario(attacks=tuple(reversed(sc.attacks)), n_uav=5, n_bs=2, mission="grid").families == sc.families
