"""Offscreen rendering to real MP4 files, checked by decoding them (frames, size, fps, audio)
and by looking at pixels where the camera projects the joints."""
from __future__ import annotations

import math
import subprocess
import warnings

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from click.testing import CliRunner
from render_helpers import NAMES, PARENTS, RATE, TPOSE, decode, decoded_audio_seconds, ffmpeg_stream_info, waving_motion

from evalsuite.cli import main
from evalsuite.motion import Motion
from renderers.audio import speech_like_audio, write_wav
from renderers.camera import Camera, frame_points, view_direction
from renderers.render import prepare_motions, render_frames, render_video, view_for
from renderers.scene import RenderSettings
from renderers.video import DurationMismatchWarning, probe


def test_clip_decodes_with_expected_frames_size_fps_and_audio(tmp_path):
    wav = tmp_path / "speech.wav"
    write_wav(wav, speech_like_audio(1.0, RATE), RATE)
    settings = RenderSettings(width=160, height=120)
    out = tmp_path / "clip.mp4"
    info = render_video([waving_motion(1.0, 30.0)], out, settings, audio=wav)
    assert info["n_frames"] == 30
    meta, frames = decode(out)
    assert frames.shape == (30, 120, 160, 3)
    assert meta["fps"] == 30.0
    assert meta["codec"] == "h264"
    assert meta["audio_codec"] == "aac"
    assert imageio_ffmpeg.count_frames_and_secs(str(out)) == (30, pytest.approx(1.0, abs=1e-6))
    text = ffmpeg_stream_info(out)
    assert "Video: h264" in text
    assert "160x120" in text
    assert "30 fps" in text
    assert "Audio: aac" in text
    # AAC codes in 1024-sample frames; the decoded length is the motion's within one AAC frame.
    assert decoded_audio_seconds(out) == pytest.approx(1.0, abs=1024 / RATE)
    # imageio v3 decodes the same frames
    assert iio.imread(out, index=15).shape == (120, 160, 3)


def test_video_fps_follows_the_motion_or_the_resampling(tmp_path):
    m = waving_motion(1.0, 24.0)
    out = tmp_path / "v24.mp4"
    render_video(prepare_motions([m], RenderSettings(width=96, height=72)), out, RenderSettings(width=96, height=72))
    assert probe(out)["fps"] == 24.0
    assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == 24
    settings = RenderSettings(width=96, height=72, fps=12.0)
    out = tmp_path / "v12.mp4"
    with pytest.warns(UserWarning, match="resampled by interpolation from 24 to 12 fps"):   # never silently
        prepared = prepare_motions([m], settings)
    info = render_video(prepared, out, settings)
    # 24 frames at 24 fps span 23/24 s; resampled at 12 fps: frames at 0, 1/12, ..., 11/12 s
    assert info["n_frames"] == 12
    assert probe(out)["fps"] == 12.0


@pytest.mark.parametrize("audio_s, frames, warns", [(1.5, 30, True), (0.5, 15, True), (1.02, 30, False),
                                                    (0.98, 30, False)])
def test_audio_and_motion_are_trimmed_to_the_shorter(tmp_path, audio_s, frames, warns):
    wav = tmp_path / "a.wav"
    write_wav(wav, speech_like_audio(audio_s, RATE), RATE)
    out = tmp_path / "t.mp4"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        render_video([waving_motion(1.0, 30.0)], out, RenderSettings(width=96, height=72), audio=wav)
    mismatch = [w for w in caught if issubclass(w.category, DurationMismatchWarning)]
    assert bool(mismatch) == warns
    assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == frames
    assert decoded_audio_seconds(out) == pytest.approx(frames / 30.0, abs=1024 / RATE)


def test_figure_pixels_are_where_the_joints_project(tmp_path):
    settings = RenderSettings(width=320, height=240)
    motion = Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)
    view = view_for([motion], settings)
    (img,) = render_frames([motion], settings, view=view)
    uv = view.camera.project(TPOSE)
    assert np.all((uv >= 0) & (uv < [320, 240])), "every joint is inside the picture"
    right_wrist, left_wrist = uv[NAMES.index("RightWrist")], uv[NAMES.index("LeftWrist")]
    # front view: the figure's left (+X) appears on the right of the picture
    assert left_wrist[0] > 160 > right_wrist[0]
    r = img[int(right_wrist[1]), int(right_wrist[0])].astype(int)
    l = img[int(left_wrist[1]), int(left_wrist[0])].astype(int)
    assert r[0] - r[2] > 80, f"right wrist pixel {r} is not the right side's orange"
    assert l[2] - l[0] > 80, f"left wrist pixel {l} is not the left side's blue"
    for y, x in [(0, 0), (0, 319), (239, 0), (239, 319)]:
        assert tuple(img[y, x]) == (255, 255, 255), "far corners show the background"
    # the figure is centred: its drawn pixels' bounding box is symmetric about the centre
    ys, xs = np.nonzero(np.any(img < 200, axis=2))
    assert abs((xs.min() + xs.max()) / 2 - 160) < 6
    assert abs((ys.min() + ys.max()) / 2 - 120) < 6
    assert xs.min() > 2 and ys.min() > 2 and xs.max() < 317 and ys.max() < 237, "not clipped"


