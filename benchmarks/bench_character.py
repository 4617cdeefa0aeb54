"""Benchmark: the skinned character style (10,000 triangles) vs the stick figure, 640x480, H.264 at 30 fps.

Both render the bundled MocapBank clip (19 joints, 30 fps) to MP4 through ``render_video``; the time covers
building the mesh, posing + skinning every frame (numpy), rasterising (pyrender, EGL) and encoding. The stick
figure measured in the same run is the baseline (the ratio says how much the character costs on this machine,
whatever its load). "Whole process" runs a fresh Python that imports evalsuite, reads the BVH and writes the
video (interpreter start, imports and GL context included).

Target (issue 36): the character >= 1x real time at 640x480 (>= 30 fps of finished video).

    python benchmarks/bench_character.py [--frames 300] [--rounds 2]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

from evalsuite.motion.io import load_motion
from evalsuite.motion.ops import cut
from evalsuite.motion.samples import sample_path
from renderers.render import prepare_motions, render_video
from renderers.scene import RenderSettings

W, H = 640, 480

WHOLE = """
import sys
from evalsuite.motion.samples import sample_path
from renderers.render import prepare_motions, render_video
from renderers.scene import RenderSettings
s = RenderSettings(width={w}, height={h}, body="{body}")
m = prepare_motions([sample_path("mocapbank")], s, start=0.0, end={seconds})
render_video(m, sys.argv[1], s)
"""


def in_process(motion, out, body: str) -> float:
    settings = RenderSettings(width=W, height=H, body=body)
    t0 = time.perf_counter()
    render_video([motion], out, settings)
    return time.perf_counter() - t0


def whole_process(out, body: str, seconds: float) -> float:
    code = WHOLE.format(w=W, h=H, body=body, seconds=seconds)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, str(out)], check=True)
    return time.perf_counter() - t0


def skinning_only(motion) -> float:
    """Seconds per frame of posing + skinning alone (no rasterising), blocks of 64 frames."""
    from renderers.styles import STYLES

    mesh = STYLES["character"].mesh(motion, RenderSettings(body="character"), 1.0)
    pos = motion.positions()
    t0 = time.perf_counter()
    for i in range(0, len(pos), 64):
        mesh.vertices(pos[i:i + 64])
    return (time.perf_counter() - t0) / len(pos)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300, help="frames to render (at 30 fps)")
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds; the best of each counts")
    args = ap.parse_args()
    source = load_motion(sample_path("mocapbank"))
    seconds = args.frames / source.fps
    motion = prepare_motions([cut(source, 0.0, seconds)], RenderSettings(width=W, height=H))[0]
    n = motion.n_frames
    out = pathlib.Path(tempfile.mkdtemp(prefix="bench_character_"))
    in_process(prepare_motions([cut(source, 0, 0.3)], RenderSettings())[0], out / "warm.mp4", "character")
    runs = {
        "stick figure, in process": lambda: in_process(motion, out / "stick.mp4", "stick"),
        "character, in process": lambda: in_process(motion, out / "character.mp4", "character"),
        "stick figure, whole process": lambda: whole_process(out / "stick_w.mp4", "stick", seconds),
        "character, whole process": lambda: whole_process(out / "character_w.mp4", "character", seconds),
    }
    best = {name: np.inf for name in runs}
    for _ in range(args.rounds):
        for name, run in runs.items():
            best[name] = min(best[name], run())
    skin_ms = 1000 * skinning_only(motion)
    load = os.getloadavg()
    print(f"Single figure, {W}x{H}, {n} frames ({n / motion.fps:.1f} s at {motion.fps:g} fps), "
          f"render + H.264 encode; best of {args.rounds} rounds")
    print(f"CPU: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} (shared machine)")
    print(f"{'renderer':30s} {'seconds':>8s} {'fps':>8s} {'x real time':>12s} {'x stick (same mode)':>20s}")
    for name, secs in best.items():
        base = best[name.replace("character", "stick figure")]
        print(f"{name:30s} {secs:8.2f} {n / secs:8.1f} {n / motion.fps / secs:12.2f} {base / secs:20.2f}")
    print(f"posing + skinning alone: {skin_ms:.2f} ms per frame")


if __name__ == "__main__":
    main()
