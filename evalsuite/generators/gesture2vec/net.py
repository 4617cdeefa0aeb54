"""Gesture2Vec networks (Yazdian, Chen and Lim, IROS 2022), re-implemented from the paper (§3-4).

1. **Frame-level denoising autoencoder** (§4.1): one linear layer to a 40-d bottleneck with tanh (encoder),
   one linear layer back (decoder); Gaussian input noise of std 0.1 and dropout 0.2 during training.
2. **VQ-DVAE** over chunks of 30 frames (stride 10 in training) of the 40-d latent pose and its derivative
   (80 features per frame, §4.2): a 2-layer bidirectional GRU encoder (hidden 200) whose last states give
   z in R^400; z is replaced by its nearest of K = 300 codebook vectors; a 2-layer bidirectional GRU decoder
   reconstructs the chunk from the code, or with ``conditioned_decoder`` (the paper's conditioned decoder, §4.3;
   the original code's ``autoencoder_conditioned``) a GRU that reads the code and its own previous output frame
   at every step, starting from the frame before the chunk. Loss (eq. 4): reconstruction + ||sg[z] - e||^2 + beta ||z - sg[e]||^2,
   gradients passed straight through the quantiser.
3. **Translation** (§3.3): a 2-layer bidirectional GRU encoder over word embeddings and a GRU decoder with
   Bahdanau (additive) attention that emits one code index per chunk, trained with cross-entropy.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn

from evalsuite.generators.gesture2vec.info import DEVIATIONS

__all__ = ["G2VConfig", "FrameDAE", "VQDVAE", "Translator", "DEVIATIONS"]


@dataclass(frozen=True)
class G2VConfig:
    pose_dim: int
    text_dim: int
    latent_dim: int = 40
    chunk: int = 30
    stride: int = 10
    vq_hidden: int = 200
    vq_layers: int = 2
    codebook: int = 300
    commitment: float = 0.25
    chunks_per_window: int = 4      # translation windows of 4 x 30 frames
    text_hidden: int = 200
    noise: float = 0.1
    dropout: float = 0.2
    aligned: bool = True            # the decoder also reads the words of its chunk and the one before (a deviation)
    conditioned_decoder: bool = False   # the VQ-DVAE decoder is fed its last output frame (the paper's §4.3)

    def to_dict(self) -> dict:
        return asdict(self)


class FrameDAE(nn.Module):
    """(B, D) -> tanh(Linear) -> (B, latent) -> Linear -> (B, D)."""

    def __init__(self, c: G2VConfig):
        super().__init__()
        self.encoder = nn.Sequential(nn.Linear(c.pose_dim, c.latent_dim), nn.Tanh())
        self.decoder = nn.Linear(c.latent_dim, c.pose_dim)
        self.noise, self.drop = c.noise, nn.Dropout(c.dropout)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.training:
            x = self.drop(x + torch.randn_like(x) * self.noise)
        return self.decoder(self.encoder(x))


class VQDVAE(nn.Module):
    """(B, chunk, 2*latent) -> code index (B,), reconstruction (B, chunk, 2*latent)."""

    def __init__(self, c: G2VConfig):
        super().__init__()
        self.c = c
        feat = 2 * c.latent_dim
        self.encoder = nn.GRU(feat, c.vq_hidden, c.vq_layers, batch_first=True, bidirectional=True)
        self.code_dim = 2 * c.vq_hidden
        self.codebook = nn.Embedding(c.codebook, self.code_dim)
        nn.init.uniform_(self.codebook.weight, -1.0 / c.codebook, 1.0 / c.codebook)
        if c.conditioned_decoder:   # one direction: each step reads the code and the frame it produced last
            self.decoder = nn.GRU(self.code_dim + feat, c.vq_hidden, c.vq_layers, batch_first=True)
            self.out = nn.Linear(c.vq_hidden, feat)
        else:
            self.decoder = nn.GRU(self.code_dim, c.vq_hidden, c.vq_layers, batch_first=True, bidirectional=True)
            self.out = nn.Linear(2 * c.vq_hidden, feat)

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        _, h = self.encoder(x)                    # (layers * 2, B, H)
        return torch.cat([h[-2], h[-1]], dim=-1)  # last layer, both directions -> (B, 2H)

    def quantise(self, z: torch.Tensor) -> torch.Tensor:
        return torch.cdist(z, self.codebook.weight).argmin(dim=-1)

    def decode(self, e: torch.Tensor, previous: torch.Tensor | None = None) -> torch.Tensor:
        """Codes ``(B, code_dim)`` -> chunks ``(B, chunk, 2*latent)``. The conditioned decoder starts from
        ``previous`` ``(B, 2*latent)``, the frame before each chunk (zeros when None), and is fed its own output."""
        if not self.c.conditioned_decoder:
            seq, _ = self.decoder(e.unsqueeze(1).expand(-1, self.c.chunk, -1).contiguous())
            return self.out(seq)
        frame = torch.zeros(len(e), self.out.out_features, dtype=e.dtype) if previous is None else previous
        state, frames = None, []
        for _ in range(self.c.chunk):
            seq, state = self.decoder(torch.cat([e, frame], dim=-1).unsqueeze(1), state)
            frame = self.out(seq[:, 0])
            frames.append(frame)
        return torch.stack(frames, dim=1)

    def decode_sequence(self, e: torch.Tensor, start: torch.Tensor | None = None) -> torch.Tensor:
        """Codes of consecutive chunks ``(N, code_dim)`` -> their frames ``(N, chunk, 2*latent)``; the conditioned
        decoder carries each chunk's last frame into the next, from ``start`` ``(2*latent,)`` (zeros when None)."""
        if not self.c.conditioned_decoder:
            return self.decode(e)
        frame, chunks = (None if start is None else start.reshape(1, -1)), []
        for k in range(len(e)):
            chunks.append(self.decode(e[k:k + 1], frame))
            frame = chunks[-1][:, -1]
        return torch.cat(chunks) if chunks else self.decode(e)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        z = self.encode(x)
        idx = self.quantise(z)
        e = self.codebook(idx)
        codebook_loss = nn.functional.mse_loss(e, z.detach())
        commit_loss = nn.functional.mse_loss(z, e.detach())
        e_st = z + (e - z).detach()  # straight-through estimator
        previous = None
        if self.c.conditioned_decoder:   # the frame before the chunk: latent - its difference, that difference
            latent, diff = x[:, 0].split(self.c.latent_dim, dim=-1)
            previous = torch.cat([latent - diff, diff], dim=-1)
        recon = self.decode(e_st, previous)
        return recon, idx, codebook_loss + self.c.commitment * commit_loss


