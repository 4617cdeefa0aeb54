"""Networks of "Moving fast and slow" (Kucherenko et al., IVA 2019 / IJHCI 2021), re-implemented from the paper.

Three systems share one speech network (paper §3.2, Fig. 2; §4.3.1):

- **Aud2Pose** (the Hasegawa et al. 2018 baseline): a window of speech frames (30 past, the current one,
  30 future) -> three fully connected layers (256, ReLU, batch normalisation, dropout 0.1) -> a
  bidirectional GRU (256) read to its last state -> a linear output layer -> the pose of the window's
  centre frame, with the pose's velocity as a second training target (multitask regularisation).
- **Aud2Motion**: the same layers but a unidirectional, causal GRU that returns the whole sequence: one pose
  per input frame, trained on 100-frame chunks without the velocity target.
- **Aud2Repr2Pose**: MotionE/MotionD, a denoising autoencoder of the pose with one hidden (bottleneck) layer,
  is learned first (Gaussian input noise of 0.05 x each feature's std, MSE, Adam 1e-3, batch 128); then
  SpeechE, the Aud2Pose network with the bottleneck code as its target, maps speech to the representation,
  and MotionD decodes it.

:class:`SpeechNet` has two forms: ``windowed`` (the paper's: one window per output frame) and ``sequence``
(a deviation for CPU budgets: the bidirectional GRU runs once over a chunk and outputs every frame, so each
frame's context is the chunk instead of a fixed 61-frame window; ~60x less computation).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn

__all__ = ["SpeechNetConfig", "SpeechNet", "MotionDAE", "DEVIATIONS", "with_past_frames"]

DEVIATIONS = (
    "Sizes are options; the CPU preset narrows the 256-unit layers.",
    "Optional sequence-level form of the speech network (one bidirectional GRU pass per chunk) instead of "
    "one 61-frame window per output frame, for CPU training budgets; the plug-ins default to it (form=windowed "
    "gives the paper's).",
    "Motion is the corpus skeleton's joint rotations (exponential maps) or positions, not the paper's 64 "
    "Japanese-corpus joint positions + velocities (384-d).",
)


@dataclass(frozen=True)
class SpeechNetConfig:
    input_dim: int
    output_dim: int
    context: int = 30            # frames before and after the centre (61-frame windows)
    width: int = 256
    n_dense: int = 3
    dropout: float = 0.1
    bidirectional: bool = True   # False for Aud2Motion (causal)
    form: str = "windowed"       # "windowed" (one window per frame) or "sequence" (per chunk)
    velocity_target: bool = True  # Aud2Pose's multitask velocity output
    past_frames: int = 1         # sequence form: each frame's input with the frames before it (1: the frame alone)

    def to_dict(self) -> dict:
        return asdict(self)


class _FrameDense(nn.Module):
    """TimeDistributed Dense -> BatchNorm -> ReLU -> Dropout over (B, T, F)."""

    def __init__(self, n_in: int, n_out: int, dropout: float):
        super().__init__()
        self.linear = nn.Linear(n_in, n_out)
        self.norm = nn.BatchNorm1d(n_out)
        self.drop = nn.Dropout(dropout)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, t, _ = x.shape
        h = self.norm(self.linear(x).reshape(b * t, -1)).reshape(b, t, -1)
        return self.drop(torch.relu(h))


def with_past_frames(x: torch.Tensor, k: int) -> torch.Tensor:
    """(B, T, F) -> (B, T, F k): for each feature, its values at frames t-k+1 .. t (zeros before the first frame);
    k = 1 returns ``x``. Causal: frame t's input holds nothing after t."""
    if k <= 1:
        return x
    b, t, _ = x.shape
    return nn.functional.pad(x, (0, 0, k - 1, 0)).unfold(1, k, 1).reshape(b, t, -1)


class SpeechNet(nn.Module):
    """windowed: (B, 2C+1, F) -> (B, out [x2 with velocity]); sequence: (B, T, F) -> (B, T, out [x2])."""

    def __init__(self, config: SpeechNetConfig):
        super().__init__()
        self.config = c = config
        if c.form not in ("windowed", "sequence"):
            raise ValueError(f"form must be 'windowed' or 'sequence', got {c.form!r}")
        if c.past_frames < 1 or (c.form == "windowed" and c.past_frames > 1):
            raise ValueError(f"past_frames must be at least 1, and 1 in the windowed form; got {c.past_frames}")
        dims = [c.input_dim * c.past_frames] + [c.width] * c.n_dense
        self.dense = nn.Sequential(*[_FrameDense(a, b, c.dropout) for a, b in zip(dims, dims[1:])])
        self.gru = nn.GRU(c.width, c.width, batch_first=True, bidirectional=c.bidirectional)
        rec = c.width * (2 if c.bidirectional else 1)
        self.post_norm = nn.BatchNorm1d(rec)
        self.post_drop = nn.Dropout(c.dropout)
        self.out = nn.Linear(rec, c.output_dim * (2 if c.velocity_target else 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        c = self.config
        if c.form == "sequence":
            x = with_past_frames(x, c.past_frames)
        h = self.dense(x)
        seq, last = self.gru(h)
        if c.form == "windowed":
            # the last state of each direction: the forward GRU has read the window left to right, the
            # backward one right to left (Keras' Bidirectional(return_sequences=False) concatenates these)
            z = torch.cat([last[0], last[1]], dim=-1) if c.bidirectional else last[0]
            return self.out(self.post_drop(torch.relu(self.post_norm(z))))
        b, t, _ = seq.shape
        z = self.post_norm(seq.reshape(b * t, -1)).reshape(b, t, -1)
        return self.out(self.post_drop(torch.relu(z)))


class MotionDAE(nn.Module):
    """MotionE / MotionD: x (B, D) -> tanh(x W1 + b1) = code (B, H) -> tanh(code W2 + b2) (B, D).

    Inputs are standardised to mean 0 and maximum absolute value 1 (paper §4.2), so tanh can reach them."""

    feature_std: torch.Tensor

    def __init__(self, pose_dim: int, code_dim: int, noise: float = 0.05, velocities: bool = False):
        super().__init__()
        width = pose_dim * (2 if velocities else 1)
        self.encoder = nn.Linear(width, code_dim)
        self.decoder = nn.Linear(code_dim, width)
        self.noise = noise
        self.pose_dim = pose_dim
        self.register_buffer("feature_std", torch.ones(width))

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.encoder(x))

    def decode(self, code: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.decoder(code))

    def pose(self, code: torch.Tensor) -> torch.Tensor:
        """The decoded pose (B, D) without the velocities, when the autoencoder also learned those."""
        return self.decode(code)[..., :self.pose_dim]

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.training and self.noise > 0:
            x = x + torch.randn_like(x) * self.noise * self.feature_std
        return self.decode(self.encode(x))
