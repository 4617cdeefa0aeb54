"""Benchmark: offscreen video rendering of each body style vs the matplotlib-3D approach of the seed repos.

All render the same motion (the bundled MocapBank clip, 19 joints, 30 fps) as a single
figure at 640x480 and encode H.264 with the same imageio-ffmpeg writer; the time covers
rendering + encoding (+ building geometry), i.e. frames per second of finished video.
Each body style (stick figure, mannequin, and any other registered style such as the skinned
character) is timed in this process, and the stick figure and the mannequin also as a whole
``evalsuite render video`` command in a fresh process (Python start, imports, GL context, writing
the file): frames / wall time of the command.

The peer follows the gesture repos' scripts (:mod:`seed_matplotlib`): a matplotlib 3D axes, cleared and
re-plotted (one line per bone) every frame, drawn with Agg, timed in this process and, beside evalsuite's whole
command, as a script in a fresh process (its whole process: Python start, imports, drawing, encoding).

Targets (issues 5 and 36): stick figure >= 10x the matplotlib peer (in this process, and as a whole command
against the peer's whole process); mannequin >= 2x real time at
30 fps (>= 60 fps), whole process; skinned character >= 1x real time.
Each renderer runs ``--rounds`` times alternately; the best round counts (the machine is
shared, so the best round is the least disturbed one).

``--stimuli N`` instead times a study's stimulus set (issue 36: "100 ten-second stimuli with --jobs 2"): N
clips of ``--stimulus-seconds`` each (windows of the same clip, two conditions per segment when N is even,
synthetic speech muxed as AAC) rendered by the real ``evalsuite render stimuli CONFIG --jobs J`` command in a
fresh process, in ``--stimulus-style``; it prints the wall time, seconds per stimulus, x real time (seconds of
video per second of wall time) and how many processes were writing a video at once (a process with an
ffmpeg child, sampled from /proc every 0.2 s), which shows whether ``--jobs`` really renders in parallel.

    python benchmarks/bench_render.py [--frames 300] [--rounds 2]
    python benchmarks/bench_render.py --stimuli 100 --stimulus-seconds 10 --jobs 2 --stimulus-style mannequin
"""
from __future__ import annotations

import argparse
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import seed_matplotlib

from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.ops import cut
from evalsuite.motion.samples import sample_path
from renderers.figure import LEFT, RIGHT, joint_sides
from renderers.render import prepare_motions, render_video
from renderers.scene import RenderSettings
from renderers.styles import STYLES

W, H = 640, 480


def ours(motion, out, msaa=4, body="stick") -> float:
    settings = RenderSettings(width=W, height=H, msaa=msaa, body=body)
    t0 = time.perf_counter()
    render_video([motion], out, settings)
    return time.perf_counter() - t0


