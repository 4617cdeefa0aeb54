"""Training and generation for Aud2Pose, Aud2Motion and Aud2Repr2Pose on plain arrays.

Arrays per segment at the model's frame rate (20 fps in the paper): ``speech`` (T, F) features (26 MFCC,
optionally + prosody), ``poses`` (T, D). Hyper-parameters default to the paper's (§4.3): Adam 1e-3; the
speech network's batch 2056 and MSE; the autoencoder's batch 128, 20 epochs, noise 0.05 x feature std.

The training split is streamed (:mod:`evalsuite.generators.datastream`): normalised speech and poses, the
autoencoder's frames and codes are memory-mapped files in a temporary folder, the statistics computed one segment
at a time and each batch gathered from the maps, so that memory does not grow with hours of corpus.
"""
from __future__ import annotations

import pathlib
import tempfile
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn

from evalsuite.generators.aud2repr2pose.net import MotionDAE, SpeechNet, SpeechNetConfig
from evalsuite.generators.aud2repr2pose.systems import SYSTEMS
from evalsuite.generators.datastream import Mapped, Rows, SegmentStore, Windows, mean_std
from evalsuite.generators.early_stopping import BestWeights
from evalsuite.generators.epoch_loop import EpochLoop
from evalsuite.generators.scaling import floored_spread
from evalsuite.generators.schedules import learning_rate_at
from evalsuite.generators.weight_averaging import WeightAverage

__all__ = ["MaxAbsScaler", "Standardiser", "TrainedSystem", "train_dae", "train_system", "generate",
           "SYSTEMS"]



@dataclass
class MaxAbsScaler:
    """Mean 0 and maximum absolute value 1 per dimension (the paper's motion normalisation)."""

    mean: np.ndarray
    scale: np.ndarray

    @classmethod
    def fit(cls, arrays: Sequence[np.ndarray], floor: float = 0.0) -> MaxAbsScaler:
        """``floor``: a dimension's range is at least this fraction of the widest one's
        (:func:`~evalsuite.generators.scaling.floored_spread`; 0: the paper's scaling). One segment at a time:
        ``mean`` is :func:`~evalsuite.generators.datastream.mean_std`'s, the concatenation's bit for bit."""
        mean = mean_std(arrays)[0]
        spread = None
        for a in arrays:
            if not len(a):
                continue
            m = np.abs(a - mean).max(0)
            spread = m if spread is None else np.maximum(spread, m)
        assert spread is not None
        return cls(mean, floored_spread(spread, floor))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) / self.scale).astype(np.float32)

    def inverse(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, np.float64) * self.scale + self.mean


@dataclass
class Standardiser:
    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, arrays: Sequence[np.ndarray]) -> Standardiser:
        """Mean and standard deviation (floored at 1e-6) of the rows of all arrays, one array at a time."""
        mean, std = mean_std(arrays)
        return cls(mean, np.maximum(std, 1e-6))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) / self.std).astype(np.float32)


@dataclass
class TrainedSystem:
    system: str
    speech_net: SpeechNet
    speech_norm: Standardiser
    pose_norm: MaxAbsScaler
    dae: MotionDAE | None = None
    history: list[dict] = field(default_factory=list)


def _epochs(n_items: int, batch: int, rng: np.random.Generator):
    order = rng.permutation(n_items)
    for i in range(0, n_items, batch):
        yield torch.from_numpy(order[i:i + batch])


