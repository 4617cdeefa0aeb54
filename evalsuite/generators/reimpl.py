"""What the four re-implemented systems share: arrays from a corpus, torch set-up, weights on disk.

Per segment the systems read speech features (a recipe of :mod:`evalsuite.features`), optionally text
features (word vectors and Gesticulator's timing features), and poses in a :class:`PoseRepresentation`, all at
the representation's frame rate (20 fps, as the papers). Feature arrays go through the features cache.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus, Segment, Transcript
from evalsuite.errors import InputError
from evalsuite.generators.contract import GenerationRequest, GeneratorError
from evalsuite.generators.pose_repr import PoseRepresentation

__all__ = ["SegmentArrays", "speech_features", "text_features", "corpus_arrays", "torch_setup", "weights_sha256",
           "save_state", "load_state", "budget_seconds", "TEXT_OPTION", "request_arrays", "write_json", "read_json",
           "open_model_folder", "splits_for_training"]

TEXT_OPTION = ("word vectors: 'minilm' (default: all-MiniLM-L6-v2 from the text extra, contextual), "
               "'minilm-static', 'hash' (no model), 'bert:FOLDER', 'fasttext:FILE.vec'")


@dataclass
class SegmentArrays:
    """One segment's arrays at the representation's frame rate."""

    id: str
    audio: np.ndarray | None        # (T, A)
    text: np.ndarray | None         # (T, X)
    poses: np.ndarray               # (T, D); (0, 0) for a request (nothing to learn from)
    transcript: Transcript | None
    extra: dict[str, Any]

    @property
    def speech(self) -> np.ndarray:
        """Audio features, then text features, side by side ``(T, A + X)``."""
        parts = [a for a in (self.audio, self.text) if a is not None]
        if not parts:
            raise GeneratorError(f"segment {self.id!r}: no speech features")
        return np.concatenate(parts, axis=1).astype(np.float32)


def speech_features(audio: Any, recipe: str, fps: float, n_frames: int) -> np.ndarray:
    from evalsuite.features import extract

    return extract(recipe, audio, fps=fps, n_frames=n_frames)


def text_features(transcript: Transcript | None, fps: float, n_frames: int, words: str,
                  timing: bool = True) -> np.ndarray:
    """``(T, X)``: the word vector of the word spoken at each frame (0 in silence) and, with ``timing``,
    Gesticulator's five timing features. A missing transcript gives silence everywhere."""
    from evalsuite.features.embeddings import frame_embeddings, get_embedder
    from evalsuite.features.text import timing_features

    embedder = get_embedder(words)
    transcript = transcript if transcript is not None else Transcript(())
    parts = [frame_embeddings(transcript, fps, n_frames, model=embedder)]
    if timing:
        parts.append(timing_features(transcript, fps, n_frames))
    return np.concatenate(parts, axis=1).astype(np.float32)


def _n_frames(duration: float, fps: float) -> int:
    return int(round(duration * fps))


def corpus_arrays(segments: Sequence[Segment], rep: PoseRepresentation, *, audio_recipe: str | None,
                  words: str | None, timing: bool = True,
                  extra: Callable[[Segment, int], dict[str, Any]] | None = None) -> list[SegmentArrays]:
    """Poses, speech and text features of each segment, ``len(poses)`` frames each."""
    out = []
    for seg in segments:
        if seg.motion is None:
            raise InputError(f"segment {seg.id!r} has no motion to learn from")
        poses = rep.encode(seg.load_motion())
        n = len(poses)
        audio = speech_features(seg.audio, audio_recipe, rep.fps, n) if audio_recipe else None
        text = text_features(seg.transcript, rep.fps, n, words, timing) if words else None
        out.append(SegmentArrays(seg.id, audio, text, poses, seg.transcript, extra(seg, n) if extra else {}))
    return out


def request_arrays(req: GenerationRequest, fps: float, *, audio_recipe: str | None, words: str | None,
                   timing: bool = True, name: str = "") -> SegmentArrays:
    """Speech and text features of a request at ``fps`` (``round(duration * fps)`` frames)."""
    n = _n_frames(req.duration, fps)
    if audio_recipe and req.audio is None:
        raise GeneratorError(f"{name}, segment {req.segment_id!r}: needs audio")
    audio = speech_features(req.audio, audio_recipe, fps, n) if audio_recipe else None
    text = text_features(req.transcript, fps, n, words, timing) if words else None
    return SegmentArrays(req.segment_id, audio, text, np.zeros((0, 0), np.float32), req.transcript, {})


def torch_setup(seed: int, threads: int) -> Any:
    """torch, seeded, with a fixed number of threads (same seed and threads: same weights on one machine)."""
    try:
        import torch
    except ImportError:
        raise InputError('the re-implemented generators need PyTorch: pip install "evalsuite[learned]" '
                         "(torch 2.13.0, CPU build)") from None
    torch.set_num_threads(max(1, int(threads)))
    torch.manual_seed(seed)
    return torch


def weights_sha256(state: dict[str, Any]) -> str:
    """sha256 over a state dict's tensors (names, shapes, bytes) in order: equal hashes, equal weights."""
    h = hashlib.sha256()
    for name, t in state.items():
        arr = t.detach().cpu().numpy() if hasattr(t, "detach") else np.asarray(t)
        h.update(f"{name}{tuple(arr.shape)}{arr.dtype}".encode())
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def save_state(folder: pathlib.Path, name: str, module: Any) -> str:
    import torch

    state = module.state_dict()
    torch.save(state, folder / name)
    return weights_sha256(state)


def load_state(folder: pathlib.Path, name: str, module: Any) -> None:
    import torch

    path = folder / name
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise InputError("model file missing from the model folder", path=path, field="--model") from None
    module.load_state_dict(state)
    module.eval()


def budget_seconds(budget_minutes: float | None) -> float | None:
    return None if budget_minutes is None else 60.0 * float(budget_minutes)


def write_json(path: pathlib.Path, data: Any) -> None:
    path.write_text(json.dumps(data, indent=1, default=float), encoding="utf-8")


def read_json(path: pathlib.Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read the model's settings ({exc})", path=path, field="--model") from None


def open_model_folder(model_dir: pathlib.Path | None) -> tuple[dict[str, Any], PoseRepresentation]:
    """A re-implementation's model folder: its ``settings.json`` and pose representation; torch set up with
    the threads it was trained with (a clear message when torch is missing)."""
    if model_dir is None:
        raise GeneratorError("a model folder is needed (--model)", field="--model")
    saved = read_json(model_dir / "settings.json")
    torch_setup(0, int(saved.get("threads", 1)))
    return saved, PoseRepresentation.load(model_dir)


def splits_for_training(corpus: Corpus) -> tuple[tuple[Segment, ...], tuple[Segment, ...]]:
    """(train, val) segments: the corpus's train split, and its val split when it has one."""
    train = corpus.split("train")
    names = {s.split for s in corpus.segments}
    val = corpus.split("val") if "val" in names else ()
    return train, val
