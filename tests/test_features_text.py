"""Text features per frame on a hand-made transcript against hand-computed values: Gesticulator's timing features
(its decisecond convention and continuous seconds), vocabulary ids, the hash and FastText embeddings."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError
from evalsuite.features import extract
from evalsuite.features.embeddings import FastTextEmbedder, frame_embeddings, get_embedder
from evalsuite.features.text import Vocabulary, count_syllables, timing_features, word_ids

# "hello" 0.1-0.5 s (2 syllables), silence, "big" 0.6-1.2 s (1), "banana." 1.2-1.5 s (3)
T = Transcript((Word("hello", 0.1, 0.5), Word("big", 0.6, 1.2), Word("banana.", 1.2, 1.5)))


def test_gesticulator_timing_at_10_fps_by_hand():
    got = timing_features(T, 10, 16)
    expected = np.zeros((16, 5))
    # hello: deciseconds 1..4 (s=1, e=5, d=4): elapsed 1..4, remaining 4..1, progress elapsed/4, 2/4 syl per ds
    for k, el in zip(range(1, 5), range(1, 5)):
        expected[k] = [el, 5 - k, 4, el / 4, 2 / 4]
    # big: 6..11 (d=6), 1 syllable
    for k in range(6, 12):
        expected[k] = [k + 1 - 6, 12 - k, 6, (k + 1 - 6) / 6, 1 / 6]
    # banana.: 12..14 (d=3), 3 syllables
    for k in range(12, 15):
        expected[k] = [k + 1 - 12, 15 - k, 3, (k + 1 - 12) / 3, 3 / 3]
    np.testing.assert_allclose(got, expected, atol=1e-12)


def test_gesticulator_timing_at_20_fps_repeats_each_decisecond_frame():
    np.testing.assert_array_equal(timing_features(T, 20, 32), np.repeat(timing_features(T, 10, 16), 2, axis=0))


def test_gesticulator_truncates_times_to_whole_deciseconds():
    t = Transcript((Word("go", 0.57, 2.39),))        # int(5.7) = 5 .. int(23.9) = 23, not rounded
    f = timing_features(t, 10, 25)
    assert f[4].tolist() == [0] * 5 and f[5, :3].tolist() == [1, 18, 18]
    assert f[22, 1] == 1 and f[23].tolist() == [0] * 5


def test_timing_in_seconds_by_hand():
    got = timing_features(T, 20, 32, convention="seconds")
    # frame 4 = 0.2 s in hello: elapsed 0.1, remaining 0.3, duration 0.4, progress 0.25, 2 / 0.4 = 5 syl/s
    np.testing.assert_allclose(got[4], [0.1, 0.3, 0.4, 0.25, 5.0], atol=1e-12)
    np.testing.assert_allclose(got[25], [0.05, 0.25, 0.3, 1 / 6, 10.0], atol=1e-12)   # 1.25 s in banana.
    assert got[11].tolist() == [0.0] * 5 and got[31].tolist() == [0.0] * 5              # silence
    with pytest.raises(InputError, match="convention: unknown timing convention 'minutes'"):
        timing_features(T, 20, convention="minutes")


def test_text_timing_recipe_without_audio_covers_the_transcript_or_n_frames():
    assert extract("text_timing", None, transcript=T, cache=False).shape == (30, 5)
    assert extract("text_timing", None, transcript=T, fps=10, n_frames=40, cache=False).shape == (40, 5)
    rate = 16000
    assert extract("text_timing", (np.zeros(2 * rate), rate), transcript=T, cache=False).shape == (40, 5)


@pytest.mark.parametrize("word,n", [("a", 1), ("the", 1), ("hello", 2), ("banana.", 3), ("make", 1), ("table", 2),
                                    ("jumped", 1), ("wanted", 2), ("boxes", 2), ("everything", 4), ("Beautiful", 3),
                                    ("gesture", 2), ("", 0)])
def test_syllable_counts(word, n):
    assert count_syllables(word) == n


def test_vocabulary_ids_per_frame():
    other = Transcript((Word("Big", 0.0, 0.5), Word("dog", 0.5, 0.9)))
    vocab = Vocabulary.build([T, other])
    assert vocab.words == ("big", "banana", "dog", "hello")            # by count, then alphabetical
    ids = word_ids(T, vocab, 10, 16)
    assert ids.tolist() == [0, 5, 5, 5, 5, 0, 2, 2, 2, 2, 2, 2, 3, 3, 3, 0]
    assert vocab.index("zebra") == 1 and len(vocab) == 6


def test_vocabulary_round_trip_and_bad_file(tmp_path):
    vocab = Vocabulary.build([T], max_size=2)
    vocab.save(tmp_path / "v.json")
    assert Vocabulary.load(tmp_path / "v.json") == vocab
    (tmp_path / "bad.json").write_text('{"words": [1, 2]}')
    with pytest.raises(InputError, match=r"bad\.json: words: expected a list of words"):
        Vocabulary.load(tmp_path / "bad.json")


def test_hash_embedding_is_deterministic_unit_ish_and_silence_is_constant():
    a = get_embedder("hash").embed(["Up", "up.", "banana"])
    np.testing.assert_array_equal(a[0], a[1])                            # normalised words
    assert abs(np.linalg.norm(a[2]) - 1) < 0.3
    # the same numbers in a fresh embedder (no state), and a pinned value (stable across machines)
    b = get_embedder("hash").embed(["banana"])
    np.testing.assert_array_equal(a[2], b[0])
    assert get_embedder("hash", seed=1).embed(["banana"])[0][0] != b[0][0]
    f = frame_embeddings(T, 10, 16, model="hash", silence=-15)
    assert f.shape == (16, 128)
    assert np.all(f[0] == -15) and np.all(f[5] == -15)
    np.testing.assert_array_equal(f[1], get_embedder("hash").vector("hello"))


def test_fasttext_vec_file(tmp_path):
    path = tmp_path / "tiny.vec"
    path.write_text("3 4\nhello 1 0 0 0\nbig 0 1 0 0\nBanana 0 0 1 0.5\n", encoding="utf-8")
    emb = FastTextEmbedder(path)
    v = emb.embed(["Hello", "banana.", "Banana", "zebra"])
    np.testing.assert_array_equal(v, [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 0]])
    out = extract("words_model", None, transcript=T, fps=10, cache=False, model=f"fasttext:{path}")
    assert out.shape == (15, 4) and out[6].tolist() == [0, 1, 0, 0]
    (tmp_path / "bad.vec").write_text("3 4\nhello 1 0\n")
    with pytest.raises(InputError, match=r"bad\.vec:2: expected 4 numbers after the word, got 2"):
        FastTextEmbedder(tmp_path / "bad.vec").embed(["hello"])
    with pytest.raises(InputError, match="model: unknown word-embedding model 'glove'"):
        get_embedder("glove")
