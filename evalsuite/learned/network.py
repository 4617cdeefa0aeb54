"""The GENEA-style convolutional motion autoencoder, laid out so reference checkpoints load by name.

Encoder (``pose_encoder``), input ``(batch, window, pose_dim)``::

    net.0   Conv1d(pose_dim -> c1, k=3)  BatchNorm1d  LeakyReLU(0.2)
    net.1   Conv1d(c1 -> c2, k=3)        BatchNorm1d  LeakyReLU(0.2)
    net.2   Conv1d(c2 -> c2, k=4, s=2)   BatchNorm1d  LeakyReLU(0.2)
    net.3   Conv1d(c2 -> 32, k=3)
    flatten -> 32 * ((window - 8) // 2 - 1) values   (320/800/1280/1760 for 30/60/90/120 frames)
    out_net Linear(->256) BN LeakyReLU(fc_slope) Linear(256->128) BN LeakyReLU(fc_slope) Linear(128->32)
    [fc_mu Linear(32->32), fc_logvar Linear(32->32)]   (Yoon et al. 2020 only; the feature is fc_mu)

Decoder (``decoder``)::

    pre_net Linear(32->h) BN LeakyReLU(fc_slope) Linear(h -> 4*window); view (batch, 4, window)
    net     ConvTranspose1d(4->32,k3) BN LeakyReLU(0.2) ConvTranspose1d(32->32,k3) BN LeakyReLU(0.2)
            Conv1d(32->32,k3) Conv1d(32->pose_dim,k3)

``(c1, c2)`` is ``(128, 64)`` for GENEA 2022/2023 and ``(32, 64)`` for GENEA 2020 and Yoon et
al.; ``h`` is 64 (128 in Yoon's 64-frame variant). The reference code builds the fully
connected activations as ``nn.LeakyReLU(True)``: the first positional argument is the
negative slope, so the slope is ``True == 1`` and the activation is the identity. That quirk
is kept (``fc_slope=1.0``) because it changes the features; the activation modules stay in
place so the parameter indices (``out_net.3``, ``out_net.6``, ``pre_net.3``) match.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn

LATENT_DIM = 32


@dataclass(frozen=True)
class Architecture:
    """Everything that fixes the network's shapes and behaviour (stored in the model file)."""

    pose_dim: int
    window: int
    conv_channels: tuple[int, int] = (128, 64)
    fc_slope: float = 1.0
    variational_head: bool = False
    decoder_hidden: int = 64

    def __post_init__(self):
        if self.window < 12:
            raise ValueError(f"window must be at least 12 frames for this network, got {self.window}")
        if self.pose_dim < 1:
            raise ValueError(f"pose_dim must be positive, got {self.pose_dim}")

    @property
    def flat_dim(self) -> int:
        """Values after the last convolution (the first Linear layer's input size)."""
        return LATENT_DIM * conv_output_length(self.window)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["conv_channels"] = list(self.conv_channels)
        d["name"] = "genea-conv-autoencoder"
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Architecture:
        return cls(pose_dim=int(d["pose_dim"]), window=int(d["window"]),
                   conv_channels=(int(d["conv_channels"][0]), int(d["conv_channels"][1])), fc_slope=float(d["fc_slope"]),
                   variational_head=bool(d["variational_head"]), decoder_hidden=int(d["decoder_hidden"]))


def conv_output_length(window: int) -> int:
    """Frames left after the encoder's convolutions: k3, k3, k4/s2, k3 without padding."""
    return (window - 8) // 2 - 1


def _conv_bn_lrelu(c_in: int, c_out: int, downsample: bool) -> nn.Sequential:
    kernel, stride = (4, 2) if downsample else (3, 1)
    return nn.Sequential(nn.Conv1d(c_in, c_out, kernel_size=kernel, stride=stride),
                         nn.BatchNorm1d(c_out), nn.LeakyReLU(0.2, inplace=True))