def test_projection_matches_an_independent_pinhole_model():
    cam = Camera(eye=(30.0, 150.0, 400.0), target=(0.0, 100.0, 0.0), up=(0.0, 1.0, 0.0), yfov_deg=35.0,
                 width=640, height=480, znear=1.0, zfar=5000.0)
    pts = np.random.default_rng(0).uniform(-80, 80, size=(50, 3)) + [0, 100, 0]
    forward = np.subtract(cam.target, cam.eye)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    rel = pts - cam.eye
    f = 240 / math.tan(math.radians(35.0) / 2)   # focal length in pixels
    u = 320 + f * (rel @ right) / (rel @ forward)
    v = 240 + f * (rel @ down) / (rel @ forward)
    np.testing.assert_allclose(cam.project(pts), np.stack([u, v], axis=1), atol=1e-6)


def test_framing_fits_every_point_with_the_margin():
    pts = np.random.default_rng(1).normal(size=(500, 3)) * [20, 60, 15] + [5, 100, -3]
    for view in ("front", "three-quarter", "side"):
        d = view_direction(np.array([0.0, 0.0, 1.0]), "y", view, 8.0)
        cam = frame_points(pts, d, "y", 400, 300, margin=0.1)
        uv = cam.project(pts)
        assert uv[:, 0].min() >= 0.05 * 400 - 1e-6
        assert uv[:, 0].max() <= 0.95 * 400 + 1e-6
        assert uv[:, 1].min() >= 0.05 * 300 - 1e-6
        assert uv[:, 1].max() <= 0.95 * 300 + 1e-6
        # tight on one axis: the extent touches the margin on width or height
        span = max((uv[:, 0].max() - uv[:, 0].min()) / 360, (uv[:, 1].max() - uv[:, 1].min()) / 270)
        assert span == pytest.approx(1.0, abs=0.02)
        centre = (uv.min(axis=0) + uv.max(axis=0)) / 2
        np.testing.assert_allclose(centre, [200, 150], atol=1.0)


def test_conditions_in_one_video_share_the_camera_and_the_upper_framing_crops_legs():
    settings = RenderSettings(width=160, height=120)
    a, b = waving_motion(), waving_motion(amplitude=60.0)
    shared = view_for([a, b], settings)
    assert shared.camera != view_for([a], settings).camera  # the view depends on every condition
    upper = view_for([a], RenderSettings(width=160, height=120, framing="upper"))
    uv = upper.camera.project(TPOSE)
    assert uv[NAMES.index("LeftAnkle"), 1] > 120, "ankles are below the picture in upper-body framing"
    assert 0 < uv[NAMES.index("Head"), 1] < 60


def test_compare_cli_side_by_side_with_audio_and_captions(tmp_path):
    from evalsuite.motion.io import save_motion

    paths = []
    for k, amp in enumerate([10.0, 40.0, 70.0]):
        p = tmp_path / f"cond{k}.npz"
        save_motion(waving_motion(1.0, 30.0, amplitude=amp), p)
        paths.append(str(p))
    wav = tmp_path / "s.wav"
    write_wav(wav, speech_like_audio(1.0, RATE), RATE)
    out = tmp_path / "cmp.mp4"
    res = CliRunner().invoke(main, ["render", "compare", *paths, "--audio", str(wav), "-o", str(out),
                                    "--width", "128", "--height", "96", "--captions", "Natural,A,B"])
    assert res.exit_code == 0, res.output
    meta, frames = decode(out)
    assert frames.shape[0] == 30
    assert meta["audio_codec"] == "aac"
    h, w = frames.shape[1:3]
    assert w >= 3 * 128 and h > 96   # three panels in a row, caption strip above
    res = CliRunner().invoke(main, ["render", "compare", *paths, "-o", str(out), "--captions", "only,two"])
    assert res.exit_code == 1
    assert "Error:" in res.output
    assert "captions" in res.output
    png = tmp_path / "s.png"
    res = CliRunner().invoke(main, ["render", "still", paths[0], "-o", str(png), "--width", "128", "--height", "96",
                                    "--time", "0.5"])
    assert res.exit_code == 0, res.output
    assert iio.imread(png).shape == (96, 128, 3)


