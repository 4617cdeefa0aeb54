"""A cut (--start/--end, start:/end: of a stimuli config) cuts the speech with the motion: the MP4's audio
track is found in the source WAV, by cross-correlation, exactly where the cut's first frame is, and the
figure's movement (raised while a noise burst sounds) lines up with the audio at lag 0."""
from __future__ import annotations

import csv
import subprocess
import warnings

import imageio_ffmpeg
import numpy as np
import pytest
from click.testing import CliRunner
from render_helpers import NAMES, PARENTS, RATE, TPOSE, decode
from scipy.signal import correlate

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.motion import Motion
from evalsuite.motion.io import save_motion
from renderers.audio import cut_audio, write_wav
from renderers.render import prepare_motions, render_video
from renderers.scene import RenderSettings
from renderers.stimuli import build_stimuli
from renderers.video import DurationMismatchWarning

FPS = 30.0
SECONDS = 4.0
SIZE = ["--width", "96", "--height", "72", "--msaa", "0"]


def _bursts(seconds=SECONDS, seed=3) -> np.ndarray:
    """Per-sample on/off of irregular noise bursts (0.1-0.3 s on, 0.1-0.5 s off): no period, one peak."""
    rng = np.random.default_rng(seed)
    on = np.zeros(int(seconds * RATE), dtype=bool)
    t = rng.uniform(0.05, 0.2)
    while t < seconds:
        length = rng.uniform(0.1, 0.3)
        on[int(t * RATE):int((t + length) * RATE)] = True
        t += length + rng.uniform(0.1, 0.5)
    return on


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    """A 4 s WAV of noise bursts, and a 4 s motion whose left arm is raised while a burst sounds."""
    folder = tmp_path_factory.mktemp("cut")
    on = _bursts()
    noise = np.random.default_rng(0).standard_normal(len(on)) * 0.3
    wav = folder / "speech.wav"
    write_wav(wav, (noise * on).astype(np.float32)[:, None], RATE)
    frames = int(SECONDS * FPS)
    raised = on[(np.arange(frames) / FPS * RATE).astype(int)]
    pos = np.repeat(TPOSE[None], frames, axis=0)
    pos[raised, NAMES.index("LeftElbow"), 1] += 15.0
    pos[raised, NAMES.index("LeftWrist"), 1] += 35.0
    motion = folder / "motion.npz"
    save_motion(Motion.from_positions(pos, NAMES, FPS, PARENTS), motion)
    return {"folder": folder, "wav": wav, "motion": motion}


def _decoded_audio(path) -> np.ndarray:
    raw = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-vn", "-f", "s16le",
                          "-ac", "1", "-ar", str(RATE), "-"], capture_output=True, check=True).stdout
    return np.frombuffer(raw, np.int16).astype(float) / 32768


def _offset_in_source(track: np.ndarray, wav) -> tuple[float, float]:
    """Where (seconds) the track best matches the source WAV, and the normalised correlation there."""
    from renderers.audio import read_audio

    src = read_audio(wav)[0][:, 0].astype(float)
    xc = correlate(src, track, mode="valid", method="fft")
    energy = np.sqrt(np.convolve(src ** 2, np.ones(len(track)), mode="valid") * np.sum(track ** 2))
    r = xc / np.maximum(energy, 1e-12)
    lag = int(np.argmax(r))
    return lag / RATE, float(r[lag])


