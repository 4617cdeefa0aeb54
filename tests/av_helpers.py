"""Tiny stimuli with sound for the audio-mismatch and muted-pair tests: each segment's "speech" is a sine tone
of its own frequency (so a clip's sound says which segment it came from), muxed with a placeholder video."""
from __future__ import annotations

import csv
import pathlib
import subprocess

import numpy as np
from scipy.io import wavfile

RATE = 16000


def tone_hz(index: int) -> float:
    return 300.0 + 200.0 * index


def ffmpeg() -> str:
    import imageio_ffmpeg
    return imageio_ffmpeg.get_ffmpeg_exe()


def make_av_stimuli(folder, conditions, segments, *, seconds=1.0, attention=()) -> pathlib.Path:
    """Clips with sound for every condition x segment (segment ``i``'s speech: a tone of ``tone_hz(i)`` as long
    as its video, ``seconds`` or ``seconds[i]``), plus silent attention clips ``(segment, expected[, check])``; returns
    the manifest path."""
    from study_app.samples import blinded_name, write_clip

    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for i, seg in enumerate(segments):
        length = seconds[i] if isinstance(seconds, (list, tuple)) else seconds
        t = np.arange(int(length * RATE)) / RATE
        wavfile.write(folder / f"tone{i}.wav", RATE, (0.5 * 32767 * np.sin(2 * np.pi * tone_hz(i) * t)).astype(np.int16))
    for ci, c in enumerate(conditions):
        for i, seg in enumerate(segments):
            name = blinded_name("av", c, seg)
            video = folder / f"video-{name}"
            write_clip(video, 10 * ci + i, seconds[i] if isinstance(seconds, (list, tuple)) else seconds, 10)
            subprocess.run([ffmpeg(), "-nostdin", "-y", "-v", "error", "-i", str(video), "-i",
                            str(folder / f"tone{i}.wav"), "-map", "0:v:0", "-map", "1:a:0", "-c:v", "copy",
                            "-c:a", "aac", "-b:a", "64k", "-shortest", str(folder / name)], check=True)
            video.unlink()
            rows.append({"file": name, "condition": c, "segment": seg})
    for k, (seg, expected, *check) in enumerate(attention):
        name = blinded_name("av-attention", seg, expected, k)
        write_clip(folder / name, 1000 + k, 1.0, 10, text=f"Attention! {expected}")
        rows.append({"file": name, "condition": "", "segment": seg, "kind": "attention", "expected": expected,
                     "check": check[0] if check else "instruction"})
    for i in range(len(segments)):
        (folder / f"tone{i}.wav").unlink()
    path = folder / "manifest.csv"
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["file", "condition", "segment", "kind", "expected", "check"])
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in w.fieldnames})
    return path


def decode_audio(path) -> np.ndarray:
    """The clip's sound as mono float samples at :data:`RATE` (empty when it has none)."""
    proc = subprocess.run([ffmpeg(), "-nostdin", "-v", "error", "-i", str(path), "-vn", "-f", "s16le", "-ac", "1",
                           "-ar", str(RATE), "-"], capture_output=True)
    return np.frombuffer(proc.stdout, dtype=np.int16).astype(np.float64) / 32767


def dominant_hz(samples: np.ndarray) -> float:
    spectrum = np.abs(np.fft.rfft(samples * np.hanning(len(samples))))
    return float(np.fft.rfftfreq(len(samples), 1 / RATE)[int(np.argmax(spectrum))])