def test_frames_rendered_in_sequence_match_frames_rendered_alone():
    """The vertex buffer is updated in place between frames: that must equal a fresh upload."""
    settings = RenderSettings(width=128, height=96)
    m = waving_motion(1.0, 30.0, amplitude=40.0)
    view = view_for([m], settings)
    seq = render_frames([m], settings, frames=[0, 10, 5], view=view)
    alone = render_frames([m], settings, frames=[5], view=view)[0]
    np.testing.assert_array_equal(seq[2], alone)
    # frames 0 and 10 are the same pose (a 1.5 Hz wave), frame 5 is the top of the wave
    np.testing.assert_array_equal(seq[0], seq[1])
    assert np.abs(seq[0].astype(int) - seq[2].astype(int)).sum() > 0, "the arms moved between frames"


def test_egl_is_the_default_platform_and_a_user_choice_is_kept():
    import os
    import sys

    code = ("import os; from renderers._gl import import_pyrender; import_pyrender(); "
            "print(os.environ['PYOPENGL_PLATFORM'])")
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "egl"
    env["PYOPENGL_PLATFORM"] = "osmesa"
    code = ("import os\nfrom renderers._gl import import_pyrender\ntry:\n    import_pyrender()\n"
            "except ImportError as exc:\n    print('ImportError', exc)\nprint(os.environ['PYOPENGL_PLATFORM'])")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    # PyOpenGL tried OSMesa (this machine has no libOSMesa): the user's choice was not overridden
    assert out.stdout.strip().splitlines()[-1] == "osmesa"
    assert "egl" not in out.stdout.lower()


def test_rendering_imports_neither_trimesh_nor_scipy_and_trimesh_still_works_after():
    """A rendering command's start: pyrender is imported with trimesh and its viewer deferred (renderers._gl),
    its scene graph without networkx (renderers._scene_tree), and the stick figure's parts are stored, so drawing
    a mannequin and a stick figure loads neither trimesh, scipy, networkx nor pyglet (over a second); asking for
    trimesh, networkx or the viewer afterwards gets the real one."""
    import sys

    code = ("import sys\n"
            "from evalsuite.motion import Motion\n"
            "from renderers.render import render_frames\n"
            "from renderers.scene import RenderSettings\n"
            "import numpy as np\n"
            "t = np.array([[0, 1, 0], [0, 1.5, 0], [0.3, 1.4, 0], [-0.3, 1.4, 0], [0.1, 0.5, 0], [-0.1, 0.5, 0]], float)\n"
            "m = Motion.from_positions(t[None], ['Hips', 'Head', 'LeftHand', 'RightHand', 'LeftFoot', 'RightFoot'],"
            " 30.0, [-1, 0, 0, 0, 0, 0])\n"
            "frame = render_frames([m], RenderSettings(width=64, height=48, body='mannequin'))[0]\n"
            "stick = render_frames([m], RenderSettings(width=64, height=48, body='stick'))[0]\n"
            "print('drawn', min(int((f < 200).any(axis=-1).sum()) for f in (frame, stick)))\n"
            "print('loaded', sorted({k.split('.')[0] for k in sys.modules} & {'scipy', 'pyglet', 'networkx'}),"
            " type(sys.modules['trimesh']).__name__)\n"
            "import trimesh\n"
            "print('after', trimesh.creation.icosphere(subdivisions=1).vertices.shape,"
            " trimesh.transformations.identity_matrix().shape, type(sys.modules['trimesh']).__name__)\n"
            "from pyrender.viewer import Trackball\n"
            "import pyrender\n"
            "print('viewer', 'pyglet' in sys.modules, pyrender.Viewer.__module__, Trackball.__name__)\n"
            "import networkx\n"
            "print('networkx', networkx.DiGraph.__module__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.splitlines()
    assert int(out[0].split()[1]) > 20, out                      # the figure was drawn
    assert out[1] == "loaded [] _DeferredTrimesh", out
    assert out[2] == "after (42, 3) (4, 4) module", out
    assert out[3] == "viewer True pyrender.viewer Trackball", out   # pyrender's viewer (pyglet) loads on use
    assert out[4] == "networkx networkx.classes.digraph", out        # the real package for anyone else


def test_floor_and_shadow():
    from renderers.figure import FigureStyle

    motion = Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)
    plain = render_frames([motion], RenderSettings(width=160, height=120))[0]
    floor = render_frames([motion], RenderSettings(width=160, height=120, style=FigureStyle(floor=True)))[0]
    shadow = render_frames([motion], RenderSettings(width=160, height=120,
                                                    style=FigureStyle(floor=True, shadow=True)))[0]
    assert tuple(plain[-1, 0]) == (255, 255, 255)
    assert max(floor[-1, 0]) < 235, "the floor fills the bottom of the picture (camera looks down)"
    assert tuple(floor[0, 0]) == (255, 255, 255), "above the horizon: background"
    darker = (shadow.astype(int).sum(axis=2) < floor.astype(int).sum(axis=2) - 30)
    assert darker.sum() > 50, "the shadow darkens part of the floor"


