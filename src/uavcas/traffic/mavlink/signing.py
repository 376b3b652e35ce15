"""MAVLink v2 message signing on the endpoints: the defence against forged commands.

MAVLink 2 signing (the MAVLink guide, "Message Signing"; pymavlink's `MAVLink.signing`): a
signed frame carries a 13-byte signature block after its CRC: link id (1 byte), a 48-bit
timestamp in 10 us units since 2015-01-01 00:00:00 UTC, and the first 6 bytes of
SHA-256(secret key + header + payload + CRC + link id + timestamp). A receiver holding the
key accepts a frame whose signature matches and whose timestamp is newer than the last one of
its (link id, sysid, compid) stream (a new stream: no more than a minute behind its own clock),
and rejects every other frame unless its `allow_unsigned_callback` lets it through: pymavlink
raises "Invalid signature", which our robust parsers turn into BAD_DATA, so the endpoint never
sees the message and sends no answer. Which unsigned messages pass is ArduPilot's rule
(libraries/GCS_MAVLink/GCS_Signing.cpp, `accept_unsigned_callback`): RADIO_STATUS only, the one
a radio modem injects itself.

The key: 32 bytes per run, SHA-256 of a fixed tag, the plan's seed and its config string
(`signing_key`): the same run signs with the same key (a twin is reproducible), two runs of one
dataset differ. The runner hands it to the ground stations' and autopilots' specs only (the
attacker's sender has no key); run.json records only whether signing was on, never the key. A
reader who knows a run's seed and config can derive it: it protects the emulated link against
the emulated attacker, not a secret of the dataset.
"""

from __future__ import annotations

import hashlib
import time

from pydantic import BaseModel, ConfigDict, Field
from pymavlink.dialects.v20 import common

KEY_TAG = b"uavcas/mavlink-signing/v1"
SIGNING_EPOCH_UNIX = 1420070400  # 2015-01-01T00:00:00Z, the origin of MAVLink 2 signing timestamps
TICKS_PER_S = 100_000  # signing timestamps count 10 us
UNSIGNED_ALLOWED = ("RADIO_STATUS",)  # ArduPilot GCS_Signing.cpp: accept_unsigned_callback


class SigningSpec(BaseModel):
    """What an endpoint needs to sign and check: the secret key (hex) and its link id."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    key_hex: str = Field(pattern=r"^[0-9a-f]{64}$")
    link_id: int = Field(default=0, ge=0, le=255)

    @property
    def key(self) -> bytes:
        return bytes.fromhex(self.key_hex)


def signing_key(seed: int, config: str) -> bytes:
    """The run's 32-byte key from its plan's seed and config string (module docstring)."""
    h = hashlib.sha256(KEY_TAG)
    h.update(b"\0" + str(int(seed)).encode() + b"\0" + config.encode())
    return h.digest()


def signing_spec(seed: int, config: str) -> SigningSpec:
    return SigningSpec(key_hex=signing_key(seed, config).hex())


def timestamp_now() -> int:
    """The current signing timestamp (10 us ticks since 2015-01-01 UTC)."""
    return int((time.time() - SIGNING_EPOCH_UNIX) * TICKS_PER_S)


def new_signing_state(spec: SigningSpec):
    """A pymavlink `MAVLinkSigning` holding the key: signs what its MAVLink object sends and
    rejects unsigned or wrongly signed frames it parses (shareable between parsers)."""
    state = common.MAVLinkSigning()
    state.secret_key = spec.key
    state.link_id = spec.link_id
    state.timestamp = timestamp_now()
    state.sign_outgoing = True
    allowed = frozenset(getattr(common, f"MAVLINK_MSG_ID_{name}") for name in UNSIGNED_ALLOWED)
    state.allow_unsigned_callback = lambda mav, msg_id: msg_id in allowed
    return state


def enable(mav, spec: SigningSpec | None) -> None:
    """Turn signing on for one pymavlink MAVLink object (nothing when `spec` is None)."""
    if spec is not None:
        mav.signing = new_signing_state(spec)
