"""Training and autoregressive generation for the Gesticulator re-implementation, on plain arrays.

Arrays per segment, all at the model's frame rate (20 fps in the paper):
``speech``: (T, A + X) audio features followed by text features; ``poses``: (T, D) exponential maps.

The paper's schedule (§4.3): sequences of 70 frames (10 past context, 40 predicted, 20 future context);
loss = MSE(pose) + 0.6 MSE(velocity) on the 40 predicted frames; Adam, learning rate 1e-4, batch 64;
the first 7 epochs without autoregression (the previous-pose input is zeroed), then autoregression with
teacher forcing that is withdrawn: the model's own predictions replace the ground truth for two
consecutive frames every 16 frames, then every 8, every 4, and finally always. Stage lengths are options
(``TrainSchedule``, its defaults the declared options') so that a CPU budget can keep the order of the stages
with fewer epochs.
"""
from __future__ import annotations

import math
import pathlib
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from evalsuite.generators.datastream import SegmentStore, Windows, mean_std
from evalsuite.generators.early_stopping import BestWeights
from evalsuite.generators.epoch_loop import EpochLoop
from evalsuite.generators.gesticulator.net import GesticulatorConfig, GesticulatorNet
from evalsuite.generators.gesticulator.options import OPTIONS
from evalsuite.generators.scaling import floored_spread
from evalsuite.generators.schedules import learning_rate_at
from evalsuite.generators.weight_averaging import WeightAverage

__all__ = ["TrainSchedule", "Normaliser", "TrainedGesticulator", "train_gesticulator", "generate_poses",
           "make_sequences", "velocity_weight", "PREDICTED_FRAMES"]

velocity_weight = 0.6  # alpha of the paper's loss (2)
PREDICTED_FRAMES = 40  # frames predicted per training sequence, between its past and future context


_D = OPTIONS.defaults()   # each option's default declared once, in options.py (the cpu-small preset)


def _pretrain_epochs(epochs: int) -> int:
    return max(1, math.ceil(0.07 * epochs))


@dataclass(frozen=True)
class TrainSchedule:
    """Epochs per stage, in the paper's order. ``teacher_periods`` are the successive periods (in frames) at
    which the model's own prediction replaces the ground truth; 1 = always its own prediction. The defaults are
    the declared options' (:func:`budgeted_schedule` of the default ``epochs``)."""

    pretrain_epochs: int = _pretrain_epochs(_D["epochs"])
    teacher_periods: tuple[int, ...] = (16, 8, 4)
    free_epochs: int = _D["epochs"] - _pretrain_epochs(_D["epochs"]) - 3   # autoregressive, no teacher forcing
    batch_size: int = _D["batch_size"]
    learning_rate: float = _D["learning_rate"]
    sequence: int = _D["past"] + PREDICTED_FRAMES + _D["future"]   # frames per training sequence
    stride: int = 10             # between training sequences (4x overlap of the predicted frames)
    lr_schedule: str = _D["lr_schedule"]   # "cosine": decays to 1 % of learning_rate over the epochs; "constant"

    def learning_rate_at(self, epoch: int) -> float:
        """Learning rate of a zero-based epoch: constant (the paper's) or a cosine decay to 1 % by the last epoch."""
        return learning_rate_at(self.lr_schedule, self.learning_rate, epoch, self.epochs)

    @property
    def epochs(self) -> int:
        return self.pretrain_epochs + len(self.teacher_periods) + self.free_epochs

    def stage(self, epoch: int) -> tuple[bool, int]:
        """(autoregressive?, own-prediction period) for a zero-based epoch."""
        if epoch < self.pretrain_epochs:
            return False, 0
        k = epoch - self.pretrain_epochs
        if k < len(self.teacher_periods):
            return True, self.teacher_periods[k]
        return True, 1


