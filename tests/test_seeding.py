"""uavcas.seeding: named streams, their frozen derivation, and that no other module builds an RNG."""

import ast
import zlib
from pathlib import Path

import numpy as np
import pytest

from uavcas import seeding

SRC = Path(__file__).resolve().parents[1] / "src" / "uavcas"

# Modules that may still build an RNG themselves, each for a reason the helper cannot cover.
BUILDS_ITS_OWN = {
    # scikit-learn's MLP takes a RandomState instance so that each partial_fit draws a new batch order
    "ids/classical.py": "RandomState",
    # a scikit-learn estimator's random_state may be None (fresh entropy), which a named stream refuses
    "ids/base.py": "default_rng",
    # the emulation benchmark's hand-made plans (random.Random): its recorded figures were measured on them
    "testing/handmade_plans.py": "Random",
}
RNG_CALLS = {"default_rng", "SeedSequence", "PCG64", "Generator", "RandomState", "Random"}


def test_same_seed_and_name_give_the_same_stream():
    a = seeding.generator(7, "http-client", 3).integers(0, 2**32, 50, dtype=np.uint64)
    b = seeding.generator(7, "http-client", 3).integers(0, 2**32, 50, dtype=np.uint64)
    assert np.array_equal(a, b)
    assert seeding.child_seed(7, "video-noise", 2) == seeding.child_seed(7, "video-noise", 2)


@pytest.mark.parametrize("other", [(8, "http-client", 3), (7, "http-clients", 3), (7, "http-client", 4),
                                   (7, "replayer", 3), (7, 3, "http-client"), (7, "http-client")])
def test_a_different_seed_name_index_or_order_gives_another_stream(other):
    a = seeding.generator(7, "http-client", 3).integers(0, 2**32, 8, dtype=np.uint64)
    assert not np.array_equal(a, seeding.generator(*other).integers(0, 2**32, 8, dtype=np.uint64))


def test_the_derivation_is_frozen():
    # recorded once; a change here changes every plan and dataset of every seed
    assert seeding.stream_key("http-client") == zlib.crc32(b"http-client") == 2814451088
    assert seeding.generator(7, "http-client", 3).integers(0, 2**32, 3, dtype=np.uint64).tolist() == \
        [1692983794, 149389827, 3788489872]
    assert seeding.child_seed(7, "video-noise", 2) == 4271259389
    ss = seeding.seed_sequence(7, "http-client", 3)
    assert ss.entropy == [7, 2814451088, 3] and ss.spawn_key == ()


def test_the_rule_is_the_one_the_plans_were_built_with():
    # twin/plan.py's numbered streams, mobility's crc32(kind), default_rng(seed): bit-for-bit
    for seed in (0, 1, 2**32 - 1, 2**40):
        assert np.array_equal(seeding.generator(seed, 3).random(4),
                              np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, 3]))).random(4))
        assert np.array_equal(seeding.generator(seed).random(4), np.random.default_rng(seed).random(4))
        assert seeding.child_seed(seed, 2) == int(np.random.SeedSequence([seed, 2]).generate_state(1, np.uint32)[0])
    mission = np.random.SeedSequence([5, zlib.crc32(b"spiral")])
    assert seeding.seed_sequence(5, "spiral").generate_state(4).tolist() == mission.generate_state(4).tolist()


def test_a_spawned_child_is_used_as_it_is():
    child = seeding.seed_sequence(3, "spiral").spawn(2)[1]
    assert seeding.as_seed_sequence(child) is child
    assert np.array_equal(seeding.generator(child).random(3), np.random.default_rng(child).random(3))
    with pytest.raises(ValueError, match="no stream keys"):
        seeding.generator(child, "x")


@pytest.mark.parametrize("seed, keys", [(-1, ()), (1.5, ()), (True, ()), (None, ()), ("3", ()),
                                        (1, ("",)), (1, ("vidéo",)), (1, (-2,)), (1, (1.0,))])
def test_bad_seeds_and_keys_are_refused(seed, keys):
    with pytest.raises(ValueError):
        seeding.generator(seed, *keys)


def test_no_other_module_builds_an_rng():
    found = {}
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel == "seeding.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(), rel)):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else None
                if name in RNG_CALLS:
                    found.setdefault(rel, set()).add(name)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                if "random" in mods:
                    found.setdefault(rel, set()).add("import random")
    allowed = {rel: {name} for rel, name in BUILDS_ITS_OWN.items()}
    allowed["testing/handmade_plans.py"].add("import random")
    assert found == allowed
