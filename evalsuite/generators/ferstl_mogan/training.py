"""Training of the Ferstl et al. (MIG 2019) re-implementation on plain arrays, in the paper's stages (§4-7).

Per segment at 20 fps: ``speech`` (T, 27) = 26 MFCC + F0 (pitch in the last column), ``positions`` (T, 3J),
``phases`` (T,) integer labels in ``PHASES`` order (for the phase classifier), and ``arm_columns``: the
columns of ``positions`` whose per-frame offsets the classifier and the displacement discriminator read.

Stages: (1) the phase classifier on labelled data (cross-entropy; its weighted F1 on held-out data is
reported); (2) the generator pre-trained with MSE, with snapshots of its weights kept as its "training
history"; (3) the phase discriminator pre-trained against that history, moving to the next snapshot once it is
right on at least 70 % of three batches in a row (or after ``phase_pretrain_tries`` batches); (4) the
motion-realism discriminator pre-trained against a fresh generator; (5) adversarial training with RMSprop, the
generator's loss the 2:4:4:1-weighted mean over the phase, realism, minibatch and displacement discriminators,
and one MSE correction step (with the discontinuity penalty between consecutive sequences) per two adversarial
steps.

With ``budget_seconds`` each stage must end by a cumulative share of the budget (``MoganStages.budget_shares``:
classifier 15 %, MSE pre-training to 45 %, discriminator pre-training to 55 %, adversarial training to 100 %; time
a stage leaves unused goes to the later ones); a stage at its deadline stops, the next starts, and its last history
row says ``"stopped": "time budget spent"`` (names in ``TrainedMogan.stopped``). The training split is memory-mapped
(:mod:`evalsuite.generators.datastream`), so that memory does not grow with hours of corpus.
"""
from __future__ import annotations

import copy
import pathlib
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import nn

from evalsuite.generators.datastream import SegmentStore, mean_std
from evalsuite.generators.epoch_loop import BUDGET_SPENT, EpochLoop
from evalsuite.generators.ferstl_mogan.data import Sequences, sequences
from evalsuite.generators.ferstl_mogan.net import (
    Generator,
    MinibatchDiscriminator,
    MoganConfig,
    PhaseClassifier,
    SequenceDiscriminator,
)
from evalsuite.generators.ferstl_mogan.options import ABLATIONS, OPTIONS
from evalsuite.generators.scaling import floored_spread

__all__ = ["MoganStages", "TrainedMogan", "train_mogan", "generate_mogan", "weighted_f1", "WEIGHTS"]

WEIGHTS = {"phase": 2.0, "realism": 4.0, "minibatch": 4.0, "displacement": 1.0}  # eq. (3)
_D = OPTIONS.defaults()   # each option's default declared once, in options.py (the cpu-small preset)


@dataclass(frozen=True)
class MoganStages:
    """Lengths and rates: the plug-in's options (their declared defaults; ``discriminator_learning_rate`` None: the
    generator's), and the paper's structure (``budget_shares``: cumulative deadlines of the four stages)."""

    classifier_epochs: int = _D["classifier_epochs"]
    pretrain_epochs: int = _D["pretrain_epochs"]
    snapshots: int = 6
    realism_pretrain_steps: int = _D["realism_pretrain_steps"]
    phase_pretrain_tries: int = _D["phase_pretrain_tries"]  # batches per snapshot at most, if never 3 right in a row
    adversarial_steps: int = _D["adversarial_steps"]
    batch_size: int = _D["batch_size"]
    learning_rate: float = _D["learning_rate"]
    adversarial_learning_rate: float = _D["adversarial_learning_rate"]
    discriminator_learning_rate: float | None = _D["discriminator_learning_rate"]
    discontinuity_weight: float = 1.0
    scale_floor: float = _D["scale_floor"]   # a position's std is at least this fraction of the widest one's
    discriminators: tuple[str, ...] = ABLATIONS[_D["ablation"]]   # ablations drop some
    budget_shares: tuple[float, ...] = (0.15, 0.45, 0.55, 1.0)


@dataclass
class TrainedMogan:
    config: MoganConfig
    generator: Generator
    classifier: PhaseClassifier
    speech_mean: np.ndarray
    speech_std: np.ndarray
    pose_mean: np.ndarray
    pose_std: np.ndarray
    arm_columns: np.ndarray
    classifier_f1: float
    history: list[dict] = field(default_factory=list)
    stopped: list[str] = field(default_factory=list)