class Translator(nn.Module):
    """word features (B, W, text_dim + 1) with lengths -> logits over codes (B, N, K), teacher forced.

    With ``c.aligned`` decoding step k also reads ``aligned[:, k]`` (B, N, 2 (text_dim + 1)): the mean
    (embedding, position in chunk) of the words starting in chunk k and in chunk k - 1 (zeros when none), through
    a tanh layer, beside the attention context: a monotonic alignment that small corpora cannot learn from
    attention alone."""

    def __init__(self, c: G2VConfig):
        super().__init__()
        self.c = c
        h = c.text_hidden
        self.encoder = nn.GRU(c.text_dim + 1, h, 2, batch_first=True, bidirectional=True)
        self.code_embedding = nn.Embedding(c.codebook + 1, h)   # + start token
        self.attn_query = nn.Linear(h, h, bias=False)
        self.attn_keys = nn.Linear(2 * h, h, bias=False)
        self.attn_v = nn.Linear(h, 1, bias=False)
        a = h if c.aligned else 0
        self.align = nn.Linear(2 * (c.text_dim + 1), h) if c.aligned else None
        self.decoder = nn.GRUCell(h + 2 * h + a, h)
        self.init_state = nn.Linear(2 * h, h)
        self.out = nn.Linear(h + 2 * h + a, c.codebook)

    def _context(self, state, keys, memory, mask, aligned: torch.Tensor | None, k: int) -> torch.Tensor:
        context = self._attend(state, keys, memory, mask)
        if self.align is None or aligned is None:
            return context
        return torch.cat([context, torch.tanh(self.align(aligned[:, k]))], -1)

    def _attend(self, state: torch.Tensor, keys: torch.Tensor, memory: torch.Tensor,
                mask: torch.Tensor) -> torch.Tensor:
        score = self.attn_v(torch.tanh(self.attn_query(state).unsqueeze(1) + keys)).squeeze(-1)
        score = score.masked_fill(~mask, -1e9)
        weights = torch.softmax(score, dim=-1)
        return torch.bmm(weights.unsqueeze(1), memory).squeeze(1)

    def _encode(self, words: torch.Tensor, mask: torch.Tensor):
        memory, _ = self.encoder(words)
        memory = memory * mask.unsqueeze(-1)
        mean = memory.sum(1) / mask.sum(1, keepdim=True).clamp_min(1)
        return memory, self.attn_keys(memory), torch.tanh(self.init_state(mean))

    def forward(self, words: torch.Tensor, mask: torch.Tensor, targets: torch.Tensor,
                aligned: torch.Tensor | None = None) -> torch.Tensor:
        memory, keys, state = self._encode(words, mask)
        prev = torch.full((words.shape[0],), self.c.codebook, dtype=torch.long)
        logits = []
        for k in range(targets.shape[1]):
            context = self._context(state, keys, memory, mask, aligned, k)
            state = self.decoder(torch.cat([self.code_embedding(prev), context], -1), state)
            logits.append(self.out(torch.cat([state, context], -1)))
            prev = targets[:, k]
        return torch.stack(logits, 1)

    @torch.no_grad()
    def generate(self, words: torch.Tensor, mask: torch.Tensor, n: int,
                 generator: torch.Generator | None = None, temperature: float = 0.0,
                 aligned: torch.Tensor | None = None) -> torch.Tensor:
        """Greedy decoding (temperature 0) or sampling with a seeded generator -> (B, n) code indices."""
        memory, keys, state = self._encode(words, mask)
        prev = torch.full((words.shape[0],), self.c.codebook, dtype=torch.long)
        out = []
        for k in range(n):
            context = self._context(state, keys, memory, mask, aligned, k)
            state = self.decoder(torch.cat([self.code_embedding(prev), context], -1), state)
            logits = self.out(torch.cat([state, context], -1))
            if temperature > 0:
                prev = torch.multinomial(torch.softmax(logits / temperature, -1), 1, generator=generator)[:, 0]
            else:
                prev = logits.argmax(-1)
            out.append(prev)
        return torch.stack(out, 1)