def whole_command(path, out, body) -> float:
    """Wall time of ``evalsuite render video PATH --style BODY`` in a fresh Python process."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "evalsuite", "render", "video", str(path), "-o", str(out), "--style", body,
                    "--width", str(W), "--height", str(H)], check=True, capture_output=True)
    return time.perf_counter() - t0


def seed_clip(motion, path) -> None:
    """Write what :mod:`seed_matplotlib` draws: positions, parents, a colour per joint (its bone's), fps."""
    sides = joint_sides(motion.joint_names)
    colors = np.where(sides == LEFT, "tab:blue", np.where(sides == RIGHT, "tab:orange", "dimgray"))
    np.savez(path, positions=motion.positions(), parents=np.asarray(motion.parents), colors=colors, fps=motion.fps)


def matplotlib_3d(clip, out, axes_visible: bool = True) -> float:
    """The seed repos' renderer (:mod:`seed_matplotlib`) in this process: drawing and encoding only."""
    with np.load(clip) as data:
        pos, parents, colors, fps = data["positions"], data["parents"], [str(c) for c in data["colors"]], data["fps"]
    t0 = time.perf_counter()
    seed_matplotlib.render(pos, parents, colors, float(fps), str(out), W, H, axes_visible=axes_visible)
    return time.perf_counter() - t0


def matplotlib_process(clip, out) -> float:
    """Wall time of the seed repos' renderer as a script in a fresh Python process (the whole process)."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, str(pathlib.Path(__file__).with_name("seed_matplotlib.py")), str(clip), str(out)],
                   check=True, capture_output=True)
    return time.perf_counter() - t0


def _children(pid: int) -> list[tuple[int, str]]:
    """(pid, command name) of the child processes of ``pid`` (from /proc)."""
    try:
        children = [int(c) for c in pathlib.Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []
    out = []
    for child in children:
        try:
            out.append((child, pathlib.Path(f"/proc/{child}/comm").read_text().strip()))
        except OSError:
            continue
    return out


def _rendering(pid: int) -> int:
    """How many processes of the tree under ``pid`` are writing a video now: a process with an ffmpeg child is
    (``pid`` itself with --jobs 1, each worker process with --jobs N)."""
    children = _children(pid)
    if any(name.startswith("ffmpeg") for _, name in children):
        return 1
    return sum(any(name.startswith("ffmpeg") for _, name in _children(child)) for child, _ in children)


def stimulus_set(n: int, seconds: float, jobs: int, style: str) -> None:
    """Time ``evalsuite render stimuli --jobs JOBS`` on ``n`` stimuli of ``seconds`` each (see the module doc)."""
    import yaml

    from renderers.audio import speech_like_audio, write_wav

    source = load_motion(sample_path("mocapbank"))
    length = source.n_frames / source.fps
    if seconds > length:
        raise SystemExit(f"--stimulus-seconds {seconds:g}: the clip lasts {length:.1f} s")
    root = pathlib.Path(tempfile.mkdtemp(prefix="bench_stimuli_"))
    save_motion(source, root / "clip.npz")
    write_wav(root / "speech.wav", speech_like_audio(length, 16000, seed=1), 16000)
    conditions = ["a", "b"] if n % 2 == 0 else ["a"]
    n_segments = n // len(conditions)
    room = length - seconds
    segments = {}
    for k in range(n_segments):   # windows spread over the clip, so the segments' cameras differ
        start = round(room * ((k * 0.37) % 1.0), 3)
        segments[f"seg{k:03d}"] = {"start": start, "end": start + seconds}
    config = {"output": "out", "segments": segments, "conditions": {c: "clip.npz" for c in conditions},
              "audio": "speech.wav", "render": {"width": W, "height": H, "style": style}}
    (root / "stimuli.yaml").write_text(yaml.safe_dump(config))
    cmd = [sys.executable, "-m", "evalsuite", "render", "stimuli", str(root / "stimuli.yaml"), "--jobs", str(jobs)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    busy_counts = []
    while proc.poll() is None:
        time.sleep(0.2)
        busy_counts.append(_rendering(proc.pid))
    wall = time.perf_counter() - t0
    output = proc.stdout.read() if proc.stdout else ""
    if proc.returncode != 0:
        raise SystemExit(f"render stimuli failed ({proc.returncode}):\n{output[-2000:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    load = os.getloadavg()
    video = n * seconds
    print(f"Stimulus set: {n} stimuli of {seconds:g} s ({len(conditions)} condition(s) x {n_segments} segments), "
          f"{W}x{H}, style {style}, speech muxed, evalsuite render stimuli --jobs {jobs} in a fresh process")
    print(f"CPU: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} (shared machine)")
    print(f"wall {wall:.1f} s = {wall / n:.2f} s per stimulus = {video / wall:.2f}x real time "
          f"({video:g} s of video); CPU {cpu:.1f} s = {cpu / wall:.2f} cores busy on average")
    peak = max(busy_counts, default=0)
    print(f"processes writing a video at once (sampled every 0.2 s): at most {peak}; {jobs} in "
          f"{sum(b >= jobs for b in busy_counts) / max(len(busy_counts), 1):.0%} of the samples")
    if n and video / wall > 0:
        print(f"extrapolated: 100 ten-second stimuli in {100 * 10 / (video / wall) / 60:.1f} min at this rate")
    shutil.rmtree(root, ignore_errors=True)   # the stimuli (100 x 10 s: tens of MB)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300, help="frames to render (at 30 fps)")
    ap.add_argument("--rounds", type=int, default=2, help="rounds per renderer; the best counts")
    ap.add_argument("--stimuli", type=int, default=0,
                    help="time a stimulus set of this many clips through 'evalsuite render stimuli' instead")
    ap.add_argument("--stimulus-seconds", type=float, default=10.0, help="length of each stimulus (--stimuli)")
    ap.add_argument("--jobs", type=int, default=2, help="--jobs of 'evalsuite render stimuli' (--stimuli)")
    ap.add_argument("--stimulus-style", default="mannequin", help="body style of the stimuli (--stimuli)")
    args = ap.parse_args()
    if args.stimuli:
        stimulus_set(args.stimuli, args.stimulus_seconds, args.jobs, args.stimulus_style)
        return
    source = load_motion(sample_path("mocapbank"))
    motion = prepare_motions([cut(source, 0.0, args.frames / source.fps)], RenderSettings(width=W, height=H))[0]
    n = motion.n_frames
    out = pathlib.Path(tempfile.mkdtemp(prefix="bench_render_"))
    clip = out / "clip.npz"
    save_motion(motion, clip)
    seed_clip(motion, out / "seed_clip.npz")
    # the other registered body styles (the mannequin; the skinned character and plug-ins when registered)
    others = [name for name in STYLES.names() if name != "stick"]
    # warm-up: imports, shader compilation, font cache, each style's first mesh
    for body in ["stick"] + others:
        ours(prepare_motions([cut(source, 0, 0.3)], RenderSettings())[0], out / "warm.mp4", body=body)
    runs = {
        "evalsuite (pyrender EGL, default)": lambda: ours(motion, out / "ours.mp4"),
        "evalsuite (pyrender EGL, msaa 0)": lambda: ours(motion, out / "ours0.mp4", msaa=0),
        **{f"{body} style (default)": (lambda body=body: ours(motion, out / f"{body}.mp4", body=body))
           for body in others},
        "stick, whole command": lambda: whole_command(clip, out / "cmd_stick.mp4", "stick"),
        "mannequin, whole command": lambda: whole_command(clip, out / "cmd_mannequin.mp4", "mannequin"),
        "matplotlib 3D (seed repos)": lambda: matplotlib_3d(out / "seed_clip.npz", out / "mpl.mp4"),
        "matplotlib 3D, axes hidden": lambda: matplotlib_3d(out / "seed_clip.npz", out / "mpl_off.mp4",
                                                            axes_visible=False),
        "matplotlib 3D, whole process": lambda: matplotlib_process(out / "seed_clip.npz", out / "mpl_proc.mp4"),
    }
    best = {name: np.inf for name in runs}
    for _ in range(args.rounds):
        for name, run in runs.items():
            best[name] = min(best[name], run())
    load = os.getloadavg()
    print(f"Single figure, {W}x{H}, {n} frames ({n / motion.fps:.1f} s at {motion.fps:g} fps), "
          f"render + H.264 encode; best of {args.rounds} rounds")
    print(f"CPU: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} "
          "(shared machine: other jobs may slow every figure)")
    mpl = n / best["matplotlib 3D (seed repos)"]
    print(f"{'renderer':36s} {'seconds':>8s} {'fps':>8s} {'x real time':>12s} {'x matplotlib':>13s}")
    for name, secs in best.items():
        fps = n / secs
        print(f"{name:36s} {secs:8.2f} {fps:8.1f} {fps / motion.fps:12.2f} {fps / mpl:13.2f}")
    fps = n / best["evalsuite (pyrender EGL, default)"]
    print("default = the stick figure, 4x multisample anti-aliasing; 'whole command' = a fresh process running "
          "evalsuite render video; 'whole process' = the seed script run as a fresh process")
    whole = best["matplotlib 3D, whole process"] / best["stick, whole command"]
    met = fps / mpl >= 10 and whole >= 10
    print(f"target stick figure >= 10x matplotlib: {'met' if met else 'NOT met'} (in process {fps / mpl:.1f}x; "
          f"whole command vs whole process {whole:.1f}x)")
    fps = n / best["mannequin, whole command"]
    print(f"target mannequin >= 2x real time, whole command: {'met' if fps >= 60 else 'NOT met'} ({fps / 30:.2f}x)")
    if "character style (default)" in best:
        fps = n / best["character style (default)"]
        print(f"target character >= 1x real time: {'met' if fps >= 30 else 'NOT met'} ({fps / 30:.2f}x)")


if __name__ == "__main__":
    main()
