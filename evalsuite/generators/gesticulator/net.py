"""The Gesticulator network, re-implemented from Kucherenko et al., "Gesticulator" (ICMI 2020), §4.

Not the published system: a re-implementation from the paper, with sizes as options (the paper's values are
the defaults of :class:`GesticulatorConfig`; CPU presets shrink them). Deviations are listed in
``DEVIATIONS``.

Per output frame t the model reads a window of speech frames t-10 ... t+19 (0.5 s past, 1 s future at 20 fps):

1. each frame's features (audio ++ text) go through one shared feed-forward layer -> ``frame_dim`` (124);
2. the window's encodings are concatenated (30 x 124 = 3720) and passed through fully connected layers
   (612, 256) with tanh and dropout 0.2;
3. FiLM (Perez et al. 2018): the previous 3 poses (dropout 0.8) are encoded into alpha and beta (2 x 256 =
   512 values) and the 256-d activation becomes ``x * alpha + beta``;
4. a final linear layer gives the pose (exponential maps of the modelled joints).

Ablations of the paper's Table 2 are options: ``use_audio=False`` / ``use_text=False`` zero one input stream,
``autoregressive=False`` drops the previous-pose conditioning, ``film=False`` concatenates the pose encoding
to the activation instead of FiLM. ``text_dropout`` (not in the paper) drops text features at the input in training.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import torch
from torch import nn

__all__ = ["GesticulatorConfig", "GesticulatorNet", "DEVIATIONS"]

DEVIATIONS = (
    "Text features: word embeddings from an offline model installed with evalsuite (or a user-supplied path) "
    "instead of BERT-base-cased fetched from a hub at run time.",
    "Sizes are options; the CPU preset uses smaller layers than the paper's 124 / 612 / 256 / 512.",
    "No PCA on the output (the paper's own ablation found PCA over-smoothed the motion).",
)


@dataclass(frozen=True)
class GesticulatorConfig:
    audio_dim: int
    text_dim: int
    pose_dim: int
    past: int = 10            # speech frames before the current one (0.5 s at 20 fps)
    future: int = 20          # speech frames after it (1 s)
    frame_dim: int = 124      # per-frame speech encoding
    hidden: tuple[int, ...] = (612, 256)
    n_prev_poses: int = 3
    film_dim: int = 512       # alpha and beta together (2 x hidden[-1])
    dropout: float = 0.2
    prev_pose_dropout: float = 0.8
    use_audio: bool = True
    use_text: bool = True
    autoregressive: bool = True
    film: bool = True
    film_identity: bool = False   # FiLM as x * (1 + alpha) + beta from a zero-initialised encoder (identity at start)
    frame_layers: int = 1         # layers of the per-frame encoder (2: input -> 2 frame_dim -> frame_dim)
    text_dropout: float = 0.0     # dropout of the text features at the input, in training (not in the paper)
    extra: dict = field(default_factory=dict)

    @property
    def window(self) -> int:
        return self.past + 1 + self.future

    def to_dict(self) -> dict:
        d = asdict(self)
        d["hidden"] = list(self.hidden)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> GesticulatorConfig:
        d = dict(d)
        d["hidden"] = tuple(d["hidden"])
        return cls(**d)


class GesticulatorNet(nn.Module):
    """speech window (B, W, A+X) and previous poses (B, P, D) -> pose (B, D)."""

    input_mask: torch.Tensor

    def __init__(self, config: GesticulatorConfig):
        super().__init__()
        self.config = c = config
        if c.frame_layers not in (1, 2):
            raise ValueError(f"frame_layers must be 1 or 2, got {c.frame_layers}")
        widths = [c.audio_dim + c.text_dim] + ([2 * c.frame_dim] if c.frame_layers == 2 else []) + [c.frame_dim]
        frame_layers: list[nn.Module] = []
        for a, b in zip(widths[:-1], widths[1:]):
            frame_layers += [nn.Linear(a, b), nn.Tanh(), nn.Dropout(c.dropout)]
        self.frame_encoder = nn.Sequential(*frame_layers)
        layers: list[nn.Module] = []
        width = c.window * c.frame_dim
        for h in c.hidden:
            layers += [nn.Linear(width, h), nn.Tanh(), nn.Dropout(c.dropout)]
            width = h
        self.speech_layers = nn.Sequential(*layers)
        self.hidden_width = width
        if c.autoregressive:
            cond_out = 2 * width if c.film else c.film_dim // 2
            if c.film_identity:
                first = nn.Linear(c.n_prev_poses * c.pose_dim, cond_out)
                nn.init.zeros_(first.weight)
                nn.init.zeros_(first.bias)
                self.pose_encoder = nn.Sequential(first, nn.Tanh(), nn.Dropout(c.prev_pose_dropout))
            else:
                self.pose_encoder = nn.Sequential(nn.Dropout(c.prev_pose_dropout),
                                                  nn.Linear(c.n_prev_poses * c.pose_dim, c.film_dim), nn.Tanh(),
                                                  nn.Linear(c.film_dim, cond_out))
            out_in = width if c.film else width + cond_out
        else:
            out_in = width
        self.output = nn.Linear(out_in, c.pose_dim)
        mask = torch.ones(c.audio_dim + c.text_dim)
        if not c.use_audio:
            mask[: c.audio_dim] = 0
        if not c.use_text:
            mask[c.audio_dim:] = 0
        self.register_buffer("input_mask", mask)

    def speech_codes(self, speech: torch.Tensor) -> torch.Tensor:
        """Speech frames (B, L, A+X), L >= window -> speech codes (B, L - window + 1, hidden): code k is the
        encoding of the window of frames k ... k + window - 1 (output frame k + past).

        Each frame is encoded once and the windows are cut from the encodings, so a sequence costs one
        frame encoding per frame instead of one per frame and window position (the same function)."""
        c = self.config
        if self.training and c.text_dropout > 0:
            # in training only: each text value is zeroed (the training mean) with this probability, the rest
            # scaled by 1 / (1 - p), so that the word vectors cannot carry what the audio can
            speech = torch.cat([speech[..., :c.audio_dim],
                                nn.functional.dropout(speech[..., c.audio_dim:], c.text_dropout, True)], dim=-1)
        b, length, _ = speech.shape
        if length < c.window:
            raise ValueError(f"{length} speech frames are fewer than the model's window of {c.window}")
        frames = self.frame_encoder(speech * self.input_mask)                      # (B, L, frame_dim)
        windows = frames.unfold(1, c.window, 1).transpose(2, 3)                     # (B, n, W, frame_dim)
        return self.speech_layers(windows.reshape(b, length - c.window + 1, -1))

    def decode(self, codes: torch.Tensor, prev_poses: torch.Tensor | None = None) -> torch.Tensor:
        """Speech codes (B, hidden) and previous poses (B, P, D) -> pose (B, D)."""
        c = self.config
        x = codes
        if c.autoregressive:
            if prev_poses is None:
                raise ValueError("an autoregressive Gesticulator needs the previous poses")
            cond = self.pose_encoder(prev_poses.reshape(len(codes), -1))
            if c.film:
                alpha, beta = cond.chunk(2, dim=-1)
                x = x * (1 + alpha) + beta if c.film_identity else x * alpha + beta
            else:
                x = torch.cat([x, cond], dim=-1)
        return self.output(x)

    def forward(self, speech: torch.Tensor, prev_poses: torch.Tensor | None = None) -> torch.Tensor:
        """One window of speech frames (B, W, A+X) and the previous poses (B, P, D) -> pose (B, D)."""
        return self.decode(self.speech_codes(speech)[:, 0], prev_poses)
