"""The payloads: the scenario's `payload` axis, each a named composition of traffic apps.

`PAYLOADS` is the one table of payloads (append a row to add one; an app name is a registered
`TrafficApp`'s, `uavcas.traffic.apps`). The scenario codec, `Scenario.payload` and the data
dictionary read the names from here; the payloads that carry MAVLink are derived from the apps'
own `carries_mavlink` (`uavcas.traffic.apps.MAVLINK_PAYLOADS`). This module imports nothing of
uavcas, so the scenario's records can validate a payload without loading any app.

An app's processes start in the row's order (servers first, then clients at t0), so the order
of a row is part of the payload.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator

# image: the paper's HTTP image fetches; telemetry: MAVLink v2 alone; video: MAVLink + H.264 over
# RTP; mixed: MAVLink + video + images. The order of the rows is the names' order everywhere.
PAYLOADS: dict[str, tuple[str, ...]] = {
    "image": ("image",),
    "telemetry": ("mavlink",),
    "video": ("mavlink", "video"),
    "mixed": ("mavlink", "video", "image"),
}
PAYLOAD_NAMES: tuple[str, ...] = tuple(PAYLOADS)
DEFAULT_PAYLOAD = "image"  # a scenario that names none, and a hand-made plan without a scenario


def _unknown(name: object) -> str:
    return f"unknown payload {name!r}; known: {', '.join(PAYLOADS)}"


def check_payload(name: str) -> str:
    """`name` if it is a payload of the table, else a one-line ValueError listing them."""
    if name not in PAYLOADS:
        raise ValueError(_unknown(name))
    return name


def apps_of(payload: str) -> tuple[str, ...]:
    """The names of the apps a payload runs, in the order they start."""
    try:
        return PAYLOADS[payload]
    except KeyError:
        raise ValueError(_unknown(payload)) from None


# A scenario's payload field: a str checked against the table when the model is validated.
PayloadName = Annotated[str, AfterValidator(check_payload)]
