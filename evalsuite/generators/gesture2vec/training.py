"""Training and generation for the Gesture2Vec re-implementation, on plain arrays.

Per segment: ``poses`` (T, D) at the model's frame rate and ``words``: a list of (embedding (E,), start
seconds). Training runs the paper's three stages in order (§4): the frame autoencoder, the VQ-DVAE (then its
decoder alone, with the rest frozen: the paper's "weakened decoder" schedule), and the translation model.

With ``budget_seconds`` each stage must end by a cumulative share of the budget (``G2VStages.budget_shares``:
10 % frame autoencoder, 45 % VQ-DVAE, 45 % translation; time a stage leaves unused goes to the later ones): a
stage that reaches its deadline stops after the current epoch, the next stage starts, and the history row says
``"stopped": "time budget spent"``. With validation data each epoch also reports ``val_loss`` (the stage's loss on
the validation segments, no noise and no dropout).
"""
from __future__ import annotations

import pathlib
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from torch import nn

from evalsuite.generators.datastream import Rows, SegmentStore, Windows, max_abs_deviation, mean_std, training_folder
from evalsuite.generators.epoch_loop import EpochLoop
from evalsuite.generators.gesture2vec.data import (
    WordTrack,
    _aligned,
    _latent_chunks,
    _pad_words,
    _translation_pairs,
    _window_words,
)
from evalsuite.generators.gesture2vec.net import VQDVAE, FrameDAE, G2VConfig, Translator
from evalsuite.generators.gesture2vec.options import OPTIONS
from evalsuite.generators.scaling import floored_spread

__all__ = ["G2VStages", "TrainedG2V", "train_gesture2vec", "generate_gesture2vec", "code_perplexity",
           "WordTrack", "latent_windows"]


_D = OPTIONS.defaults()   # each option's default declared once, in options.py (the cpu-small preset)


@dataclass(frozen=True)
class G2VStages:
    """The stages' lengths and rates: the plug-in's options (their declared defaults; the translation stage's rate
    is ``learning_rate`` unless given), and ``budget_shares`` of the three stages."""

    dae_epochs: int = _D["dae_epochs"]
    vq_epochs: int = _D["vq_epochs"]
    vq_decoder_epochs: int = _D["vq_decoder_epochs"]
    translation_epochs: int = _D["translation_epochs"]
    learning_rate: float = _D["learning_rate"]
    translation_learning_rate: float = _D["learning_rate"]
    batch_size: int = _D["batch_size"]
    reset_dead_codes: bool = _D["reset_dead_codes"]   # codes unused in a VQ epoch restart at a random chunk's encoding
    scale_floor: float = _D["scale_floor"]            # a dimension's range is at least this fraction of the widest one's
    budget_shares: tuple[float, float, float] = (0.10, 0.45, 0.45)
    weakened_decoder: bool = _D["weakened_decoder"]   # the paper's §4.3: the decoder frozen in the first VQ-DVAE stage


@dataclass
class TrainedG2V:
    config: G2VConfig
    fps: float
    dae: FrameDAE
    vq: VQDVAE
    translator: Translator
    pose_mean: np.ndarray
    pose_scale: np.ndarray
    code_counts: np.ndarray
    history: list[dict] = field(default_factory=list)
    train_chunks: Mapping[int, Any] = field(default_factory=dict)  # per code: its clips (n, chunk, D), retrieval
    stopped: list[str] = field(default_factory=list)                         # stages cut by the budget
    data: Any = None                                                         # the training maps' folder


def code_perplexity(counts: np.ndarray) -> float:
    """exp(entropy) of the code-usage distribution: K when every code is used equally, 1 when one is."""
    p = counts / max(counts.sum(), 1)
    p = p[p > 0]
    return float(np.exp(-(p * np.log(p)).sum()))


def _batches(n: int, size: int, rng: np.random.Generator):
    order = rng.permutation(n)
    for i in range(0, n, size):
        yield torch.from_numpy(order[i:i + size])


