"""Render motions to MP4 videos and PNG stills: one figure, side by side, or a grid.

Every panel of one video is seen through the same :class:`~renderers.scene.View`, so the
conditions of a segment are framed identically (pass ``view=`` to share it across videos).
"""
from __future__ import annotations

import pathlib
import warnings

import numpy as np
from tqdm import tqdm

from evalsuite.errors import InputError
from evalsuite.motion import Motion, load_motion
from evalsuite.motion.ops import cut, resample
from renderers.audio import cut_audio, read_audio
from renderers.layout import Compositor
from renderers.scene import FigureRenderer, RenderSettings, View, make_view
from renderers.skeleton import body_motion
from renderers.styles import STYLES
from renderers.video import VideoWriter, fit_audio


class PreparedMotions(list):
    """The motions :func:`prepare_motions` returns, with the window of the source files they show.

    ``start``: seconds of the source at the first frame (``round(start * fps) / fps``, the
    frame the cut begins with); ``end``: seconds just after the last frame asked for, or None
    when the motion runs to its end. :func:`render_video` cuts the speech audio to the same
    window, so speech and motion stay in sync.
    """

    start: float = 0.0
    end: float | None = None


def prepare_motions(sources, settings: RenderSettings, start: float | None = None,
                    end: float | None = None) -> PreparedMotions:
    """Load (paths) or take (Motion objects), cut to ``start``-``end`` s, bring to one fps.

    The frame rate is ``settings.fps`` if set, else the first motion's; others are resampled
    to it so the panels stay in step, each with a ``UserWarning`` naming the file and both rates.
    Joints that are not part of the body (a world root at the floor, zero-length helpers,
    see :mod:`renderers.skeleton`) and ``settings.drop_joints`` are left out. The result
    records the cut (``.start``, ``.end``), which :func:`render_video` applies to the audio.
    """
    motions = [s if isinstance(s, Motion) else load_motion(s) for s in sources]
    if not motions:
        raise InputError("no motion given")
    fps = settings.fps or motions[0].fps
    for m in motions:   # never silently (the render CLI shows these as 'Warning:' lines)
        if abs(m.fps - fps) > 1e-9 * fps:
            warnings.warn(f"{m.source or m.name or 'motion'}: resampled by interpolation from {m.fps:g} to "
                          f"{fps:g} fps for the video", UserWarning, stacklevel=2)
    # resample before cutting, so a cut of S seconds has S * fps frames whatever the source rate
    motions = [resample(m, fps) for m in motions]
    if start is not None or end is not None:
        motions = [cut(m, start or 0.0, end) for m in motions]
    motions = [body_motion(m, settings.up_axis, settings.drop_joints) for m in motions]
    if settings.center:
        motions = [center_on_ground(m, settings.up_axis) for m in motions]
    out = PreparedMotions(motions)
    # the same frames cut() keeps: frame round(start * fps) up to, not including, round(end * fps)
    out.start = int(round((start or 0.0) * fps)) / fps
    out.end = None if end is None else int(round(end * fps)) / fps
    return out


def center_on_ground(motion: Motion, up_axis: str = "y") -> Motion:
    """Shift the whole clip so the root's mean position is at the origin of the ground plane.

    One constant shift per clip: movement within the clip (sway, steps) is kept, but clips
    recorded at different places in the room line up under a shared camera.
    """
    from renderers.camera import UP_AXES

    pos = motion.positions()
    roots = np.flatnonzero(np.asarray(motion.parents) < 0)
    root = int(roots[0]) if len(roots) else 0
    up = UP_AXES[up_axis]
    shift = np.nanmean(pos[:, root], axis=0)
    shift = shift - np.dot(shift, up) * up
    return motion.with_positions(pos - shift)


def view_for(motions, settings: RenderSettings) -> View:
    """The shared view of several motions (the conditions of one segment)."""
    return make_view([m.positions() for m in motions], [m.joint_names for m in motions], settings,
                     [m.parents for m in motions])


def _meshes(motions, settings, view):
    """One mesh per motion, from the body style the settings name (shared figure size ``view.size``)."""
    style = STYLES[settings.body]
    meshes = [style.mesh(m, settings, view.size) for m in motions]
    for mesh in meshes:   # a style that draws on the floor (a contact shadow) learns the shared floor height
        if hasattr(mesh, "floor_height"):
            mesh.floor_height = view.floor_height
    return meshes


