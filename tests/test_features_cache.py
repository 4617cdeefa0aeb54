"""The content-hash feature cache: a miss computes and stores, a hit reads without computing, anything that
changes the numbers changes the key, and a corrupt or mismatched entry is recomputed, never trusted."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.corpus.types import Transcript, Word
from evalsuite.features import Recipe, extract, register_recipe
from evalsuite.features.base import RECIPES
from evalsuite.features.cache import default_cache_dir


@pytest.fixture()
def counting():
    calls = []

    def compute(audio, transcript, fps, n, opts):
        calls.append(opts)
        return np.full((4, 2), opts["scale"]) * audio.mono()[:4, None]

    register_recipe(Recipe(name="_test_counting", native_fps=10.0, dim=2, reproduces="test", quirks="none",
                           compute=compute, params={"scale": 1.0}))
    yield calls
    RECIPES.pop("_test_counting", None)


def audio(seed=0):
    return (np.random.default_rng(seed).uniform(-1, 1, 100), 8000)


def entries(folder):
    return sorted(folder.rglob("*.npz"))


def test_miss_then_hit(tmp_path, counting):
    a = extract("_test_counting", audio(), cache_dir=tmp_path)
    b = extract("_test_counting", audio(), cache_dir=tmp_path)
    assert len(counting) == 1 and len(entries(tmp_path)) == 1
    np.testing.assert_array_equal(a, b)
    extract("_test_counting", audio(), cache_dir=tmp_path, fps=20)            # resampling is after the cache
    assert len(counting) == 1


def test_the_key_covers_audio_parameters_and_transcript(tmp_path, counting):
    extract("_test_counting", audio(), cache_dir=tmp_path)
    extract("_test_counting", audio(1), cache_dir=tmp_path)
    extract("_test_counting", audio(), cache_dir=tmp_path, scale=2.0)
    extract("_test_counting", audio(), cache_dir=tmp_path, transcript=Transcript((Word("a", 0, 1),)))
    assert len(counting) == 4 and len(entries(tmp_path)) == 4
    x, rate = audio()
    extract("_test_counting", (x, rate + 1), cache_dir=tmp_path)                 # same samples, other rate
    assert len(counting) == 5


def test_file_audio_is_keyed_by_its_bytes(tmp_path, counting):
    from evalsuite.audio import write_wav

    path = tmp_path / "a.wav"
    write_wav(path, audio()[0], 8000)
    extract("_test_counting", path, cache_dir=tmp_path / "c")
    write_wav(path, audio(2)[0], 8000)                                           # same name, new content
    extract("_test_counting", path, cache_dir=tmp_path / "c")
    assert len(counting) == 2


@pytest.mark.parametrize("damage", ["truncate", "garbage", "other_array"])
def test_a_corrupt_entry_is_recomputed_and_replaced(tmp_path, counting, damage):
    good = extract("_test_counting", audio(), cache_dir=tmp_path)
    (entry,) = entries(tmp_path)
    if damage == "truncate":
        entry.write_bytes(entry.read_bytes()[:50])
    elif damage == "garbage":
        entry.write_bytes(b"\x00" * 300)
    else:                                           # a valid file whose data does not match its checksum
        with np.load(entry) as z:
            key, checksum = z["key"], z["sha256"]
        np.savez(entry, data=np.zeros((4, 2)), key=key, sha256=checksum)
    again = extract("_test_counting", audio(), cache_dir=tmp_path)
    assert len(counting) == 2
    np.testing.assert_array_equal(again, good)
    extract("_test_counting", audio(), cache_dir=tmp_path)                      # the entry was rewritten
    assert len(counting) == 2


def test_no_cache_writes_nothing(tmp_path, counting):
    extract("_test_counting", audio(), cache=False, cache_dir=tmp_path)
    extract("_test_counting", audio(), cache=False, cache_dir=tmp_path)
    assert len(counting) == 2 and entries(tmp_path) == []


def test_default_folder(monkeypatch, tmp_path):
    monkeypatch.delenv("EVALSUITE_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / "evalsuite" / "features"
    monkeypatch.setenv("EVALSUITE_CACHE_DIR", str(tmp_path / "x"))
    assert default_cache_dir() == tmp_path / "x"


def test_text_recipes_are_keyed_by_rate_and_frame_count(tmp_path):
    t = Transcript((Word("a", 0.0, 1.0), Word("b", 2.0, 3.0)))
    short = extract("text_timing", None, transcript=t, fps=10, n_frames=15, cache_dir=tmp_path)
    full = extract("text_timing", None, transcript=t, fps=10, n_frames=30, cache_dir=tmp_path)
    assert short.shape == (15, 5) and full.shape == (30, 5) and full[25, 2] == 10
    np.testing.assert_array_equal(full[:15], short)
    assert extract("text_timing", None, transcript=t, fps=20, n_frames=30, cache_dir=tmp_path)[25, 2] == 0
    assert len(entries(tmp_path)) == 3