def train_gesture2vec(poses: Sequence[np.ndarray], words: Sequence[WordTrack], config: G2VConfig, fps: float,
                      stages: G2VStages = G2VStages(), *, seed: int = 0,
                      val_poses: Sequence[np.ndarray] = (), val_words: Sequence[WordTrack] = (),
                      budget_seconds: float | None = None, on_epoch: Callable[[dict], None] | None = None,
                      data_dir: pathlib.Path | None = None) -> TrainedG2V:
    """The three stages on segments (lists or stores). The training split's normalised poses, latents, chunks and
    word windows are memory-mapped in a temporary folder in ``data_dir`` (default: a
    :func:`~evalsuite.generators.datastream.training_folder`), removed when the model is no longer used (the
    retrieval pool's clips are views of the poses' map)."""
    data = (tempfile.TemporaryDirectory(prefix="gesture2vec-data-", dir=data_dir) if data_dir is not None
            else training_folder("gesture2vec"))
    folder = pathlib.Path(data.name)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    history: list[dict] = []
    stopped: list[str] = []
    start_time = time.perf_counter()
    shares = np.cumsum(stages.budget_shares) / sum(stages.budget_shares)

    def stage_loop(name: str, k: int, epochs: int, state: dict) -> EpochLoop:
        """Stage ``k``'s loop: its deadline is the cumulative share ``k`` of the budget."""
        deadline = None if budget_seconds is None else budget_seconds * shares[k]
        return EpochLoop(name, epochs, state, history=history, on_epoch=on_epoch, budget_seconds=deadline,
                         started=start_time, stopped=stopped)

    mean = mean_std(poses)[0]   # one segment at a time, the concatenation's figures bit for bit
    # mean 0, max |x| 1 (paper §4.1), but a rotation-matrix entry that hardly moves (idle sway) is not stretched
    # to +-1 (evalsuite.generators.scaling)
    scale = floored_spread(max_abs_deviation(poses, mean), stages.scale_floor)
    norm = SegmentStore(folder / "poses.npy", (((p - mean) / scale).astype(np.float32) for p in poses))
    vnorm = [((p - mean) / scale).astype(np.float32) for p in val_poses]
    # 1. frame autoencoder
    dae = FrameDAE(config)
    x = Rows(norm)
    vx = torch.from_numpy(np.concatenate(vnorm)) if vnorm else None
    opt = torch.optim.Adam(dae.parameters(), lr=stages.learning_rate)
    # resumable: each state holds everything its stage's next epoch depends on
    loop = stage_loop("frame autoencoder", 0, stages.dae_epochs, {"dae": dae, "opt": opt, "rng": rng})
    for epoch in loop:
        dae.train()
        total = 0.0
        for idx in _batches(len(x), stages.batch_size, rng):
            xb = torch.from_numpy(x[idx.numpy()])
            loss = nn.functional.mse_loss(dae(xb), xb)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        rec: dict = {"stage": "frame autoencoder", "epoch": epoch + 1, "train_loss": total / len(x)}
        if vx is not None:
            dae.eval()
            with torch.no_grad():
                rec["val_loss"] = nn.functional.mse_loss(dae(vx), vx).item()
        if loop.end(rec):
            break
    dae.eval()
    with torch.no_grad():
        latents = SegmentStore(folder / "latents.npy", (dae.encoder(torch.from_numpy(np.array(p))).numpy()
                                                        for p in norm))
        vlatents = [dae.encoder(torch.from_numpy(p)).numpy() for p in vnorm]
    # 2. VQ-DVAE, then its decoder alone: chunks of the latents and their frame differences
    chunks = Windows(SegmentStore(folder / "latent_chunks.npy", (np.concatenate(
        [lat, np.diff(lat, axis=0, prepend=lat[:1])], axis=1).astype(np.float32) for lat in latents)),
        config.chunk, config.stride)
    if not len(chunks):
        raise ValueError(f"no segment has {config.chunk} frames for a VQ-DVAE chunk")

    def ct(idx: Any) -> torch.Tensor:
        return torch.from_numpy(chunks[np.asarray(idx)])
    vchunks = [_latent_chunks(lat, config.chunk, config.stride) for lat in vlatents]
    vct = torch.from_numpy(np.concatenate(vchunks).astype(np.float32)) if sum(map(len, vchunks)) else None
    vq = VQDVAE(config)
    # start the codebook from encoder outputs of random chunks, so that no code starts unused
    with torch.no_grad():
        z0 = vq.encode(ct(rng.choice(len(chunks), config.codebook, replace=len(chunks) < config.codebook)))
        vq.codebook.weight.copy_(z0 + 0.01 * torch.randn_like(z0))
    decoder = [*vq.decoder.parameters(), *vq.out.parameters()]
    for p in decoder:  # weakened decoder: no gradient reaches it, the encoder carries the reconstruction
        p.requires_grad_(not stages.weakened_decoder)
    opt = torch.optim.Adam([p for p in vq.parameters() if p.requires_grad], lr=stages.learning_rate)
    decoder_opt = torch.optim.Adam(decoder, lr=stages.learning_rate)
    total_vq = stages.vq_epochs + stages.vq_decoder_epochs
    loop = stage_loop("vq-dvae", 1, total_vq, {"vq": vq, "opt": opt, "decoder_opt": decoder_opt, "rng": rng})
    for epoch in loop:
        decoder_only = epoch >= stages.vq_epochs
        if decoder_only and opt is not decoder_opt:  # the decoder alone from here on (also when resumed here)
            for p in [*vq.encoder.parameters(), *vq.codebook.parameters()]:
                p.requires_grad_(False)
            for p in decoder:
                p.requires_grad_(True)
            opt = decoder_opt
        vq.train()
        total, counts = 0.0, np.zeros(config.codebook)
        for idx in _batches(len(chunks), stages.batch_size, rng):
            cb = ct(idx.numpy())
            recon, codes, vq_loss = vq(cb)
            loss = nn.functional.mse_loss(recon, cb) + (0 if decoder_only else vq_loss)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
            counts += np.bincount(codes.numpy(), minlength=config.codebook)
        if stages.reset_dead_codes and not decoder_only and epoch < stages.vq_epochs - 1:
            dead = np.flatnonzero(counts == 0)
            if len(dead):
                with torch.no_grad():
                    z = vq.encode(ct(rng.choice(len(chunks), len(dead), replace=len(chunks) < len(dead))))
                    vq.codebook.weight[torch.from_numpy(dead)] = z + 0.01 * torch.randn_like(z)
        stage = "vq-dvae decoder" if decoder_only else "vq-dvae"
        rec = {"stage": stage, "epoch": epoch + 1,
               "train_loss": total / len(chunks), "perplexity": code_perplexity(counts)}
        if vct is not None:
            vq.eval()
            with torch.no_grad():
                recon, _, vq_loss = vq(vct)
                rec["val_loss"] = (nn.functional.mse_loss(recon, vct) + (0 if decoder_only else vq_loss)).item()
        # out of time: a cut encoder stage still gets one decoder epoch (the decoder must fit the codes)
        if loop.end(rec, budget_next=stages.vq_epochs if not decoder_only and stages.vq_decoder_epochs else None):
            break
    vq.eval()
    # 3. translation: word windows (one every `stride` frames) -> codes of each window's non-overlapping chunks
    train_chunks: dict[int, Sequence[np.ndarray]] = {}
    srcs, tgts, al = _translation_pairs(vq, latents, words, config, fps, norm, train_chunks, folder)
    vsrcs, vtgts, val_al = _translation_pairs(vq, vlatents, val_words, config, fps)
    if not len(srcs):
        raise ValueError(f"no segment has {config.chunk * config.chunks_per_window} frames for a translation window")
    code_counts = np.bincount(tgts.reshape(-1), minlength=config.codebook)
    translator = Translator(config)
    opt = torch.optim.Adam(translator.parameters(), lr=stages.translation_learning_rate)
    targets = torch.from_numpy(tgts.astype(np.int64))
    ce = nn.functional.cross_entropy
    loop = stage_loop("translation", 2, stages.translation_epochs, {"translator": translator, "opt": opt, "rng": rng})
    for epoch in loop:
        translator.train()
        total = 0.0
        for idx in _batches(len(srcs), stages.batch_size, rng):
            wx, mask = _pad_words(srcs.take(idx.tolist()), config.text_dim)
            logits = translator(wx, mask, targets[idx], torch.from_numpy(al[idx.numpy()]))
            loss = ce(logits.reshape(-1, config.codebook), targets[idx].reshape(-1))
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        rec = {"stage": "translation", "epoch": epoch + 1, "train_loss": total / len(srcs)}
        if vsrcs:
            translator.eval()
            with torch.no_grad():
                wx, mask = _pad_words(vsrcs, config.text_dim)
                vt = torch.from_numpy(vtgts.astype(np.int64))
                logits = translator(wx, mask, vt, torch.from_numpy(np.stack(val_al)))
                rec["val_loss"] = ce(logits.reshape(-1, config.codebook), vt.reshape(-1)).item()
                rec["val_code_error"] = float((logits.argmax(-1) != vt).float().mean())
        if loop.end(rec):
            break
    translator.eval()
    model = TrainedG2V(config, fps, dae, vq, translator, mean, scale, code_counts, history, train_chunks, stopped)
    model.data = data   # the folder lives as long as the model (its pool's clips are views of a map)
    return model


