"""The seed repos' renderer, the baseline of ``bench_render.py``: matplotlib 3D, cleared and re-plotted every frame.

Follows the gesture repos' video scripts (e.g. Co-Speech_Gesture_Generation's ``create_video_and_save``): one
``plot`` per bone with ``linewidth=5``, fixed axis limits, axis labels and a per-frame title, Agg canvas. Frames go
to H.264 through imageio-ffmpeg with evalsuite's encoder settings (libx264 ``veryfast``, CRF 20, yuv420p,
faststart), so only the drawing differs from evalsuite's renderer.

It imports only numpy, matplotlib and imageio-ffmpeg, so that run as a script it is the seed repos' *whole
process* (Python start, imports, drawing, encoding), timed beside ``evalsuite render video`` in a fresh process::

    python benchmarks/seed_matplotlib.py CLIP.npz OUT.mp4 [--axes-hidden]

``CLIP.npz`` holds ``positions`` (T, J, 3), ``parents`` (J,), ``colors`` (J,) (a matplotlib colour per joint's
bone) and ``fps`` (written by ``bench_render.py``).
"""
from __future__ import annotations

import sys

import numpy as np


def render(pos: np.ndarray, parents, colors, fps: float, out: str, width: int = 640, height: int = 480,
           axes_visible: bool = True) -> None:
    """Draw ``pos`` (T, J, 3), Y-up, as the seed repos do and write ``out`` (H.264 MP4)."""
    import imageio_ffmpeg
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    bones = [(j, int(p)) for j, p in enumerate(parents) if p >= 0]
    lo, hi = pos.reshape(-1, 3).min(axis=0), pos.reshape(-1, 3).max(axis=0)
    fig = plt.figure(figsize=(width / 100, height / 100), dpi=100)
    ax = fig.add_subplot(111, projection="3d")
    writer = imageio_ffmpeg.write_frames(out, (width, height), fps=float(fps), codec="libx264", quality=None,
                                         macro_block_size=2, pix_fmt_out="yuv420p", ffmpeg_log_level="error",
                                         output_params=["-preset", "veryfast", "-crf", "20", "-movflags", "+faststart"])
    writer.send(None)
    for f in range(len(pos)):
        ax.cla()
        p = pos[f]
        for j, par in bones:
            # BVH is Y-up; matplotlib's 3D axes are Z-up
            ax.plot([p[j, 0], p[par, 0]], [p[j, 2], p[par, 2]], [p[j, 1], p[par, 1]], color=colors[j], linewidth=5)
        ax.set_xlim3d(lo[0], hi[0])
        ax.set_ylim3d(lo[2], hi[2])
        ax.set_zlim3d(lo[1], hi[1])
        ax.view_init(elev=8, azim=-90)
        if axes_visible:
            ax.set_xlabel("x")
            ax.set_ylabel("z")
            ax.set_zlabel("y")
            ax.set_title(f"natural ({f + 1}/{len(pos)})")
        else:
            ax.set_axis_off()
        fig.canvas.draw()
        writer.send(np.ascontiguousarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]))
    writer.close()
    plt.close(fig)


def main(argv: list[str]) -> None:
    if len(argv) not in (2, 3) or (len(argv) == 3 and argv[2] != "--axes-hidden"):
        raise SystemExit("usage: seed_matplotlib.py CLIP.npz OUT.mp4 [--axes-hidden]")
    with np.load(argv[0]) as clip:
        render(clip["positions"], clip["parents"], [str(c) for c in clip["colors"]], float(clip["fps"]), argv[1],
               axes_visible=len(argv) == 2)


if __name__ == "__main__":
    main(sys.argv[1:])
