"""The traffic-app registry and the payload table: a payload is a named list of registered apps,
and every list of payloads (the codec's, `Scenario.payload`'s, the MAVLink ones, the data
dictionary's) derives from the one table."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from uavcas import vocabulary as v
from uavcas.attacks import families
from uavcas.dataset.dictionary import describe
from uavcas.scenario import Scenario, ScenarioError, parse
from uavcas.traffic import apps, registry
from uavcas.traffic.apps.image import ImageApp
from uavcas.traffic.apps.mavlink import MavlinkApp
from uavcas.traffic.apps.video import VideoApp
from uavcas.traffic.base import AppContext, AppOptions, TrafficApp
from uavcas.traffic.benign import BenignTraffic
from uavcas.traffic.payloads import DEFAULT_PAYLOAD, PAYLOAD_NAMES, PAYLOADS, apps_of, check_payload
from uavcas.twin.plan import plan
from uavcas.views import view


def test_the_payloads_are_compositions_of_registered_apps():
    assert PAYLOADS == {"image": ("image",), "telemetry": ("mavlink",), "video": ("mavlink", "video"),
                        "mixed": ("mavlink", "video", "image")}
    assert registry.unregistered() == {}  # every app a row names is registered
    assert {"image", "mavlink", "video"} <= set(apps.names())
    assert (apps.app("image"), apps.app("mavlink"), apps.app("video")) == (ImageApp, MavlinkApp, VideoApp)
    assert apps.payload_apps("mixed") == (MavlinkApp, VideoApp, ImageApp)
    assert all(issubclass(apps.app(n), TrafficApp) for n in apps.names())


def test_mavlink_payloads_derive_from_the_apps_that_carry_mavlink():
    assert [n for n in apps.names() if apps.app(n).carries_mavlink] == ["mavlink"]
    assert apps.MAVLINK_PAYLOADS == ("telemetry", "video", "mixed")
    assert [p for p in PAYLOAD_NAMES if apps.carries_mavlink(p)] == list(apps.MAVLINK_PAYLOADS)
    # the families that act on MAVLink take the derived list; the others every payload
    payloads = {f.name: f.payloads for f in families()}
    assert payloads["mavlink_inject"] == payloads["gps_spoof"] == apps.MAVLINK_PAYLOADS
    assert payloads["dos"] == PAYLOAD_NAMES


def test_the_vocabulary_lists_no_payload_and_the_codec_reads_the_table():
    assert not any(n.upper().startswith("PAYLOAD") or n.upper().startswith("MAVLINK_PAYLOAD") for n in dir(v))
    for name in PAYLOAD_NAMES:
        assert parse(f"benign-3-1-{name}-logdist-adaptive-random-30-95").payload == name
        assert Scenario(n_uav=3, n_bs=1, payload=name).payload == name
    assert Scenario(n_uav=3, n_bs=1).payload == DEFAULT_PAYLOAD == "image"
    with pytest.raises(ScenarioError, match=r"^field 'payload': 'audio' is not one of image, telemetry, video, mixed$"):
        parse("benign-3-1-audio-logdist-adaptive-random-30-95")
    with pytest.raises(ValidationError, match="unknown payload 'audio'; known: image, telemetry, video, mixed"):
        Scenario(n_uav=3, n_bs=1, payload="audio")
    assert describe("payload", "cic", view("5tuple"))[1].endswith("one of image, telemetry, video, mixed")


def test_unknown_names_are_one_line_errors():
    with pytest.raises(ValueError, match=r"^unknown payload 'x'; known: image, telemetry, video, mixed$"):
        check_payload("x")
    with pytest.raises(ValueError, match="unknown payload"):
        apps_of("x")
    with pytest.raises(ValueError, match=r"^unknown traffic app 'x'; registered: image, mavlink, video"):
        apps.app("x")


def test_register_refuses_bad_apps():
    class Nameless(TrafficApp):
        summary = "no name"

        def start_servers(self) -> None: ...

        def start_clients(self, t0_unix: float) -> None: ...

    with pytest.raises(ValueError, match="must match"):
        registry.register(Nameless)
    with pytest.raises(TypeError, match="is not a TrafficApp"):
        registry.register(dict)  # type: ignore[arg-type]

    class Twice(Nameless):
        name = "image"

    with pytest.raises(ValueError, match="'image' registered twice"):
        registry.register(Twice)
    assert apps.app("image") is ImageApp


def test_benign_traffic_builds_the_payloads_apps_in_the_rows_order(tmp_path):
    for payload, row in PAYLOADS.items():
        p = plan(f"benign-3-2-{payload}-logdist-adaptive-random-30-95", seed=1, windows=1)
        t = BenignTraffic(None, p, tmp_path, 5.0, options=AppOptions(mavlink_signing=True))
        assert [a.name for a in t.apps] == list(row)
        assert t.mavlink_signed == (payload in apps.MAVLINK_PAYLOADS)
        assert not BenignTraffic(None, p, tmp_path, 5.0).mavlink_signed  # signing off
        # nothing started: no client rows, no app logs (each app with a section reports its BSs)
        assert t.summary() == []
        streams = t.streams_summary()
        assert (streams is None) == (payload == "image")
        if streams is not None:
            assert set(streams) == set(row) - {"image"}
            assert all(set(section) == {"bs0", "bs1"} for section in streams.values())


def test_an_app_without_an_emulation_cannot_start_a_process(tmp_path):
    p = plan("benign-3-1-image-logdist-adaptive-random-30-95", seed=1, windows=1)
    ctx = AppContext(None, p, tmp_path, 5.0)
    assert ctx.pairs == [("bs0", "uav0"), ("bs0", "uav1"), ("bs0", "uav2")]
    with pytest.raises(RuntimeError, match="no emulation"):
        ctx.starter("uav0")