def weighted_f1(true: np.ndarray, pred: np.ndarray, n_classes: int) -> float:
    """Support-weighted mean of the per-class F1 scores (what the paper reports as the overall F-score)."""
    total, score = 0, 0.0
    for k in range(n_classes):
        tp = np.sum((pred == k) & (true == k))
        fp = np.sum((pred == k) & (true != k))
        fn = np.sum((pred != k) & (true == k))
        if support := tp + fn:
            score += 2 * tp / max(2 * tp + fp + fn, 1) * support   # the class's F1 x its support
            total += support
    return float(score / max(total, 1))


def _classifier_input(pos: torch.Tensor, pitch: torch.Tensor, arm: torch.Tensor) -> torch.Tensor:
    a = pos[..., arm]
    vel = torch.diff(a, dim=1, prepend=a[:, :1])
    return torch.cat([vel, pitch.unsqueeze(-1)], -1)


def train_mogan(speech: Sequence[np.ndarray], positions: Sequence[np.ndarray], phases: Sequence[np.ndarray],
                arm_columns: Sequence[int], config: MoganConfig, stages: MoganStages = MoganStages(), *,
                seed: int = 0, val: tuple[Sequence[np.ndarray], Sequence[np.ndarray], Sequence[np.ndarray]] | None = None,
                budget_seconds: float | None = None, on_step: Callable[[dict], None] | None = None,
                data_dir: pathlib.Path | None = None) -> TrainedMogan:
    """The paper's stages on segments (lists of arrays or stores); the normalised training sequences are
    memory-mapped in a temporary folder in ``data_dir`` (default: the system's)."""
    with tempfile.TemporaryDirectory(prefix="ferstl-mogan-data-", dir=data_dir) as tmp:
        return _train(speech, positions, phases, arm_columns, config, stages, seed, val, budget_seconds, on_step,
                      pathlib.Path(tmp))