def test_side_by_side_panels_equal_single_renders_through_the_shared_camera():
    from renderers.layout import Compositor

    settings = RenderSettings(width=128, height=96)
    a, b = waving_motion(amplitude=10.0), waving_motion(amplitude=60.0)
    view = view_for([a, b], settings)
    (both,) = render_frames([a, b], settings, frames=[5], view=view)
    (only_a,) = render_frames([a], settings, frames=[5], view=view)
    (only_b,) = render_frames([b], settings, frames=[5], view=view)
    comp = Compositor(2, 128, 96)
    for k, single in enumerate([only_a, only_b]):
        x, y = comp.panel_origin(k)
        np.testing.assert_array_equal(both[y:y + 96, x:x + 128], single)
    assert np.abs(only_a.astype(int) - only_b.astype(int)).sum() > 0


def test_side_view_sees_the_t_pose_edge_on():
    motion = Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)
    spans = {}
    for view_name in ("front", "three-quarter", "side"):
        cam = view_for([motion], RenderSettings(width=160, height=120, view=view_name)).camera
        uv = cam.project(TPOSE)
        spans[view_name] = abs(uv[NAMES.index("LeftWrist"), 0] - uv[NAMES.index("RightWrist"), 0])
    # arm span across the picture: widest from the front, ~cos 45 of it at three-quarter, ~0 from the side
    assert spans["side"] < 2.0
    assert spans["front"] > spans["three-quarter"] > 0.3 * spans["front"]


def test_audio_is_aligned_to_frame_zero(tmp_path):
    """A tone burst at 0.5 s in the WAV is at 0.5 s in the video's audio track."""
    t = np.arange(RATE) / RATE
    burst = np.where((t >= 0.5) & (t < 0.6), 0.5 * np.sin(2 * np.pi * 440 * t), 0.0).astype(np.float32)
    wav = tmp_path / "burst.wav"
    write_wav(wav, burst[:, None], RATE)
    out = tmp_path / "burst.mp4"
    render_video([waving_motion(1.0, 30.0)], out, RenderSettings(width=96, height=72), audio=wav)
    raw = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(out), "-vn", "-f", "s16le",
                          "-ac", "1", "-ar", str(RATE), "-"], capture_output=True, check=True).stdout
    decoded = np.frombuffer(raw, np.int16).astype(float) / 32768
    loud = np.flatnonzero(np.abs(decoded) > 0.1)
    assert abs(loud[0] / RATE - 0.5) < 0.01
    assert abs(loud[-1] / RATE - 0.6) < 0.01


def test_partial_redraw_gives_the_same_frames_as_full_redraws():
    """Only the figure's screen box is cleared/drawn/resolved each frame: must be invisible."""
    from renderers.figure import FigureMesh
    from renderers.scene import FigureRenderer

    settings = RenderSettings(width=128, height=96)
    m = waving_motion(1.0, 30.0, amplitude=60.0, shift=(0.0, 0.0, 0.0))
    pos = m.positions().copy()
    pos[:, :, 0] += np.linspace(-40, 40, len(pos))[:, None]   # the figure also travels sideways
    m = m.with_positions(pos)
    view = view_for([m], settings)
    mesh = FigureMesh(m.joint_names, m.parents, settings.style, view.size, rest_positions=pos)
    with FigureRenderer(view, settings) as r:
        partial = [f.copy() for f in r.frames(mesh, pos)]
    with FigureRenderer(view, settings) as r:
        r.partial_redraw = False
        full = [f.copy() for f in r.frames(mesh, pos)]
    for k, (a, b) in enumerate(zip(partial, full)):
        np.testing.assert_array_equal(a, b, err_msg=f"frame {k}")