@torch.no_grad()
def latent_windows(model: TrainedG2V, poses: np.ndarray, stride: int | None = None) -> np.ndarray:
    """The VQ-DVAE encoder's continuous output z (before quantisation) of every ``chunk``-frame window of one
    pose sequence (T, D), every ``stride`` frames (default the model's): (N, 2 * vq_hidden)."""
    c = model.config
    norm = ((np.asarray(poses) - model.pose_mean) / model.pose_scale).astype(np.float32)
    lat = model.dae.encoder(torch.from_numpy(norm)).numpy()
    feats = _latent_chunks(lat, c.chunk, stride or c.stride)
    if not len(feats):
        return np.zeros((0, model.vq.code_dim), np.float32)
    return model.vq.encode(torch.from_numpy(feats.astype(np.float32))).numpy()


@torch.no_grad()
def generate_gesture2vec(model: TrainedG2V, words: WordTrack, n_frames: int, *, seed: int = 0,
                         temperature: float = 0.0, retrieval: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Poses (n_frames, D) and the predicted codes for one segment.

    Generative decoding: codes -> VQ-DVAE decoder -> frame decoder. With ``retrieval`` each code is replaced
    by a random training chunk of that code (the original repository's decoding), seeded."""
    c = model.config
    win = c.chunk * c.chunks_per_window
    n_windows = max(1, -(-n_frames // win))
    gen = torch.Generator().manual_seed(seed)
    rng = np.random.default_rng(seed)
    srcs = [_window_words(words, w * win / model.fps, win / model.fps, c.text_dim) for w in range(n_windows)]
    wx, mask = _pad_words(srcs, c.text_dim)
    al = np.stack([_aligned(words, w * win / model.fps, c.chunk / model.fps, c.chunks_per_window, c.text_dim)
                   for w in range(n_windows)])
    codes = model.translator.generate(wx, mask, c.chunks_per_window, gen, temperature,
                                      torch.from_numpy(al)).reshape(-1)
    if retrieval:
        pieces = []
        for code in codes.tolist():
            pool = model.train_chunks.get(int(code))
            pieces.append(pool[int(rng.integers(len(pool)))] if pool is not None and len(pool)
                          else np.zeros((c.chunk, c.pose_dim), np.float32))
        norm = np.concatenate(pieces)
    else:
        # a conditioned decoder carries its last frame across chunks, starting from the mean pose at rest
        start = torch.cat([model.dae.encoder(torch.zeros(1, c.pose_dim))[0], torch.zeros(c.latent_dim)])
        latent = model.vq.decode_sequence(model.vq.codebook(codes), start)[..., :c.latent_dim]
        norm = model.dae.decoder(latent.reshape(-1, c.latent_dim)).numpy()
    poses = norm[:n_frames] * model.pose_scale + model.pose_mean
    return poses.astype(np.float64), codes.numpy()
