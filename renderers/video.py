"""H.264 MP4 writing with the ffmpeg that imageio-ffmpeg ships, audio muxing, and probing.

Audio is aligned to frame 0 and cut to the video's exact length before muxing; when audio
and motion lengths differ by more than one frame, the longer one is trimmed to the shorter
and a :class:`DurationMismatchWarning` says so.
"""
from __future__ import annotations

import contextlib
import math
import os
import pathlib
import queue
import tempfile
import threading
import warnings

import numpy as np

from evalsuite.errors import InputError
from renderers.audio import fit_length, write_wav
from renderers.filesize import cbr_params
from renderers.media_probe import probe as probe  # public here too: renderers.video.probe


class DurationMismatchWarning(UserWarning):
    """Audio and motion lengths differ by more than one video frame."""


def fit_audio(samples: np.ndarray, rate: int, n_frames: int, fps: float, label: str = "") -> tuple[np.ndarray, int]:
    """Align audio with ``n_frames`` of video: ``(samples cut to the video, frames to keep)``.

    Both start at time 0. If the audio is shorter than the motion by more than one frame,
    the video is cut to the audio; if longer, the audio is cut; either way with a warning.
    Differences up to one frame are absorbed (audio cut or padded with silence).
    """
    motion_s = n_frames / fps
    audio_s = len(samples) / rate
    if abs(motion_s - audio_s) > 1.0 / fps:
        warnings.warn(f"{label + ': ' if label else ''}audio lasts {audio_s:.3f} s but the motion "
                      f"{motion_s:.3f} s ({n_frames} frames at {fps:g} fps); trimming to the shorter "
                      f"({min(audio_s, motion_s):.3f} s)", DurationMismatchWarning, stacklevel=2)
    keep = n_frames if audio_s >= motion_s - 1.0 / fps else int(math.floor(audio_s * fps + 1e-9))
    if keep < 1:
        raise InputError(f"audio of {audio_s:.3f} s is shorter than one frame")
    return fit_length(samples, int(round(keep / fps * rate))), keep


# Up to this many pixels a frame, one x264 thread (veryfast) encodes faster than the renderer draws (about
# 550 frames/s at 640x480 on one core of the benchmark machine), so more threads only compete with the
# renderer's: x264's own choice (1.5 x cores, plus lookahead) took 1.17 s of CPU for 300 such frames where one
# thread took 0.88 s, the same file size (docs/results/speed.md). Larger frames keep x264's choice.
ONE_THREAD_PIXELS = 1280 * 720


def x264_threads(width: int, height: int) -> int:
    """x264's ``-threads`` for frames of ``width`` x ``height``: 1 up to :data:`ONE_THREAD_PIXELS`, else 0
    (x264 chooses)."""
    return 1 if int(width) * int(height) <= ONE_THREAD_PIXELS else 0


class VideoWriter:
    """Write RGB frames to an H.264 MP4 (yuv420p, playable in every browser), audio optional.

    Args:
        path: output ``.mp4``.
        width, height: frame size (even numbers).
        fps: frame rate (any positive number; passed to ffmpeg as a fraction).
        audio: ``(samples (n, ch) float32, rate)`` already aligned with the video, or None.
        crf: x264 constant rate factor (18 = visually lossless, 23 = ffmpeg's default).
        bitrate: constant bitrate instead of ``crf`` (e.g. ``"400k"``; :func:`renderers.filesize.cbr_params`).
        threads: x264's threads; None: :func:`x264_threads` of the frame size.

    Frames go to ffmpeg from a writer thread through a short queue (``QUEUE`` frames), so the caller renders
    the next frame while ffmpeg takes the previous one from the pipe (a write of a whole frame waits until
    ffmpeg has read it); :meth:`write` copies the frame, so the caller may reuse its array at once. An error
    in the thread (ffmpeg gone) is raised by the next :meth:`write` or by :meth:`close`.
    """

    QUEUE = 4

    def __init__(self, path, width: int, height: int, fps: float, audio=None, crf: int = 20,
                 preset: str = "veryfast", bitrate: str | None = None, threads: int | None = None):
        import imageio_ffmpeg

        self.path = pathlib.Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.n_frames = 0
        self._wav = None
        audio_path = None
        if audio is not None:
            fd, self._wav = tempfile.mkstemp(suffix=".wav", dir=self.path.parent, prefix=".audio-")
            os.close(fd)
            write_wav(self._wav, audio[0], audio[1])
            audio_path = self._wav
        rate = cbr_params(bitrate) if bitrate else ["-crf", str(int(crf))]
        threads = x264_threads(width, height) if threads is None else int(threads)
        params = ["-preset", preset, *rate, "-threads", str(threads), "-movflags", "+faststart"]
        if audio is not None:
            params += ["-b:a", "128k"]
        self._gen = imageio_ffmpeg.write_frames(
            str(self.path), (int(width), int(height)), fps=float(fps), codec="libx264", quality=None,
            macro_block_size=2, pix_fmt_out="yuv420p", output_params=params, audio_path=audio_path,
            audio_codec="aac" if audio is not None else None, ffmpeg_log_level="error")
        self._gen.send(None)
        self._queue: queue.Queue = queue.Queue(maxsize=self.QUEUE)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._pump, name=f"ffmpeg writer {self.path.name}", daemon=True)
        self._thread.start()

    def _pump(self) -> None:
        """The writer thread: send queued frames to ffmpeg until ``None``; keep the first error."""
        while (data := self._queue.get()) is not None:
            if self._error is None:
                try:
                    self._gen.send(data)
                except BaseException as exc:   # re-raised in the caller's thread
                    self._error = exc

    def write(self, frame: np.ndarray) -> None:
        if self._error is not None:
            raise self._error
        self._queue.put(np.asarray(frame, dtype=np.uint8).tobytes())     # one copy, in row order, whatever the strides
        self.n_frames += 1

    def close(self) -> None:
        if self._gen is not None:
            self._queue.put(None)
            self._thread.join()
            self._gen.close()
            self._gen = None
        if self._wav is not None:
            with contextlib.suppress(OSError):
                os.remove(self._wav)
            self._wav = None
        if self._error is not None:          # after the temporary WAV is gone; raised once
            error, self._error = self._error, None
            raise error

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc):
        failed = exc_type is not None
        try:
            self.close()
        except BaseException:
            failed = True
            raise
        finally:
            if failed:   # an unfinished file is no video
                with contextlib.suppress(OSError):
                    self.path.unlink()


def read_video_frames(path):
    """Iterate RGB frames ``(H, W, 3)`` uint8 of a video; returns also its size and fps first.

    Yields ``(meta, frame)`` pairs where ``meta`` is imageio-ffmpeg's metadata dict.
    """
    import imageio_ffmpeg

    gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    meta = next(gen)
    w, h = meta["size"]
    for raw in gen:
        yield meta, np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)