def render_video(motions, out, settings: RenderSettings | None = None, *, audio=None, captions=None,
                 layout: str = "side", cols: int | None = None, view: View | None = None,
                 frame_filter=None, progress: bool = False, label: str = "", start: float | None = None,
                 end: float | None = None, bitrate: str | None = None) -> dict:
    """Render one or more motions (already at one fps) into an H.264 MP4.

    Args:
        motions: list of :class:`Motion` (see :func:`prepare_motions`).
        out: output ``.mp4`` path.
        audio: path of the speech audio, or ``(samples, rate)`` of the whole source; its
            ``start``-``end`` window is muxed from frame 0 and trimmed with the video to the
            shorter of the two.
        captions: one caption per panel (or None).
        layout, cols: ``side`` (one row) or ``grid``; ``cols`` forces the column count.
        view: the shared view; computed from ``motions`` when None.
        frame_filter: ``f(index, frame) -> frame`` applied to every composed frame.
        start, end: the window (seconds) of the source the motions show, so the audio is cut
            with them; default: the cut :func:`prepare_motions` recorded, else all of it.
        bitrate: constant-bitrate encoding (e.g. ``"400k"``) instead of ``settings.crf``.

    Returns:
        dict with ``n_frames``, ``fps``, ``width``, ``height``, ``duration`` and ``view``.
    """
    settings = settings or RenderSettings()
    fps = motions[0].fps
    if any(abs(m.fps - fps) > 1e-9 * fps for m in motions):
        raise InputError("motions have different frame rates; use prepare_motions to resample them")
    view = view or view_for(motions, settings)
    positions = [m.positions() for m in motions]
    n = min(len(p) for p in positions)
    if n < 1:
        raise InputError("the motion has no frames")
    audio_data = None
    if audio is not None:
        samples, rate = read_audio(audio) if not isinstance(audio, tuple) else audio
        start = getattr(motions, "start", 0.0) if start is None else start
        end = getattr(motions, "end", None) if end is None else end
        samples = cut_audio(samples, rate, start, end, label=label or str(out))
        samples, n = fit_audio(samples, rate, n, fps, label=label or str(out))
        audio_data = (samples, rate)
    comp = Compositor(len(motions), settings.width, settings.height, layout=layout, cols=cols, captions=captions)
    meshes = _meshes(motions, settings, view)
    with FigureRenderer(view, settings) as renderer, \
            VideoWriter(out, comp.width, comp.height, fps, audio=audio_data, crf=settings.crf,
                        bitrate=bitrate) as writer:
        streams = [renderer.frames(mesh, pos[:n]) for mesh, pos in zip(meshes, positions)]
        if len(streams) > 1:      # a frame is a view of the context's buffer, which the next panel's draw overwrites
            streams = [(frame.copy() for frame in stream) for stream in streams]
        for i, panels in enumerate(tqdm(zip(*streams), total=n, disable=not progress, unit="frame",
                                        desc=label or pathlib.Path(out).name, leave=False)):
            frame = comp.compose(panels)
            if frame_filter is not None:
                frame = frame_filter(i, frame)
            writer.write(frame)
    return {"n_frames": n, "fps": fps, "width": comp.width, "height": comp.height, "duration": n / fps,
            "view": view}


def render_frames(motions, settings: RenderSettings | None = None, *, frames=None, captions=None,
                  layout: str = "side", cols: int | None = None, view: View | None = None) -> list[np.ndarray]:
    """Composed frames (copies) at the given frame indices (default: frame 0)."""
    settings = settings or RenderSettings()
    view = view or view_for(motions, settings)
    positions = [m.positions() for m in motions]
    n = min(len(p) for p in positions)
    idx = [0] if frames is None else [int(f) for f in frames]
    for f in idx:
        if not 0 <= f < n:
            raise InputError(f"frame {f} is outside the motion (0-{n - 1})", field="frame")
    comp = Compositor(len(motions), settings.width, settings.height, layout=layout, cols=cols, captions=captions)
    meshes = _meshes(motions, settings, view)
    out = []
    with FigureRenderer(view, settings) as renderer:
        for f in idx:
            panels = [next(renderer.frames(mesh, pos[f:f + 1])).copy() for mesh, pos in zip(meshes, positions)]
            out.append(comp.compose(panels).copy())
    return out


def render_still(motions, out, settings: RenderSettings | None = None, *, frame: int = 0, **kwargs) -> pathlib.Path:
    """Write one composed frame as PNG."""
    import imageio.v3 as iio

    img = render_frames(motions, settings, frames=[frame], **kwargs)[0]
    out = pathlib.Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(out, img)
    return out
