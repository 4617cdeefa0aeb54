"""Attention-check stimuli made from any normal stimulus video.

Three kinds, as used in the seed papers' and GENEA's studies:

* ``distorted_audio``: the same video with the speech heavily distorted
  (:func:`renderers.audio.distort_audio`); an attentive rater rates it at the bottom.
* ``distorted_video``: the same audio with the picture heavily distorted (coarse
  pixelation, colour-channel swap, noise and frame-to-frame jitter).
* ``instruction``: the same clip with a boxed instruction appearing ``appear_s`` seconds in
  ("Attention: please rate this video 73", "Attention: select the left video"); the
  expected answer is the one the text asks for.
"""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.errors import InputError
from renderers.audio import decode_audio, distort_audio
from renderers.layout import Overlay
from renderers.media_probe import probe
from renderers.video import VideoWriter, read_video_frames

CHECKS = ("distorted_audio", "distorted_video", "instruction")
DEFAULT_TEXT = "Attention: please rate this video 73"


def distort_frame(frame: np.ndarray, rng: np.random.Generator, block: int) -> np.ndarray:
    """Heavy picture distortion of one frame: pixelate by ``block``, swap colour channels,
    add strong noise and shift the picture by a random offset (jitter across frames)."""
    h, w, _ = frame.shape
    hp, wp = -(-h // block) * block, -(-w // block) * block
    padded = np.pad(frame.astype(np.float32), ((0, hp - h), (0, wp - w), (0, 0)), mode="edge")
    coarse = padded.reshape(hp // block, block, wp // block, block, 3).mean(axis=(1, 3))
    pix = np.repeat(np.repeat(coarse, block, axis=0), block, axis=1)[:h, :w]
    pix = pix[..., ::-1]                                   # RGB -> BGR
    noisy = pix + rng.normal(0.0, 60.0, size=pix.shape)
    dy, dx = rng.integers(-block, block + 1, size=2)
    shifted = np.roll(noisy, (int(dy), int(dx)), axis=(0, 1))
    return np.clip(shifted, 0, 255).astype(np.uint8)


def make_attention_check(src, out, check: str, *, text: str | None = None, appear_s: float = 3.0,
                         seed: int = 0, crf: int = 20, bitrate: str | None = None) -> dict:
    """Write an attention-check version of video ``src`` to ``out``; returns its info.

    The frame count, frame rate and audio length are those of ``src``. For ``instruction``
    the overlay appears at ``appear_s`` seconds, or at 40% of a shorter clip. ``bitrate``: constant-bitrate
    encoding instead of ``crf``.
    """
    if check not in CHECKS:
        raise InputError(f"unknown attention check {check!r}; expected one of {', '.join(CHECKS)}", field="check")
    src, out = pathlib.Path(src), pathlib.Path(out)
    if not src.is_file():
        raise InputError("no such video", path=src)
    info = probe(src)
    if "video_codec" not in info:
        raise InputError("no video stream found", path=src)
    audio = None
    if "audio_codec" in info:
        samples, rate = decode_audio(src, sample_rate=info["audio_rate"])
        if check == "distorted_audio":
            samples = distort_audio(samples, rate, seed=seed)
        audio = (samples, rate)
    elif check == "distorted_audio":
        raise InputError("the video has no audio to distort", path=src)
    rng = np.random.default_rng(seed)
    frames = read_video_frames(src)
    meta, first = next(frames)
    fps = float(meta["fps"])
    w, h = meta["size"]
    duration = float(meta.get("duration") or info.get("duration") or 0.0)
    appear = min(appear_s, 0.4 * duration) if duration else appear_s
    overlay = Overlay(text or DEFAULT_TEXT, w, h) if check == "instruction" else None
    block = max(8, w // 24)
    n = 0
    with VideoWriter(out, w, h, fps, audio=audio, crf=crf, bitrate=bitrate) as writer:
        for i, frame in enumerate(_chain(first, frames)):
            if check == "distorted_video":
                frame = distort_frame(frame, rng, block)
            elif overlay is not None and i / fps >= appear - 1e-9:
                frame = overlay.apply(frame)
            writer.write(frame)
            n += 1
    return {"n_frames": n, "fps": fps, "width": w, "height": h, "duration": n / fps,
            "appear_s": appear if check == "instruction" else None}


def _chain(first, rest):
    yield first
    for _, frame in rest:
        yield frame