def train_dae(poses: SegmentStore, code_dim: int, *, epochs: int = 20, batch_size: int = 128,
              learning_rate: float = 1e-3, noise: float = 0.05, seed: int = 0, velocities: bool = False,
              on_epoch: Callable[[dict], None] | None = None) -> MotionDAE:
    """MotionE/MotionD on normalised frames (N, D) (a float32 store, batches gathered from its map): denoising
    reconstruction with MSE. ``velocities``: each frame is a pose followed by its velocity (N, 2 x pose
    dimensions), the paper's Japanese-data setup."""
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    x = Rows(poses)
    width = poses.width
    dae = MotionDAE(width // 2 if velocities else width, code_dim, noise, velocities=velocities)
    with warnings.catch_warnings():  # torch's std over the read-only map (nothing writes to it)
        warnings.simplefilter("ignore", UserWarning)
        dae.feature_std.copy_(torch.from_numpy(poses.data).std(0).clamp_min(1e-6))
    poses.release()
    opt = torch.optim.Adam(dae.parameters(), lr=learning_rate)
    loop = EpochLoop("autoencoder", epochs, {"dae": dae, "opt": opt, "rng": rng}, on_epoch=on_epoch)
    for epoch in loop:
        dae.train()
        total = 0.0
        for idx in _epochs(len(x), batch_size, rng):
            xb = torch.from_numpy(x[idx.numpy()])
            loss = nn.functional.mse_loss(dae(xb), xb)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        loop.end({"stage": "autoencoder", "epoch": epoch + 1, "train_loss": total / len(x)})
    dae.eval()
    return dae


def _windows(speech: np.ndarray, context: int) -> np.ndarray:
    """(T, F) -> (T, 2C+1, F): frame t's window t-C .. t+C, zero-padded (zero = training mean)."""
    padded = np.concatenate([np.zeros((context, speech.shape[1]), np.float32), speech,
                             np.zeros((context, speech.shape[1]), np.float32)])
    return np.lib.stride_tricks.sliding_window_view(padded, 2 * context + 1, axis=0).transpose(0, 2, 1)


def _with_velocities(poses: Sequence[np.ndarray], velocity_norm: MaxAbsScaler) -> Mapped:
    """(T, D) normalised poses -> (T, 2D): each pose and its normalised frame difference (the first frame's 0),
    computed when a segment is read."""
    return Mapped(lambda y: np.concatenate([y, velocity_norm(np.diff(y, axis=0, prepend=y[:1]))], 1), poses)


def _chunks(x: np.ndarray, length: int) -> list[np.ndarray]:
    return [x[i:i + length] for i in range(0, len(x) - length + 1, length // 2)] or [x]


class StreamedPairs:
    """The training (input, target) pairs gathered batch by batch from the maps: ``pairs[idx]`` equals the
    in-memory pairs' rows ``idx``. Sequence form: ``chunk``-frame chunks every ``chunk // 2`` frames of each
    segment (speech ``(B, chunk, F)``, targets ``(B, chunk, D)``, their frame difference appended with ``vel``);
    windowed form: each frame's ``2 context + 1``-frame speech window (zero-padded) and its target ``(B, D)``."""

    def __init__(self, xs: SegmentStore, ys: SegmentStore, form: str, context: int, chunk: int, vel: bool,
                 folder: pathlib.Path):
        self.vel, self.windowed = vel, form == "windowed"
        if self.windowed:
            pad = np.zeros((context, xs.width), np.float32)
            padded = SegmentStore(folder / "speech_padded.npy", (np.concatenate([pad, x, pad]) for x in xs))
            self.x: Windows | Rows = Windows(padded, 2 * context + 1, 1)
            self.y: Windows | Rows = Rows(ys if not vel else SegmentStore(
                folder / "targets.npy", (np.concatenate([y, np.diff(y, axis=0, prepend=y[:1])], 1) for y in ys)))
        else:
            self.x, self.y = Windows(xs, chunk, chunk // 2), Windows(ys, chunk, chunk // 2)
        if not len(self.x):
            raise ValueError(f"no training segment has {chunk} frames for a chunk")

    def __len__(self) -> int:
        return len(self.x)

    def __getitem__(self, idx: np.ndarray) -> tuple[torch.Tensor, torch.Tensor]:
        x, y = self.x[idx], self.y[idx]
        if self.vel and not self.windowed:
            y = np.concatenate([y, np.diff(y, axis=1, prepend=y[:, :1])], -1)
        return torch.from_numpy(x), torch.from_numpy(y.astype(np.float32))



def train_system(system: str, speech: Sequence[np.ndarray], poses: Sequence[np.ndarray], *,
                 config: dict | None = None, code_dim: int = 40, dae_epochs: int = 20, epochs: int = 120,
                 batch_size: int = 2056, learning_rate: float = 1e-3, chunk: int = 100, seed: int = 0,
                 val_speech: Sequence[np.ndarray] = (), val_poses: Sequence[np.ndarray] = (),
                 budget_seconds: float | None = None, patience: int | None = None, scale_floor: float = 0.0,
                 lr_schedule: str = "constant", ema: float = 0.0, validate_on: str = "targets",
                 dae_velocities: bool = False, on_epoch: Callable[[dict], None] | None = None,
                 data_dir: pathlib.Path | None = None) -> TrainedSystem:
    """Train one of ``SYSTEMS`` on segments (lists of arrays or stores); deterministic for a seed on one machine.
    The normalised training data is memory-mapped in a temporary folder in ``data_dir`` (default: the system's). With validation data the
    weights of the best validation epoch are kept (:class:`~evalsuite.generators.early_stopping.BestWeights`;
    ``patience``: stop after that many epochs without improvement). ``validate_on``: ``"targets"`` (the
    training loss on the validation chunks: the representation for Aud2Repr2Pose) or ``"poses"`` (MSE of the
    normalised poses over whole validation segments, the representation decoded)."""
    if system not in SYSTEMS:
        raise ValueError(f"unknown system {system!r}; expected one of {', '.join(SYSTEMS)}")
    if validate_on not in ("targets", "poses"):
        raise ValueError(f"validate_on must be 'targets' or 'poses', got {validate_on!r}")
    uses_repr, overrides = SYSTEMS[system]
    start = time.perf_counter()
    data = tempfile.TemporaryDirectory(prefix=f"{system}-data-", dir=data_dir)  # the maps, removed at the end
    folder = pathlib.Path(data.name)
    speech_norm, pose_norm = Standardiser.fit(speech), MaxAbsScaler.fit(poses, scale_floor)
    xs = SegmentStore(folder / "speech.npy", (speech_norm(s) for s in speech), np.float32)
    ys = SegmentStore(folder / "poses.npy", (pose_norm(p) for p in poses), np.float32)
    dae = velocity_norm = None
    if uses_repr:
        frames = ys   # what the autoencoder codes: the poses, or each pose followed by its velocity
        if dae_velocities:
            velocity_norm = MaxAbsScaler.fit(Mapped(lambda y: np.diff(y, axis=0), ys), scale_floor)
            frames = SegmentStore(folder / "frames.npy", _with_velocities(ys, velocity_norm), np.float32)
        dae = train_dae(frames, code_dim, epochs=dae_epochs, seed=seed, on_epoch=on_epoch, velocities=dae_velocities)
        with torch.no_grad():
            ys = SegmentStore(folder / "codes.npy", (dae.encode(torch.from_numpy(np.array(y))).numpy()
                                                     for y in frames), np.float32)
    base = {"input_dim": xs.width, "output_dim": ys.width, **overrides, **(config or {})}
    net_config = SpeechNetConfig(**base)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = SpeechNet(net_config)
    opt = torch.optim.Adam(net.parameters(), lr=learning_rate)
    vel = net_config.velocity_target

    def dataset(xl: Sequence[np.ndarray], yl: Sequence[np.ndarray]) -> tuple[torch.Tensor, torch.Tensor]:
        """All (input, target) pairs in memory (the validation split's)."""
        if net_config.form == "windowed":
            x = np.concatenate([_windows(x, net_config.context) for x in xl])
            y = np.concatenate([np.concatenate([y, np.diff(y, axis=0, prepend=y[:1])], 1) if vel else y
                                for y in yl])
            return torch.from_numpy(np.ascontiguousarray(x)), torch.from_numpy(y.astype(np.float32))
        xc = [c for x in xl for c in _chunks(x, chunk) if len(c) == chunk]
        yc = [c for y in yl for c in _chunks(y, chunk) if len(c) == chunk]
        y = np.stack(yc)
        if vel:
            y = np.concatenate([y, np.diff(y, axis=1, prepend=y[:, :1])], -1)
        return torch.from_numpy(np.stack(xc)), torch.from_numpy(y.astype(np.float32))

    train_pairs = StreamedPairs(xs, ys, net_config.form, net_config.context, chunk, vel, folder)
    val = None
    whole: list[tuple[np.ndarray, torch.Tensor]] = []   # (normalised speech, poses) per validation segment
    if len(val_speech) and validate_on == "poses":
        whole = [(speech_norm(s), torch.from_numpy(pose_norm(p))) for s, p in zip(val_speech, val_poses)]
    elif len(val_speech):
        vy = [pose_norm(p) for p in val_poses]
        if dae is not None:
            if velocity_norm is not None:
                vy = list(_with_velocities(vy, velocity_norm))
            with torch.no_grad():
                vy = [dae.encode(torch.from_numpy(y)).numpy() for y in vy]
        val = dataset([speech_norm(s) for s in val_speech], vy)
    history: list[dict] = []
    averaged = WeightAverage(net, ema)  # with ema=0 its module is net itself
    judged = averaged.module
    best = BestWeights(judged, patience)

    @torch.no_grad()
    def validation_loss() -> float:
        """What picks the kept epoch (``validate_on``): the training loss on the validation chunks, or the MSE of
        the normalised poses over whole validation segments."""
        judged.eval()
        if val is not None:
            return float(nn.functional.mse_loss(judged(val[0]), val[1]))
        err = [_decoded(judged, dae, x) - y for x, y in whole]
        return float(sum(float((e ** 2).sum()) for e in err) / sum(e.numel() for e in err))
    state = {"net": net, "opt": opt, "average": averaged, "best": best, "rng": rng}
    loop = EpochLoop("speech", epochs, state, history=history, on_epoch=on_epoch, best=best,
                     budget_seconds=budget_seconds, started=start)
    for epoch in loop:
        for group in opt.param_groups:
            group["lr"] = learning_rate_at(lr_schedule, learning_rate, epoch, epochs)
        net.train()
        total = 0.0
        for idx in _epochs(len(train_pairs), batch_size, rng):
            if len(idx) < 2:  # batch normalisation needs two samples
                continue
            xb, yb = train_pairs[idx.numpy()]
            loss = nn.functional.mse_loss(net(xb), yb)
            opt.zero_grad()
            loss.backward()
            opt.step()
            averaged.update(net)
            total += loss.item() * len(idx)
        record = {"stage": "speech", "epoch": epoch + 1, "train_loss": total / len(train_pairs)}
        if len(val_speech):
            record["val_loss"] = validation_loss()
        if loop.end(record):
            break
    best.restore()
    judged.eval()
    data.cleanup()
    return TrainedSystem(system, judged, speech_norm, pose_norm, dae, history)


def _decoded(net: SpeechNet, dae: MotionDAE | None, x: np.ndarray, batch: int = 4096) -> torch.Tensor:
    """(T, F) normalised speech -> (T, D) normalised poses: one pass over the segment (sequence form) or its
    windows in batches (windowed form), the representation decoded when there is an autoencoder."""
    c = net.config
    if c.form == "windowed":
        w = _windows(x, c.context)
        out = torch.cat([net(torch.from_numpy(np.ascontiguousarray(w[i:i + batch])))
                         for i in range(0, len(w), batch)])
    else:
        out = net(torch.from_numpy(x)[None])[0]
    out = out[:, :c.output_dim]
    return dae.pose(out) if dae is not None else out


@torch.no_grad()
def generate(model: TrainedSystem, speech: np.ndarray, batch: int = 4096) -> np.ndarray:
    """(T, F) speech features -> (T, D) poses in the training data's units."""
    model.speech_net.eval()
    out = _decoded(model.speech_net, model.dae, model.speech_norm(speech), batch)
    return model.pose_norm.inverse(out.numpy())