def test_msaa_setting_reaches_the_framebuffer():
    """4x multisampling blends edge pixels with the background; without it edges are hard."""
    motion = Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)

    def edge_blend(img):
        # pixels that are neither background nor close to a figure colour: partial coverage
        dist_bg = np.abs(img.astype(int) - 255).max(axis=2)
        return int(((dist_bg > 20) & (img.astype(int).min(axis=2) > 150)).sum())

    hard = render_frames([motion], RenderSettings(width=160, height=120, msaa=0))[0]
    smooth = render_frames([motion], RenderSettings(width=160, height=120, msaa=4))[0]
    assert not np.array_equal(hard, smooth)
    assert edge_blend(smooth) > 1.5 * edge_blend(hard)


def test_video_writer_sends_frames_from_a_thread_and_copies_them(tmp_path):
    """VideoWriter hands frames to ffmpeg from its own thread (rendering goes on meanwhile); the caller may
    refill its array right after write(): every frame is encoded as it was when written."""
    import threading

    from renderers.video import VideoWriter, read_video_frames

    buf = np.zeros((48, 64, 3), dtype=np.uint8)
    levels = [30, 90, 150, 210, 250, 10]
    with VideoWriter(tmp_path / "v.mp4", 64, 48, 30.0) as writer:
        assert any(t.name == "ffmpeg writer v.mp4" for t in threading.enumerate())
        for level in levels:
            buf[:] = level          # the same array, refilled at once
            writer.write(buf)
    assert not any(t.name == "ffmpeg writer v.mp4" for t in threading.enumerate())
    means = [float(frame.mean()) for _, frame in read_video_frames(tmp_path / "v.mp4")]
    assert len(means) == len(levels)
    np.testing.assert_allclose(means, levels, atol=3)


@pytest.mark.parametrize("body", ["stick", "mannequin"])
def test_replayed_draws_and_partial_reads_give_pyrenders_own_frames(monkeypatch, tmp_path, body):
    """After a clip's first frame each frame is drawn by replaying the captured draw calls and only the redrawn
    rectangle is read back (renderers._gl): two panels taking turns on one context (the compositor's case, where a
    frame buffer reused between panels would show the other panel) give the frames of pyrender's full pass."""
    import renderers.scene as scene

    pos = waving_motion(1.0, 30.0, amplitude=60.0, shift=(0.0, 0.0, 0.0)).positions().copy()
    pos[:, :, 0] += np.linspace(-40, 40, len(pos))[:, None]   # the figure also travels sideways
    motions = [Motion.from_positions(pos, NAMES, 30.0, PARENTS), Motion.from_positions(pos[::-1], NAMES, 30.0, PARENTS)]
    settings = RenderSettings(width=128, height=96, body=body)

    def frames(tmp):
        out = []
        render_video(motions, tmp, settings, frame_filter=lambda i, f: out.append(f.copy()) or f)
        return out

    replayed = []
    replay = scene.replay_draws
    monkeypatch.setattr(scene, "replay_draws", lambda *a: replayed.append(1) or replay(*a))
    fast = frames(tmp_path / "fast.mp4")
    assert len(replayed) >= 2 * len(fast) - 2, "every frame after the first of each panel is a replay"
    original_init = scene.FigureRenderer.__init__

    def full_pass(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        self.partial_redraw = False

    monkeypatch.setattr(scene, "capture_draws", lambda *a: None)
    monkeypatch.setattr(scene.FigureRenderer, "__init__", full_pass)
    slow = frames(tmp_path / "slow.mp4")
    assert len(fast) == len(slow) == len(pos)
    for k, (a, b) in enumerate(zip(fast, slow)):
        np.testing.assert_array_equal(a, b, err_msg=f"frame {k}")


def test_x264_runs_one_thread_up_to_720p(tmp_path):
    """Frames up to 1280x720 are encoded by one x264 thread (it keeps up with the renderer, whose cores it
    would otherwise take); larger ones let x264 choose. x264 writes its settings into the stream."""
    from renderers.video import VideoWriter, x264_threads

    assert x264_threads(640, 480) == 1 and x264_threads(1280, 720) == 1 and x264_threads(1920, 1080) == 0
    with VideoWriter(tmp_path / "v.mp4", 64, 48, 30.0) as writer:
        for level in (40, 200):
            writer.write(np.full((48, 64, 3), level, np.uint8))
    data = (tmp_path / "v.mp4").read_bytes()
    assert b" threads=1 " in data and b"lookahead_threads=1 " in data