def _fc_stack(sizes: list[int], slope: float) -> nn.Sequential:
    """Linear, then (BatchNorm1d, LeakyReLU(slope), Linear) for each further size."""
    layers: list[nn.Module] = [nn.Linear(sizes[0], sizes[1])]
    for a, b in zip(sizes[1:-1], sizes[2:]):
        layers += [nn.BatchNorm1d(a), nn.LeakyReLU(slope), nn.Linear(a, b)]
    return nn.Sequential(*layers)


class PoseEncoder(nn.Module):
    def __init__(self, arch: Architecture):
        super().__init__()
        c1, c2 = arch.conv_channels
        self.net = nn.Sequential(_conv_bn_lrelu(arch.pose_dim, c1, False), _conv_bn_lrelu(c1, c2, False),
                                 _conv_bn_lrelu(c2, c2, True), nn.Conv1d(c2, LATENT_DIM, 3))
        self.out_net = _fc_stack([arch.flat_dim, 256, 128, LATENT_DIM], arch.fc_slope)
        if arch.variational_head:
            self.fc_mu = nn.Linear(LATENT_DIM, LATENT_DIM)
            self.fc_logvar = nn.Linear(LATENT_DIM, LATENT_DIM)
        self.variational_head = arch.variational_head

    def forward(self, poses: torch.Tensor) -> torch.Tensor:
        out = self.net(poses.transpose(1, 2)).flatten(1)
        out = self.out_net(out)
        # Yoon et al. evaluate with variational_encoding=False: the feature is the mean.
        return self.fc_mu(out) if self.variational_head else out


class PoseDecoder(nn.Module):
    def __init__(self, arch: Architecture):
        super().__init__()
        self.window = arch.window
        self.pre_net = _fc_stack([LATENT_DIM, arch.decoder_hidden, 4 * arch.window], arch.fc_slope)
        self.net = nn.Sequential(
            nn.ConvTranspose1d(4, 32, 3), nn.BatchNorm1d(32), nn.LeakyReLU(0.2, inplace=True),
            nn.ConvTranspose1d(32, 32, 3), nn.BatchNorm1d(32), nn.LeakyReLU(0.2, inplace=True),
            nn.Conv1d(32, 32, 3), nn.Conv1d(32, arch.pose_dim, 3))

    def forward(self, feature: torch.Tensor) -> torch.Tensor:
        out = self.pre_net(feature).view(feature.shape[0], 4, self.window)
        return self.net(out).transpose(1, 2)


class EmbeddingNet(nn.Module):
    """Autoencoder with the reference attribute names (``pose_encoder``, ``decoder``)."""

    def __init__(self, arch: Architecture):
        super().__init__()
        self.arch = arch
        self.pose_encoder = PoseEncoder(arch)
        self.decoder = PoseDecoder(arch)

    def forward(self, poses: torch.Tensor):
        feature = self.pose_encoder(poses)
        return feature, self.decoder(feature)


def architecture_from_state_dict(state: dict, window: int | None = None) -> Architecture:
    """Infer the architecture of a reference checkpoint's state dict from its shapes."""
    def shape(name):
        if name not in state:
            raise KeyError(name)
        return tuple(state[name].shape)

    c1, pose_dim, _ = shape("pose_encoder.net.0.0.weight")
    c2 = shape("pose_encoder.net.1.0.weight")[0]
    flat = shape("pose_encoder.out_net.0.weight")[1]
    hidden = shape("decoder.pre_net.0.weight")[0]
    out = shape("decoder.pre_net.3.weight")[0]
    inferred = out // 4
    if window is not None and window != inferred:
        raise ValueError(f"window {window} does not match the checkpoint (decoder output {out} = 4 x {inferred})")
    arch = Architecture(pose_dim=pose_dim, window=inferred, conv_channels=(c1, c2),
                        variational_head="pose_encoder.fc_mu.weight" in state, decoder_hidden=hidden)
    if arch.flat_dim != flat:
        raise ValueError(f"the encoder's first Linear layer takes {flat} values, but a {inferred}-frame window "
                         f"gives {arch.flat_dim}")
    return arch
