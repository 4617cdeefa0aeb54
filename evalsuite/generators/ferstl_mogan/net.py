"""Networks of the multi-objective adversarial gesture model of Ferstl, Neff and McDonnell (MIG 2019),
re-implemented from the paper (§4-7). Ferstl et al. published no code; sizes follow the paper's figures where it
gives them and are options everywhere.

- :class:`PhaseClassifier` (§4.2): per-frame joint velocities (x, y, z offsets of the arm joints) and pitch ->
  feed-forward input layer -> unidirectional LSTM -> bidirectional LSTM -> dropout -> batch normalisation ->
  a phase label per frame (4 classes in adversarial training: preparation, stroke, hold, other).
- :class:`Generator` (§5.1): 26 MFCC + F0 (+ seeded noise channels, see ``DEVIATIONS``) -> feed-forward 256
  (ReLU, dropout 0.3 in pre-training / 0.2 adversarial, batch normalisation) -> GRU 256 (dropout 0.5 / 0.2)
  -> linear -> x, y, z of every joint.
- :class:`SequenceDiscriminator` (Fig. 6 a): feed-forward input transformation -> dropout -> GRU -> sigmoid;
  used for the phase-structure (soft phase labels + pitch), motion-realism (positions + speech) and
  displacement (per-frame arm offsets) discriminators.
- :class:`MinibatchDiscriminator` (Fig. 6 b, eq. 2; Salimans et al. 2016): each frame's pose is projected by a
  trainable tensor W into 300 features; L1 distances to every other sequence of the batch give similarity
  features, appended before the feed-forward layers, so that repeated output across a batch is detectable.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn

__all__ = ["MoganConfig", "PhaseClassifier", "Generator", "SequenceDiscriminator", "MinibatchDiscriminator",
           "DEVIATIONS", "PHASES"]

PHASES = ("preparation", "stroke", "hold", "other")  # the paper's 4-class set for adversarial training

DEVIATIONS = (
    "Seeded noise channels are appended to the generator's speech input so that one model gives k different "
    "samples per segment (the paper's generator reads speech only).",
    "The phase-structure discriminator reads the phase classifier's class probabilities rather than hard labels, "
    "so that its gradient reaches the generator.",
    "Phase labels for training the classifier come from the synthetic speaker's per-frame labels or a documented "
    "heuristic labeller (wrist speed and acceleration), not from the authors' 3.8 h of hand annotation.",
    "Positions of the corpus skeleton's upper-body joints instead of the paper's 21 mocap joints; the MFCC/F0 "
    "come from evalsuite's ferstl_mfcc26_f0 recipe instead of openSMILE; sizes are options.",
)


@dataclass(frozen=True)
class MoganConfig:
    speech_dim: int = 27          # 26 MFCC + F0
    pose_dim: int = 63            # x, y, z of 21 joints in the paper
    arm_dim: int = 48             # x, y, z offsets of the 16 arm joints the classifier reads
    noise_dim: int = 8
    width: int = 256
    classifier_width: int = 128
    discriminator_width: int = 128
    minibatch_features: int = 300
    minibatch_kernel: int = 5
    n_phases: int = len(PHASES)
    sequence: int = 100           # 5 s at 20 fps

    def to_dict(self) -> dict:
        return asdict(self)


class PhaseClassifier(nn.Module):
    """(B, T, arm_dim + 1) velocities and pitch -> (B, T, n_phases) logits."""

    def __init__(self, c: MoganConfig, dropout: float = 0.3):
        super().__init__()
        h = c.classifier_width
        self.inp = nn.Linear(c.arm_dim + 1, h)
        self.lstm1 = nn.LSTM(h, h, batch_first=True)
        self.lstm2 = nn.LSTM(h, h, batch_first=True, bidirectional=True)
        self.drop = nn.Dropout(dropout)
        self.norm = nn.BatchNorm1d(2 * h)
        self.out = nn.Linear(2 * h, c.n_phases)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h, _ = self.lstm1(self.drop(self.inp(x)))
        h, _ = self.lstm2(self.drop(h))
        b, t, f = h.shape
        h = self.norm(self.drop(h).reshape(b * t, f)).reshape(b, t, f)
        return self.out(h)


class Generator(nn.Module):
    """(B, T, speech_dim) speech and (B, T, noise_dim) noise -> (B, T, pose_dim) positions (normalised)."""

    def __init__(self, c: MoganConfig):
        super().__init__()
        self.c = c
        self.inp = nn.Linear(c.speech_dim + c.noise_dim, c.width)
        self.norm = nn.BatchNorm1d(c.width)
        self.gru = nn.GRU(c.width, c.width, batch_first=True)
        self.out = nn.Linear(c.width, c.pose_dim)
        self.set_phase("pretrain")

    def set_phase(self, phase: str) -> None:
        """Dropout rates of the paper: (0.3, 0.5) in MSE pre-training, (0.2, 0.2) in adversarial training."""
        self.in_drop, self.rec_drop = (0.3, 0.5) if phase == "pretrain" else (0.2, 0.2)

    def forward(self, speech: torch.Tensor, noise: torch.Tensor) -> torch.Tensor:
        x = torch.relu(self.inp(torch.cat([speech, noise], -1)))
        x = nn.functional.dropout(x, self.in_drop, self.training)
        b, t, f = x.shape
        x = self.norm(x.reshape(b * t, f)).reshape(b, t, f)
        h, _ = self.gru(x)
        return self.out(nn.functional.dropout(h, self.rec_drop, self.training))


class SequenceDiscriminator(nn.Module):
    """(B, T, F) -> (B,) probability that the sequence is real (mean of per-frame logits through a sigmoid)."""

    def __init__(self, n_in: int, width: int, dropout: float = 0.2):
        super().__init__()
        self.inp = nn.Linear(n_in, width)
        self.drop = nn.Dropout(dropout)
        self.gru = nn.GRU(width, width, batch_first=True)
        self.out = nn.Linear(width, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h, _ = self.gru(self.drop(torch.relu(self.inp(x))))
        return self.out(h).mean(dim=(1, 2))  # logits; BCEWithLogits applies the sigmoid


class MinibatchDiscriminator(nn.Module):
    """(B, T, pose_dim) -> (B,) logits, with minibatch similarity features (eq. 2)."""

    def __init__(self, c: MoganConfig, dropout: float = 0.2):
        super().__init__()
        self.kernels = c.minibatch_features // c.minibatch_kernel
        self.kernel = c.minibatch_kernel
        self.W = nn.Parameter(torch.randn(c.pose_dim, self.kernels * self.kernel) * 0.1)
        self.ff = nn.Sequential(nn.Linear(c.pose_dim + self.kernels, c.discriminator_width), nn.ReLU(),
                                nn.Dropout(dropout), nn.Linear(c.discriminator_width, c.discriminator_width),
                                nn.ReLU(), nn.Linear(c.discriminator_width, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, t, _ = x.shape
        m = (x @ self.W).reshape(b, t, self.kernels, self.kernel)
        # L1 distance between sequence i and j at the same frame, per kernel: (B, B, T, kernels)
        dist = (m.unsqueeze(1) - m.unsqueeze(0)).abs().sum(-1)
        sim = torch.exp(-dist).sum(1) - 1.0     # minus the self-similarity exp(0)
        return self.ff(torch.cat([x, sim], -1)).mean(dim=(1, 2))
