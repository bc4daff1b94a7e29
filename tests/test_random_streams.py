"""One registry of random streams: every generator simrig makes comes from it, keys never collide within a seed,
and the keys are the ones the documented outputs were drawn with."""

from __future__ import annotations

import ast
import zlib
from pathlib import Path

import numpy as np
import pytest

from simrig.seeding import ROOTS, STREAMS, RandomStreams, stream_generator, stream_sequence

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [p for folder in ("simrig", "tracker", "scenarios") for p in sorted((ROOT / folder).rglob("*.py"))]
MAKERS = {"default_rng", "SeedSequence", "RandomState"}
"""Calls that make a random generator; with any call into ``numpy.random`` or ``random`` (a global generator),
only :mod:`simrig.seeding` may make them."""


def _random_calls(path: Path) -> list[str]:
    """``file:line call`` of each call in ``path`` that makes a generator or draws from a global one."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if not isinstance(node, ast.Call):
            continue
        name = ast.unparse(node.func)
        if name.split(".")[-1] in MAKERS or name.startswith(("np.random.", "numpy.random.", "random.")):
            found.append(f"{path.relative_to(ROOT)}:{node.lineno} {name}")
    return found


def test_no_module_but_the_registry_makes_a_random_generator():
    found = [call for path in SOURCES if path.name != "seeding.py" for call in _random_calls(path)]
    assert found == []


def test_the_scan_finds_a_generator_made_outside_the_registry(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text("import numpy as np\nrng = np.random.default_rng(3)\nx = np.random.normal()\n")
    global ROOT
    saved, ROOT = ROOT, tmp_path
    try:
        assert _random_calls(planted) == ["planted.py:2 np.random.default_rng", "planted.py:3 np.random.normal"]
    finally:
        ROOT = saved


def test_every_stream_names_a_known_root_and_no_two_share_a_key_under_one_seed():
    assert {stream.root for stream in STREAMS.values()} <= set(ROOTS)
    for root in ROOTS.keys() - {"analysis", "fixed"}:  # analysis streams each run alone on the seed they are given
        keys = [(s.key, s.spawned) for s in STREAMS.values() if s.root == root]
        assert len(keys) == len(set(keys)), root


@pytest.mark.parametrize("seed", [0, 7, 2**31 - 1])
def test_the_keys_are_those_the_documented_outputs_were_drawn_with(seed):
    """Written out as the modules drew them before the registry: a changed key changes every documented number."""
    def first(sequence):
        return int(sequence.generate_state(1)[0])

    assert first(stream_sequence("traffic", seed)) == first(np.random.SeedSequence(seed, spawn_key=(0,)))
    assert first(stream_sequence("ego_pose", seed, 3)) == first(np.random.SeedSequence(seed, spawn_key=(7, 3)))
    assert first(stream_sequence("explain_orders", seed)) == first(np.random.SeedSequence(seed, spawn_key=(20,)))
    assert first(stream_sequence("collection_seeds", seed, 5)) == first(np.random.SeedSequence(seed,
                                                                                               spawn_key=(1, 5)))
    assert first(stream_sequence("search_tpe", seed, 4)) == first(np.random.SeedSequence([seed, zlib.crc32(b"tpe"),
                                                                                         4]))
    assert stream_generator("degraded_velocity", seed).random() == np.random.default_rng([seed, 2]).random()
    assert stream_generator("reid_pairs", seed).random() == np.random.default_rng(seed).random()
    assert stream_generator("planning_road").random() == np.random.default_rng(0).random()
    assert RandomStreams(seed).generator("sensor", 1, 2).random() == stream_generator("sensor", seed, 1, 2).random()


def test_a_stream_asked_for_with_the_wrong_seed_or_name_says_so():
    with pytest.raises(ValueError, match="'traffic' needs the scenario seed"):
        stream_sequence("traffic")
    with pytest.raises(ValueError, match="'planning_road' takes no seed"):
        stream_sequence("planning_road", 3)
    with pytest.raises(KeyError, match="unknown random stream 'noise'"):
        stream_generator("noise", 1)
    with pytest.raises(KeyError, match="unknown random stream 'collection_seeds'"):
        RandomStreams(1).generator("collection_seeds")  # a collection's stream is not a scenario run's