@dataclass
class Normaliser:
    """Per-dimension standardisation fitted on the training split (std floored to avoid division by ~0)."""

    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, arrays: Sequence[np.ndarray], floor: float = 0.0) -> Normaliser:
        """``floor``: a dimension's standard deviation is taken as at least this fraction of the widest one's
        (:func:`~evalsuite.generators.scaling.floored_spread`; 0: unit variance for every dimension). One
        segment at a time (:func:`~evalsuite.generators.datastream.mean_std`: the concatenation's figures)."""
        mean, std = mean_std(arrays)
        return cls(mean, floored_spread(std, floor))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) / self.std).astype(np.float32)

    def inverse(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, dtype=np.float64) * self.std + self.mean


@dataclass
class TrainedGesticulator:
    net: GesticulatorNet
    speech_norm: Normaliser
    pose_norm: Normaliser
    history: list[dict]


def make_sequences(speech: Sequence[np.ndarray], poses: Sequence[np.ndarray], config: GesticulatorConfig,
                   length: int, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """Cut every segment into overlapping sequences -> (N, length, A+X), (N, length, D).

    Segments are padded at both ends (speech by zeros = the training mean after standardisation, poses by
    their first/last frame) so that every frame of a segment is predicted once in some sequence."""
    xs, ys = [], []
    for s, p in zip(speech, poses):
        s = np.concatenate([np.zeros((config.past, s.shape[1]), np.float32), s,
                            np.zeros((config.future, s.shape[1]), np.float32)])
        p = np.concatenate([np.repeat(p[:1], config.past, 0), p, np.repeat(p[-1:], config.future, 0)])
        for start in range(0, max(len(s) - length, 0) + 1, stride):
            if start + length <= len(s):
                xs.append(s[start:start + length])
                ys.append(p[start:start + length])
    if not xs:
        raise ValueError(f"no segment is long enough for {length}-frame training sequences")
    return np.stack(xs), np.stack(ys)


def sequence_windows(speech: Sequence[np.ndarray], poses: Sequence[np.ndarray], speech_norm: Normaliser,
                     pose_norm: Normaliser, config: GesticulatorConfig, length: int, stride: int,
                     folder: pathlib.Path) -> tuple[Windows, Windows]:
    """:func:`make_sequences`'s windows of the normalised segments, without making them: each segment normalised
    and padded as there, written to ``folder`` (memory-mapped .npy), and gathered batch by batch."""
    def padded(norm: Normaliser, arrays: Sequence[np.ndarray], speech_side: bool) -> Iterator[np.ndarray]:
        for a in arrays:
            a = norm(a)
            if speech_side:
                yield np.concatenate([np.zeros((config.past, a.shape[1]), np.float32), a,
                                      np.zeros((config.future, a.shape[1]), np.float32)])
            else:
                yield np.concatenate([np.repeat(a[:1], config.past, 0), a, np.repeat(a[-1:], config.future, 0)])

    xs = Windows(SegmentStore(folder / "speech_windows.npy", padded(speech_norm, speech, True)), length, stride)
    ys = Windows(SegmentStore(folder / "pose_windows.npy", padded(pose_norm, poses, False)), length, stride)
    if not len(xs):
        raise ValueError(f"no segment is long enough for {length}-frame training sequences")
    return xs, ys


def _rollout(net: GesticulatorNet, x: torch.Tensor, y: torch.Tensor, autoregressive: bool,
             period: int) -> torch.Tensor:
    """Predict frames past .. len-future-1 of each sequence; returns (B, n_predicted, D).

    The speech codes of all predicted frames are computed at once (they do not depend on the poses); only
    the pose conditioning runs frame by frame, and not at all without autoregression."""
    c = net.config
    codes = net.speech_codes(x)                                   # (B, n_pred, hidden)
    b, n_pred, _ = codes.shape
    prev = y[:, c.past - c.n_prev_poses:c.past].clone()
    if not c.autoregressive:
        return net.decode(codes.reshape(b * n_pred, -1)).reshape(b, n_pred, -1)
    if not autoregressive:    # pretraining: the previous-pose input is zeroed, so every frame is independent
        zeros = torch.zeros(b * n_pred, c.n_prev_poses, prev.shape[-1])
        return net.decode(codes.reshape(b * n_pred, -1), zeros).reshape(b, n_pred, -1)
    outputs = []
    for k in range(n_pred):
        t = c.past + k
        out = net.decode(codes[:, k], prev)
        outputs.append(out)
        # own prediction for two consecutive frames every `period` frames (period 1: always)
        own = period == 1 or (k % period) < 2
        nxt = out if own else y[:, t]
        prev = torch.cat([prev[:, 1:], nxt.unsqueeze(1)], dim=1)
    return torch.stack(outputs, dim=1)


def _loss(pred: torch.Tensor, target: torch.Tensor, alpha: float = velocity_weight) -> torch.Tensor:
    mse = nn.functional.mse_loss(pred, target)
    vel = nn.functional.mse_loss(pred[:, 1:] - pred[:, :-1], target[:, 1:] - target[:, :-1])
    return mse + alpha * vel


def train_gesticulator(speech: Sequence[np.ndarray], poses: Sequence[np.ndarray], config: GesticulatorConfig,
                       schedule: TrainSchedule = TrainSchedule(), *, seed: int = 0,
                       val_speech: Sequence[np.ndarray] = (), val_poses: Sequence[np.ndarray] = (),
                       budget_seconds: float | None = None, patience: int | None = None,
                       weight_decay: float = 0.0, scale_floor: float = 0.0,
                       velocity_weight: float = velocity_weight, ema: float = 0.0,
                       on_epoch: Callable[[dict], None] | None = None,
                       data_dir: pathlib.Path | None = None) -> TrainedGesticulator:
    """Train on segments of (speech (T, A+X), poses (T, D)); deterministic for a seed on one machine.

    With ``budget_seconds`` the schedule is compressed so that its stages still run in order: training stops
    when the budget is spent, and the history says so. With validation data the weights of the best validation
    epoch are kept (``patience``: stop after that many epochs without improvement). The training windows are
    memory-mapped from a temporary folder in ``data_dir`` (default: the system's), not held in memory."""
    with tempfile.TemporaryDirectory(prefix="gesticulator-data-", dir=data_dir) as tmp:
        return _train(speech, poses, config, schedule, seed, val_speech, val_poses, budget_seconds, patience,
                      weight_decay, scale_floor, velocity_weight, ema, on_epoch, pathlib.Path(tmp))


def _train(speech: Sequence[np.ndarray], poses: Sequence[np.ndarray], config: GesticulatorConfig,
           schedule: TrainSchedule, seed: int, val_speech: Sequence[np.ndarray], val_poses: Sequence[np.ndarray],
           budget_seconds: float | None, patience: int | None, weight_decay: float, scale_floor: float,
           velocity_weight: float, ema: float, on_epoch: Callable[[dict], None] | None,
           folder: pathlib.Path) -> TrainedGesticulator:
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    speech_norm, pose_norm = Normaliser.fit(speech), Normaliser.fit(poses, scale_floor)
    xt, yt = sequence_windows(speech, poses, speech_norm, pose_norm, config, schedule.sequence, schedule.stride,
                              folder)
    val = None
    if len(val_speech):
        vx, vy = make_sequences([speech_norm(s) for s in val_speech], [pose_norm(p) for p in val_poses],
                                config, schedule.sequence, schedule.sequence - config.past - config.future)
        val = torch.from_numpy(vx), torch.from_numpy(vy)
    net = GesticulatorNet(config)
    opt = torch.optim.Adam(net.parameters(), lr=schedule.learning_rate, weight_decay=weight_decay)
    history: list[dict] = []
    averaged = WeightAverage(net, ema)
    best = BestWeights(averaged.module, patience)
    state = {"net": net, "opt": opt, "average": averaged, "best": best, "rng": rng}
    loop = EpochLoop("gesticulator", schedule.epochs, state, history=history, on_epoch=on_epoch, best=best,
                     budget_seconds=budget_seconds)
    for epoch in loop:
        autoregressive, period = schedule.stage(epoch)
        for group in opt.param_groups:
            group["lr"] = schedule.learning_rate_at(epoch)
        net.train()
        order = rng.permutation(len(xt))
        total, n = 0.0, 0
        for i in range(0, len(order), schedule.batch_size):
            idx = order[i:i + schedule.batch_size]
            xb, yb = torch.from_numpy(xt[idx]), torch.from_numpy(yt[idx])
            pred = _rollout(net, xb, yb, autoregressive and config.autoregressive, period)
            loss = _loss(pred, yb[:, config.past:schedule.sequence - config.future], velocity_weight)
            opt.zero_grad()
            loss.backward()
            opt.step()
            averaged.update(net)
            total += loss.item() * len(idx)
            n += len(idx)
        record = {"epoch": epoch + 1, "stage": "pretrain" if not autoregressive else
                  ("autoregressive" if period == 1 else f"teacher forcing 1/{period}"), "train_loss": total / n}
        if val is not None:
            averaged.module.eval()
            with torch.no_grad():
                vpred = _rollout(averaged.module, val[0], val[1], config.autoregressive, 1)
                record["val_loss"] = float(_loss(vpred, val[1][:, config.past:schedule.sequence - config.future],
                                                 velocity_weight))
        if loop.end(record):
            break
    best.restore()
    net = averaged.module
    net.eval()
    return TrainedGesticulator(net, speech_norm, pose_norm, history)


@torch.no_grad()
def generate_poses(model: TrainedGesticulator, speech: Sequence[np.ndarray],
                   initial_pose: np.ndarray | None = None) -> list[np.ndarray]:
    """Autoregressive generation for several segments at once -> list of (T, D) poses (unnormalised).

    The first previous poses are the training mean pose (as the original initialises with its mean pose)."""
    net, c = model.net, model.net.config
    net.eval()
    lengths = [len(s) for s in speech]
    t_max = max(lengths)
    feats = np.zeros((len(speech), c.past + t_max + c.future, speech[0].shape[1]), np.float32)
    for i, s in enumerate(speech):
        feats[i, c.past:c.past + len(s)] = model.speech_norm(s)
    x = torch.from_numpy(feats)
    start = np.zeros(c.pose_dim, np.float32) if initial_pose is None else model.pose_norm(initial_pose)
    prev = torch.from_numpy(np.tile(start, (len(speech), c.n_prev_poses, 1)).astype(np.float32))
    codes = net.speech_codes(x)                                   # (B, t_max, hidden)
    if not c.autoregressive:
        out = net.decode(codes.reshape(-1, codes.shape[-1])).reshape(len(speech), t_max, -1)
    else:
        out = torch.empty(len(speech), t_max, c.pose_dim)
        for t in range(t_max):
            pose = net.decode(codes[:, t], prev)
            out[:, t] = pose
            prev = torch.cat([prev[:, 1:], pose.unsqueeze(1)], dim=1)
    return [model.pose_norm.inverse(out[i, :n].numpy()) for i, n in enumerate(lengths)]


def budgeted_schedule(epochs: int) -> TrainSchedule:
    """The paper's stage order squeezed into ``epochs`` epochs (>= 5): about 7 % pretraining, one epoch per
    teacher-forcing period, the rest autoregressive without teacher forcing."""
    if epochs < 5:
        raise ValueError("the schedule needs at least 5 epochs (pretraining, 3 teacher-forcing stages, free)")
    pretrain = _pretrain_epochs(epochs)
    return TrainSchedule(pretrain_epochs=pretrain, free_epochs=epochs - pretrain - 3)