def _motion_audio_lag(video) -> int:
    """Lag in frames at which the figure's raised arm best matches the loudness of the video's own audio."""
    _, frames = decode(video)
    blue = (frames[..., 2] > 150) & (frames[..., 2].astype(int) - frames[..., 0] > 80)
    rows = np.arange(frames.shape[1])[None, :, None]
    height = -(blue * rows).sum(axis=(1, 2)) / np.maximum(blue.sum(axis=(1, 2)), 1)   # up is larger
    per_frame = int(RATE / FPS)
    # loudness over a frame's time centred on the frame (the motion samples the bursts at frame times)
    track = np.concatenate([np.zeros(per_frame // 2), _decoded_audio(video)])
    n = min(len(frames), len(track) // per_frame)
    loud = np.sqrt((track[:n * per_frame].reshape(n, per_frame) ** 2).mean(axis=1))
    a, b = height[:n] - height[:n].mean(), loud - loud.mean()
    lags = range(-10, 11)
    scores = [np.dot(a[max(k, 0):n + min(k, 0)], b[max(-k, 0):n - max(k, 0)]) for k in lags]
    return list(lags)[int(np.argmax(scores))]


def _check_sync(video, wav, start, seconds):
    track = _decoded_audio(video)
    assert len(track) / RATE == pytest.approx(seconds, abs=1024 / RATE)
    offset, r = _offset_in_source(track, wav)
    assert r > 0.9
    first = round(start * FPS) / FPS                          # the cut begins with this frame
    assert abs(offset - first) < 1 / FPS, f"audio starts at {offset:.3f} s of the WAV, the motion at {first:.3f} s"
    assert _motion_audio_lag(video) == 0


@pytest.mark.parametrize("start, end", [(0.5, 2.0), (1.3, 2.8), (2.0, None)])
def test_render_video_cuts_the_audio_with_the_motion(source, tmp_path, start, end):
    out = tmp_path / "v.mp4"
    args = ["render", "video", str(source["motion"]), "--audio", str(source["wav"]), "-o", str(out), *SIZE,
            "--start", str(start)] + (["--end", str(end)] if end is not None else [])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "Warning" not in res.output, "a correct cut is no length mismatch"
    _check_sync(out, source["wav"], start, (end or SECONDS) - start)


def test_render_compare_cuts_the_audio_with_the_motion(source, tmp_path):
    out = tmp_path / "c.mp4"
    res = CliRunner().invoke(main, ["render", "compare", str(source["motion"]), str(source["motion"]), "--audio",
                                    str(source["wav"]), "-o", str(out), *SIZE, "--captions", "",
                                    "--start", "1.7", "--end", "3.2"])
    assert res.exit_code == 0, res.output
    assert "Warning" not in res.output
    _check_sync(out, source["wav"], 1.7, 1.5)


def test_render_stimuli_cuts_the_audio_with_the_motion(source):
    folder = source["folder"]
    cfg = folder / "stimuli.yaml"
    cfg.write_text("output: out\nsegments: {a: {start: 0.4, end: 1.9}, b: {start: 2.1}}\n"
                   "conditions: {natural: 'motion.npz'}\naudio: speech.wav\n"
                   "render: {width: 96, height: 72, msaa: 0}\n")
    messages: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = build_stimuli(cfg, echo=messages.append)
    assert not [w for w in caught if issubclass(w.category, DurationMismatchWarning)]
    assert result["rendered"] == 2
    with open(result["manifest"], newline="") as f:
        rows = {row["segment"]: row for row in csv.DictReader(f)}
    _check_sync(folder / "out" / rows["a"]["file"], source["wav"], 0.4, 1.5)
    _check_sync(folder / "out" / rows["b"]["file"], source["wav"], 2.1, SECONDS - 2.1)


def test_python_api_carries_the_cut_to_the_audio(source, tmp_path):
    settings = RenderSettings(width=96, height=72, msaa=0)
    motions = prepare_motions([source["motion"]], settings, start=1.01, end=2.5)
    assert (motions.start, motions.end) == (1.0, 2.5)             # frame-aligned: frame 30 begins the cut
    out = tmp_path / "api.mp4"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        render_video(motions, out, settings, audio=source["wav"])
    assert not [w for w in caught if issubclass(w.category, DurationMismatchWarning)]
    _check_sync(out, source["wav"], 1.0, 1.5)
    # motions cut by hand: the window is given explicitly
    out2 = tmp_path / "explicit.mp4"
    render_video(list(motions), out2, settings, audio=source["wav"], start=1.0, end=2.5)
    _check_sync(out2, source["wav"], 1.0, 1.5)


def test_a_cut_past_the_audio_is_a_clear_error_or_warning(source, tmp_path):
    samples = np.zeros((RATE, 1), dtype=np.float32)
    assert len(cut_audio(samples, RATE, 0.25, 0.5)) == RATE // 4
    with pytest.raises(InputError, match="the cut starts at 1.500 s but the audio lasts 1.000 s"):
        cut_audio(samples, RATE, 1.5)
    short = tmp_path / "short.wav"
    write_wav(short, samples, RATE)
    res = CliRunner().invoke(main, ["render", "video", str(source["motion"]), "--audio", str(short), "-o",
                                    str(tmp_path / "x.mp4"), *SIZE, "--start", "0.5", "--end", "2"])
    assert res.exit_code == 0, res.output
    assert "Warning:" in res.output and "trimming to the shorter" in res.output   # audio ends at 1 s


def test_still_time_is_on_the_files_clock(source, tmp_path):
    """--time 2.6 with --start 1.0 shows the file's frame at 2.6 s (frame 48 of the cut), not 3.6 s."""
    import imageio.v3 as iio

    imgs = {}
    for name, extra in {"time": ["--time", "2.6"], "file": ["--frame", "48"], "cut_clock": ["--frame", "78"]}.items():
        png = tmp_path / f"{name}.png"
        res = CliRunner().invoke(main, ["render", "still", str(source["motion"]), "-o", str(png), *SIZE,
                                        "--start", "1.0", *extra])
        assert res.exit_code == 0, res.output
        imgs[name] = iio.imread(png).astype(int)
    assert np.abs(imgs["time"] - imgs["file"]).max() == 0
    assert np.abs(imgs["time"] - imgs["cut_clock"]).max() > 100   # the arm is up at 2.6 s, down at 3.6 s
    res = CliRunner().invoke(main, ["render", "still", str(source["motion"]), "-o", str(tmp_path / "e.png"),
                                    "--start", "1.0", "--time", "0.5"])
    assert res.exit_code == 1 and "before the cut" in res.output