def _train(speech: Sequence[np.ndarray], positions: Sequence[np.ndarray], phases: Sequence[np.ndarray],
           arm_columns: Sequence[int], config: MoganConfig, stages: MoganStages, seed: int,
           val: tuple[Sequence[np.ndarray], Sequence[np.ndarray], Sequence[np.ndarray]] | None,
           budget_seconds: float | None, on_step: Callable[[dict], None] | None,
           folder: pathlib.Path) -> TrainedMogan:
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    history: list[dict] = []
    stopped: list[str] = []
    t0 = time.perf_counter()

    def deadline(k: int) -> float | None:   # the cumulative share k of the budget, in seconds after t0
        return None if budget_seconds is None else budget_seconds * stages.budget_shares[k]

    def stage_loop(name: str, k: int, epochs: int, state: dict) -> EpochLoop:   # resumable stage k
        return EpochLoop(name, epochs, state, history=history, on_epoch=on_step, budget_seconds=deadline(k),
                         started=t0, stopped=stopped)

    def late(stage: int, name: str) -> bool:   # the discriminators' pre-training (not resumable: re-run)
        if (limit := deadline(stage)) is None or time.perf_counter() - t0 < limit:
            return False
        if name not in stopped:
            stopped.append(name)
            log({"stage": name, "stopped": BUDGET_SPENT})
        return True

    def log(record: dict) -> None:
        record["seconds"] = time.perf_counter() - t0
        history.append(record)
        if on_step is not None:
            on_step(record)

    (smean, sstd), (pmean, pstd) = mean_std(speech), mean_std(positions)
    sstd, pstd = np.maximum(sstd, 1e-6), floored_spread(pstd, stages.scale_floor)
    X = Sequences(SegmentStore(folder / "speech.npy", (((s - smean) / sstd).astype(np.float32) for s in speech)),
                   config.sequence)
    Y = Sequences(SegmentStore(folder / "positions.npy", (((p - pmean) / pstd).astype(np.float32)
                                                           for p in positions)), config.sequence)
    L = Sequences(SegmentStore(folder / "phases.npy", (np.asarray(p, np.int64).reshape(len(p), 1) for p in phases)),
                   config.sequence, squeeze=True)
    if not len(X):
        raise ValueError(f"no training segment has {config.sequence} frames for a sequence")
    F = torch.from_numpy(X.follows)
    arm = torch.as_tensor(np.asarray(arm_columns, np.int64))
    n = len(X)
    bce = nn.BCEWithLogitsLoss()

    def batches(size: int):
        # runs of consecutive windows, so that the discontinuity penalty sees neighbours
        start = int(rng.integers(0, max(n - size, 0) + 1))
        return torch.arange(start, min(start + size, n))

    # (1) phase classifier on real motion
    clf = PhaseClassifier(config)
    opt = torch.optim.Adam(clf.parameters(), lr=stages.learning_rate)
    loop = stage_loop("phase classifier", 0, stages.classifier_epochs, {"classifier": clf, "opt": opt, "rng": rng})
    for epoch in loop:
        clf.train()
        for idx in torch.from_numpy(rng.permutation(n)).split(stages.batch_size):
            logits = clf(_classifier_input(Y[idx], X[idx][..., -1], arm))
            loss = nn.functional.cross_entropy(logits.reshape(-1, config.n_phases), L[idx].reshape(-1))
            opt.zero_grad()
            loss.backward()
            opt.step()
        if loop.end({"stage": "phase classifier", "epoch": epoch + 1, "train_loss": loss.item()}):
            break
    clf.eval()
    for p in clf.parameters():
        p.requires_grad_(False)
    f1 = float("nan")
    held: tuple[torch.Tensor, torch.Tensor] | None = None   # held-out (speech, positions) sequences
    if val is not None:
        vx, _ = sequences([((s - smean) / sstd).astype(np.float32) for s in val[0]], config.sequence)
        vy, _ = sequences([((p - pmean) / pstd).astype(np.float32) for p in val[1]], config.sequence)
        vl, _ = sequences([np.asarray(p, np.int64) for p in val[2]], config.sequence)
        held = torch.from_numpy(vx), torch.from_numpy(vy)
        with torch.no_grad():
            pred = clf(_classifier_input(held[1], held[0][..., -1], arm)).argmax(-1)
        f1 = weighted_f1(vl.reshape(-1), pred.numpy().reshape(-1), config.n_phases)
        log({"stage": "phase classifier", "val_weighted_f1": f1})

    def val_mse(g: Generator) -> dict:
        """The generator's MSE on the held-out sequences (noise channels at zero, so that measuring draws no
        random numbers and leaves training as it would be without it)."""
        if held is None:
            return {}
        g.eval()
        with torch.no_grad():
            out = g(held[0], torch.zeros(len(held[0]), config.sequence, config.noise_dim))
        return {"val_mse": float(nn.functional.mse_loss(out, held[1]))}

    def noise(b: int, t: int) -> torch.Tensor:
        return torch.randn(b, t, config.noise_dim)

    # (2) generator pre-training with MSE, keeping its history
    gen = Generator(config)
    gen.set_phase("pretrain")
    opt = torch.optim.Adam(gen.parameters(), lr=stages.learning_rate)
    snapshots = [copy.deepcopy(gen.state_dict())]
    every = max(1, stages.pretrain_epochs // stages.snapshots)
    loop = stage_loop("generator MSE pre-training", 1, stages.pretrain_epochs,
                      {"generator": gen, "opt": opt, "rng": rng, "snapshots": snapshots})
    for epoch in loop:
        gen.train()
        for idx in torch.from_numpy(rng.permutation(n)).split(stages.batch_size):
            loss = nn.functional.mse_loss(gen(X[idx], noise(len(idx), config.sequence)), Y[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
        cut = loop.out_of_time()
        if (epoch + 1) % every == 0 or cut:
            snapshots.append(copy.deepcopy(gen.state_dict()))
        if loop.end({"stage": "generator MSE pre-training", "epoch": epoch + 1, "train_loss": loss.item(),
                     **val_mse(gen)}, late=cut):
            break
    if "mse_only" in stages.discriminators or not stages.discriminators:
        gen.eval()
        return TrainedMogan(config, gen, clf, smean, sstd, pmean, pstd, np.asarray(arm_columns), f1, history,
                            stopped)

    width = config.discriminator_width
    discs: dict[str, nn.Module] = {
        "phase": SequenceDiscriminator(config.n_phases + 1, width),
        "realism": SequenceDiscriminator(config.pose_dim + config.speech_dim, width),
        "minibatch": MinibatchDiscriminator(config),
        "displacement": SequenceDiscriminator(config.arm_dim, width),
    }
    active = [k for k in WEIGHTS if k in stages.discriminators]

    def disc_input(name: str, pos: torch.Tensor, sp: torch.Tensor) -> torch.Tensor:
        if name == "phase":
            probs = torch.softmax(clf(_classifier_input(pos, sp[..., -1], arm)), -1)
            return torch.cat([probs, sp[..., -1:]], -1)
        if name == "realism":
            return torch.cat([pos, sp], -1)
        if name == "minibatch":
            return pos
        a = pos[..., arm]
        return torch.diff(a, dim=1, prepend=a[:, :1])

    def d_step(name: str, d_opt: torch.optim.Optimizer, fake_pos: torch.Tensor, idx: torch.Tensor) -> float:
        d = discs[name]
        real = d(disc_input(name, Y[idx], X[idx]))
        fake = d(disc_input(name, fake_pos.detach(), X[idx]))
        loss = bce(real, torch.ones_like(real)) + bce(fake, torch.zeros_like(fake))
        d_opt.zero_grad()
        loss.backward()
        d_opt.step()
        return float(((real > 0).float().mean() + (fake < 0).float().mean()) / 2)

    d_opts = {k: torch.optim.RMSprop(discs[k].parameters(), lr=stages.adversarial_learning_rate) for k in active}
    # (3) phase discriminator against the generator's pre-training history
    if "phase" in active:
        shadow = Generator(config)
        for k, snap in enumerate(snapshots[1:], 1):
            shadow.load_state_dict(snap)
            shadow.eval()
            streak, tries, acc = 0, 0, float("nan")
            while streak < 3 and tries < stages.phase_pretrain_tries and not late(2, "discriminator pre-training"):
                idx = batches(stages.batch_size)
                with torch.no_grad():
                    fake = shadow(X[idx], noise(len(idx), config.sequence))
                acc = d_step("phase", d_opts["phase"], fake, idx)
                streak = streak + 1 if acc >= 0.7 else 0
                tries += 1
            log({"stage": "phase discriminator pre-training", "snapshot": k, "accuracy": acc})
    # (4) motion-realism discriminator against a fresh generator
    if "realism" in active:
        fresh = Generator(config)
        f_opt = torch.optim.RMSprop(fresh.parameters(), lr=stages.adversarial_learning_rate)
        for _ in range(stages.realism_pretrain_steps):
            if late(2, "discriminator pre-training"):
                break
            idx = batches(stages.batch_size)
            fake = fresh(X[idx], noise(len(idx), config.sequence))
            d_step("realism", d_opts["realism"], fake, idx)
            out = discs["realism"](disc_input("realism", fake, X[idx]))
            g_loss = bce(out, torch.ones_like(out))
            f_opt.zero_grad()
            g_loss.backward()
            f_opt.step()
        log({"stage": "realism discriminator pre-training", "steps": stages.realism_pretrain_steps})
    # (5) adversarial training
    if stages.discriminator_learning_rate is not None:
        for d_opt in d_opts.values():
            for group in d_opt.param_groups:
                group["lr"] = stages.discriminator_learning_rate
    gen.set_phase("adversarial")
    g_opt = torch.optim.RMSprop(gen.parameters(), lr=stages.adversarial_learning_rate)
    mse_opt = torch.optim.RMSprop(gen.parameters(), lr=stages.adversarial_learning_rate)
    total_w = sum(WEIGHTS[k] for k in active)
    state = {"generator": gen, "g_opt": g_opt, "mse_opt": mse_opt, "rng": rng,
             **{f"d_{k}": discs[k] for k in active}, **{f"d_{k}_opt": d_opts[k] for k in active}}
    loop = stage_loop("adversarial", 3, stages.adversarial_steps, state)  # resumed: discriminators re-pretrained, then loaded
    for step in loop:
        gen.train()
        idx = batches(stages.batch_size)
        fake = gen(X[idx], noise(len(idx), config.sequence))
        accs = {k: d_step(k, d_opts[k], fake, idx) for k in active}
        g_loss = sum(WEIGHTS[k] * bce(o := discs[k](disc_input(k, fake, X[idx])), torch.ones_like(o))
                     for k in active) / total_w
        g_opt.zero_grad()
        g_loss.backward()
        g_opt.step()
        if step % 2 == 1:  # one MSE correction per two adversarial steps, with the discontinuity penalty
            out = gen(X[idx], noise(len(idx), config.sequence))
            mse = nn.functional.mse_loss(out, Y[idx])
            follows = F[idx][1:]
            if follows.any():
                jump = (out[1:, 0] - out[:-1, -1]).pow(2).mean(-1)
                mse = mse + stages.discontinuity_weight * (jump * follows).sum() / follows.sum()
            mse_opt.zero_grad()
            mse.backward()
            mse_opt.step()
        if loop.end({"stage": "adversarial", "step": step + 1, "generator_loss": g_loss.item(),
                     **{f"d_{k}_accuracy": v for k, v in accs.items()}},
                    log=step % 50 == 0 or step == stages.adversarial_steps - 1):
            break
    gen.eval()
    return TrainedMogan(config, gen, clf, smean, sstd, pmean, pstd, np.asarray(arm_columns), f1, history, stopped)


@torch.no_grad()
def generate_mogan(model: TrainedMogan, speech: np.ndarray, seed: int = 0) -> np.ndarray:
    """(T, 27) speech -> (T, pose_dim) positions; the GRU runs over the whole segment (continuous output)."""
    gen = torch.Generator().manual_seed(seed)
    x = torch.from_numpy(((speech - model.speech_mean) / model.speech_std).astype(np.float32))[None]
    z = torch.randn(1, len(speech), model.config.noise_dim, generator=gen)
    out = model.generator(x, z)[0].numpy()
    return out.astype(np.float64) * model.pose_std + model.pose_mean
