"""Small placeholder stimuli: blinded MP4 files plus a manifest, for demos and tests.

The videos are tiny H.264 clips written with imageio-ffmpeg (a moving bar whose colour and
speed differ per condition and segment). Attention-check clips show a text instruction that
appears only after the first part of the clip, as the real checks do.
"""
from __future__ import annotations

import csv
import hashlib
import pathlib
from collections.abc import Sequence

import numpy as np

WIDTH, HEIGHT = 160, 120


def _text_image(text: str, width: int, height: int) -> np.ndarray:
    """White-on-black text rendered with matplotlib (Agg), as a (H, W) float mask in 0..1."""
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    canvas = FigureCanvasAgg(fig)
    fig.patch.set_facecolor("black")
    fig.text(0.5, 0.5, text, color="white", ha="center", va="center", fontsize=7, wrap=True)
    canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())[:height, :width, 0]
    return rgba.astype(np.float64) / 255.0


def write_clip(path, seed: int, seconds: float = 1.0, fps: int = 10, text: str | None = None,
               text_from: float = 0.4, size: tuple[int, int] = (WIDTH, HEIGHT)):
    """Write one placeholder clip of ``size`` (width, height; multiples of 8); ``text`` is overlaid from
    ``text_from`` of its duration."""
    import imageio_ffmpeg

    width, height = size

    n = max(2, int(round(seconds * fps)))
    rng = np.random.default_rng(seed)
    colour = rng.integers(60, 255, size=3)
    speed = rng.uniform(0.5, 2.0)
    t = np.arange(n)[:, None]
    x = np.arange(width)[None, :]
    # A vertical bar sweeping across the frame: one boolean mask per frame, no per-frame loop.
    centre = ((t * speed * width / n) + rng.integers(0, width)) % width
    bar = np.abs(x - centre) < 12                                     # (n, W)
    frames = np.zeros((n, height, width, 3), np.uint8)
    frames[:] = (colour // 4).astype(np.uint8)
    frames[np.broadcast_to(bar[:, None, :], (n, height, width))] = colour.astype(np.uint8)
    if text:
        mask = _text_image(text, width, height) > 0.5
        start = int(n * text_from)
        frames[start:, :, :, :] = (frames[start:] * 0.3).astype(np.uint8)
        frames[start:][:, mask] = 255
    writer = imageio_ffmpeg.write_frames(str(path), (width, height), fps=fps, codec="libx264",
                                         pix_fmt_out="yuv420p", macro_block_size=8,
                                         output_params=["-movflags", "+faststart"],
                                         ffmpeg_log_level="error")
    writer.send(None)
    for f in frames:
        writer.send(np.ascontiguousarray(f))
    writer.close()


def _attention_text(expected: str) -> str:
    """The instruction an attention-check clip shows for its expected answer."""
    if expected.isdigit():
        return f"Attention!\nRate this video {expected}"
    side, _, strength = expected.partition("_")
    words = {"this": "Choose this video", "other": "Choose the other video",
             "left": "Choose the left video", "right": "Choose the right video",
             "equal": "Answer: they are equal"}
    if side in words:
        return "Attention!\n" + words[side] + (f" ({strength})" if strength else "")
    return f"Attention!\nRate this video\n{expected}"


def blinded_name(*parts) -> str:
    return hashlib.sha256("|".join(map(str, parts)).encode()).hexdigest()[:12] + ".mp4"


def make_sample_stimuli(folder, conditions, segments, *, mismatched=False,
                        attention: Sequence[tuple[str, str]] = (), seconds: float = 1.0, fps: int = 10,
                        salt: str = "evalsuite", size: tuple[int, int] = (WIDTH, HEIGHT)) -> pathlib.Path:
    """Write clips and ``manifest.csv`` into ``folder``; returns the manifest path.

    ``attention`` lists ``(segment, expected)`` attention-check clips to add; ``mismatched``
    adds, for every condition and segment, a clip whose motion comes from the next segment; ``size``
    is the clips' (width, height), e.g. ``(256, 144)`` for 16:9.
    """
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    seed = 0
    for c in conditions:
        for i, s in enumerate(segments):
            name = blinded_name(salt, c, s)
            write_clip(folder / name, seed, seconds, fps, size=size)
            rows.append({"file": name, "condition": c, "segment": s})
            seed += 1
            if mismatched:
                other = segments[(i + 1) % len(segments)]
                name = blinded_name(salt, c, s, other)
                write_clip(folder / name, seed, seconds, fps, size=size)
                rows.append({"file": name, "condition": c, "segment": s, "motion_segment": other})
                seed += 1
    for k, (s, expected) in enumerate(attention):
        name = blinded_name(salt, "attention", s, expected, k)
        write_clip(folder / name, 1000 + k, seconds, fps, text=_attention_text(expected), size=size)
        rows.append({"file": name, "condition": "", "segment": s, "kind": "attention",
                     "expected": expected})
    path = folder / "manifest.csv"
    cols = ["file", "condition", "segment", "kind", "expected", "motion_segment"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow({c: r.get(c, "") for c in cols})
    return path
