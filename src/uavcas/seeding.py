"""Named, independent random streams from one integer seed: the only place an RNG is built.

A stream is addressed by the run's (or the caller's) integer seed and a path of keys:

    generator(seed, "http-client", k)  ->  Generator(PCG64(SeedSequence([seed, crc32("http-client"), k])))

Derivation, frozen (changing it changes every plan and dataset; `tests/test_seeding.py` records values):

* a `str` key becomes `zlib.crc32(key.encode("ascii"))`, a 32-bit word that is the same in every
  process and on every machine (Python's `hash()` is salted per process, so it is never used);
* an `int` key (>= 0) is used as it is: the twin's and the channel's numbered streams
  (`twin/plan.py`, `channel/model.py`), the calibration splits' keys and the campaign's run index
  predate the names and keep their numbers, so their plans stay byte-identical;
* the seed and the keys, in order, are the entropy of one numpy `SeedSequence`, which hashes the
  whole list: [seed, a] and [seed, b] give unrelated streams, so do [s, a, b] and [s, b, a];
* no key at all is `SeedSequence(seed)`, i.e. exactly `numpy.random.default_rng(seed)`.

Why the keys extend the entropy rather than numpy's `spawn_key`: the plans' streams were already
built as `SeedSequence([seed, stream])` and mobility's as `SeedSequence([seed, crc32(kind)])`;
this is that rule, named, so no existing plan changes. A stream's own sub-streams (one per UAV
inside a mission) still come from `SeedSequence.spawn`, numpy's rule for children.

Names are ASCII and say whose stream it is (`image-sizes`, `replayer`); a new consumer takes a
new name, never another's, so adding a stream never shifts the numbers another one draws.
scikit-learn and LightGBM estimators keep their integer `random_state` (their API takes an int
and builds its own RandomState); `uavcas.ids` passes the seed through as it is, and its
early-stopping base builds `default_rng(random_state)` itself because scikit-learn allows None
(fresh entropy), which a named stream refuses (`tests/test_seeding.py` lists these exceptions).
"""

from __future__ import annotations

import zlib

import numpy as np

Key = str | int
SeedLike = int | np.random.SeedSequence


def stream_key(key: Key) -> int:
    """The 32-bit word (or the non-negative int) a key contributes to the entropy (module docstring)."""
    if isinstance(key, str):
        if not key or not key.isascii():
            raise ValueError(f"stream name {key!r} must be non-empty ASCII")
        return zlib.crc32(key.encode("ascii"))
    if isinstance(key, (bool, np.bool_)) or not isinstance(key, (int, np.integer)) or key < 0:
        raise ValueError(f"stream key must be a name or a non-negative integer, got {key!r}")
    return int(key)


def _root(seed: int) -> int:
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def seed_sequence(seed: int, *keys: Key) -> np.random.SeedSequence:
    """The SeedSequence of stream `keys` of `seed` (module docstring)."""
    root = _root(seed)
    if not keys:
        return np.random.SeedSequence(root)
    return np.random.SeedSequence([root, *(stream_key(k) for k in keys)])


def as_seed_sequence(seed: SeedLike) -> np.random.SeedSequence:
    """A SeedSequence as it is (a parent's child), an integer seed as its root stream."""
    if isinstance(seed, np.random.SeedSequence):
        return seed
    return seed_sequence(seed)


def generator(seed: SeedLike, *keys: Key) -> np.random.Generator:
    """A PCG64 Generator on stream `keys` of `seed`; a SeedSequence (a spawned child) takes no keys."""
    if isinstance(seed, np.random.SeedSequence):
        if keys:
            raise ValueError("a SeedSequence seed takes no stream keys (name the stream from its integer seed)")
        return np.random.Generator(np.random.PCG64(seed))
    return np.random.Generator(np.random.PCG64(seed_sequence(seed, *keys)))


def child_seed(seed: int, *keys: Key) -> int:
    """A 32-bit integer seed for a consumer that takes an int (a sub-model, ffmpeg, a campaign run)."""
    return int(seed_sequence(seed, *keys).generate_state(1, np.uint32)[0])
