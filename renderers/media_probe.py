"""What ffmpeg says about a media file (codecs, size, frame and sample rates, duration)."""
from __future__ import annotations

import re
import subprocess

__all__ = ["probe"]

_DURATION_RE = re.compile(r"Duration:\s*(\d+):(\d+):([\d.]+)")
_VIDEO_RE = re.compile(r"Stream #\S+.*?Video:\s*(\w+).*?(\d{2,5})x(\d{2,5})")
_FPS_RE = re.compile(r"([\d.]+)\s*fps")
_AUDIO_RE = re.compile(r"Stream #\S+.*?Audio:\s*(\w+).*?(\d+)\s*Hz")


def probe(path) -> dict:
    """What ``ffmpeg -i`` says about a media file: codecs, size, fps, container duration.

    Keys: ``duration``, ``video_codec``, ``width``, ``height``, ``fps``, ``audio_codec``,
    ``audio_rate`` (missing keys mean no such stream).
    """
    import imageio_ffmpeg

    proc = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
                          capture_output=True, text=True, errors="replace")
    text = proc.stderr
    info: dict = {}
    m = _DURATION_RE.search(text)
    if m:
        info["duration"] = int(m.group(1)) * 3600 + int(m.group(2)) * 60 + float(m.group(3))
    for line in text.splitlines():
        v = _VIDEO_RE.search(line)
        if v and "video_codec" not in info:
            info["video_codec"], info["width"], info["height"] = v.group(1), int(v.group(2)), int(v.group(3))
            f = _FPS_RE.search(line)
            if f:
                info["fps"] = float(f.group(1))
        a = _AUDIO_RE.search(line)
        if a and "audio_codec" not in info:
            info["audio_codec"], info["audio_rate"] = a.group(1), int(a.group(2))
    return info
