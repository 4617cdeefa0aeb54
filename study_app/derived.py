"""Clips that ``evalsuite study build`` makes from the manifest's clips: audio-mismatched and video-only.

Two pairwise designs need a video the renderer did not write:

* **audio mismatching** (the GENEA Leaderboard's speech-gesture alignment, ``audio_mismatch: true``): the
  same motion twice, once with its own speech and once with the speech of another segment *of the same
  speaker*. The mismatched clip of condition ``c`` and segment ``m`` is ``c``'s clip of ``m`` with its video
  stream copied (not re-encoded) and the sound of ``c``'s clip of a donor segment ``d``, encoded AAC at
  128 kb/s as the renderer encodes sound, cut or padded with silence to ``m``'s length. The donors are a
  random derangement (no segment donates to itself) of each speaker's segments, seeded from the study's seed,
  block and condition: every segment donates exactly once per condition, so over the plans each speech
  segment is heard as often mismatched as matched (:func:`audio_balance`).
* **muted blocks** (``muted: true`` on a pairwise block): each clip that has sound gets a video-only copy
  (video stream copied, no audio stream), and the plans name the copy, so a participant cannot unmute the
  player and hear the speech; the player is muted as well.

The clips' names are registered when the definition is loaded (:attr:`Manifest.derived`, so plans and the
server know them); :func:`write_derived` writes the files into ``derived/`` beside the manifest (blinded
names: a hash of the source file names). The server refuses plans whose derived clips are missing.
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
import pathlib
import struct
import subprocess
from collections import Counter
from collections.abc import Callable
from typing import Any

from study_app.errors import StudyDefinitionError
from study_app.model import DerivedClip, Manifest, Stimulus
from study_app.ordering import order_rng
from study_app.playback import _boxes, probe_seconds

__all__ = ["DERIVED_FOLDER", "AUDIO_SUFFIX", "load_speakers", "derangement", "register_audio_mismatch",
           "register_silent", "has_audio", "write_derived", "missing_derived", "audio_balance"]

DERIVED_FOLDER = "derived"
AUDIO_SUFFIX = ":audio_mismatched"   # how results.csv names an audio-mismatched clip's condition
AUDIO_BITRATE = "128k"               # as renderers.video encodes sound


def derived_name(*parts: str) -> str:
    """``derived/<16 hex>.mp4``: blinded (a hash of the sources' blinded names and the recipe)."""
    digest = hashlib.sha256("|".join(("evalsuite-derived",) + parts).encode()).hexdigest()[:16]
    return f"{DERIVED_FOLDER}/{digest}.mp4"


def load_speakers(chk: Any, value: Any, where: str, segments: list[str]) -> dict[str, list[str]]:
    """Speaker -> the block's segments of that speaker, from the block's ``speakers`` (a mapping segment:
    speaker, or one speaker name for every segment). Fails naming the field when a segment has no speaker or
    a speaker has a single segment (no other speech of that speaker to mismatch with)."""
    field = f"{where}.speakers"
    if value is None:
        chk.fail(field, "missing; audio_mismatch needs each segment's speaker (the manifest names none): a "
                 "mapping segment: speaker, or one speaker name for all segments")
    if isinstance(value, str):
        value = {s: value for s in segments}
    if not isinstance(value, dict) or not all(isinstance(k, str) and isinstance(v, (str, int))
                                              and not isinstance(v, bool) for k, v in value.items()):
        chk.fail(field, "expected a mapping segment: speaker (or one speaker name for all segments)")
    missing = [s for s in segments if s not in value]
    if missing:
        chk.fail(field, f"no speaker for segment(s) {', '.join(missing[:5])}"
                 + (f" and {len(missing) - 5} more" if len(missing) > 5 else "") + "; expected one for every "
                 "segment of the block")
    groups: dict[str, list[str]] = {}
    for s in segments:
        groups.setdefault(str(value[s]), []).append(s)
    for speaker, segs in groups.items():
        if len(segs) < 2:
            chk.fail(field, f"speaker {speaker!r} has only one segment ({segs[0]}) in this block; audio "
                     "mismatching needs another segment of the same speaker: add one, or leave "
                     f"{segs[0]} out of the block's segments")
    return groups


def derangement(rng: Any, n: int) -> list[int]:
    """A uniformly random permutation ``p`` of ``range(n)`` with ``p[i] != i`` for every ``i`` (``n >= 2``):
    shuffles until no element stays in place (about ``e`` tries on average)."""
    if n < 2:
        raise ValueError("a derangement needs at least 2 elements")
    p = list(range(n))
    while True:
        rng.shuffle(p)
        if all(p[i] != i for i in range(n)):
            return p


def register_audio_mismatch(manifest: Manifest, block_id: str, conditions: list[str],
                            groups: dict[str, list[str]], seed: int) -> dict[tuple[str, str], str]:
    """Register the audio-mismatched clip of every (condition, segment) of a block; returns
    ``(condition, segment) -> derived file``. Donor segments: a derangement per speaker and condition."""
    matched = {(s.condition, s.segment): s for s in manifest.stimuli if s.kind == "stimulus" and not s.mismatched}
    out: dict[tuple[str, str], str] = {}
    for c in conditions:
        for speaker, segs in sorted(groups.items()):
            perm = derangement(order_rng(seed, block_id, "audio-mismatch", c, speaker), len(segs))
            for i, m in enumerate(segs):
                src, donor = matched[(c, m)], matched[(c, segs[perm[i]])]
                name = derived_name("audio", src.file, donor.file)
                stim = dataclasses.replace(src, file=name, audio_segment=donor.segment, motion_segment="")
                manifest.derived[name] = DerivedClip(stim, video=src.file, audio=donor.file, seconds=src.duration_s)
                out[(c, m)] = name
    return out


def register_silent(manifest: Manifest, files: list[str]) -> dict[str, str]:
    """Register a video-only copy of every clip in ``files`` that has sound; returns ``file -> copy``."""
    by_file = manifest.by_file()
    out: dict[str, str] = {}
    for f in files:
        if f in out or not has_audio(manifest.root / f):
            continue
        name = derived_name("silent", f)
        manifest.derived[name] = DerivedClip(dataclasses.replace(by_file[f], file=name, silent=True), video=f,
                                             seconds=by_file[f].duration_s)
        out[f] = name
    return out


def has_audio(path: pathlib.Path) -> bool:
    """Whether a media file has a sound track: the MP4/MOV track handlers (``hdlr`` = ``soun``), read from
    the header; other files are asked of ffmpeg."""
    try:
        with open(path, "rb") as fh:
            handlers = _mp4_handlers(fh, os.fstat(fh.fileno()).st_size)
    except (OSError, struct.error, ValueError, IndexError):
        handlers = None
    if handlers is None:
        from renderers.media_probe import probe
        return "audio_codec" in probe(path)
    return b"soun" in handlers


def _mp4_handlers(fh: Any, size: int) -> set[bytes] | None:
    for kind, start, end in _boxes(fh, 0, size):
        if kind != b"moov":
            continue
        found: set[bytes] = set()
        for trak, ts, te in _boxes(fh, start, end):
            for mdia, ms, me in (_boxes(fh, ts, te) if trak == b"trak" else ()):
                for hdlr, hs, _he in (_boxes(fh, ms, me) if mdia == b"mdia" else ()):
                    if hdlr == b"hdlr":
                        fh.seek(hs + 8)
                        found.add(fh.read(4))
        return found
    return None


def _stale(root: pathlib.Path, name: str, clip: DerivedClip) -> bool:
    out = root / name
    if not out.is_file():
        return True
    newest = max((root / f).stat().st_mtime_ns for f in (clip.video, clip.audio) if f)
    return out.stat().st_mtime_ns < newest


def missing_derived(manifest: Manifest) -> list[str]:
    """Derived clips whose file is missing or older than its sources (``study build`` writes them)."""
    return [f for f, clip in manifest.derived.items() if _stale(manifest.root, f, clip)]


def write_derived(manifest: Manifest, *, force: bool = False, progress: bool = True) -> list[str]:
    """Write the derived clips that are missing or older than their sources (all with ``force``) with
    imageio-ffmpeg's ffmpeg; returns their names. A source without sound where sound is needed is an error
    naming its manifest line."""
    import imageio_ffmpeg
    from tqdm import tqdm

    root = manifest.root
    todo = [f for f, clip in manifest.derived.items() if force or _stale(root, f, clip)]
    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    for name in tqdm(todo, desc="derived clips", unit="clip", disable=not (progress and todo)):
        clip = manifest.derived[name]
        _write_one(ffmpeg, root, name, clip, manifest)
    return todo


def _write_one(ffmpeg: str, root: pathlib.Path, name: str, clip: DerivedClip, manifest: Manifest) -> None:
    out = root / name
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.stem + ".part.mp4")
    cmd = [ffmpeg, "-nostdin", "-y", "-v", "error", "-i", str(root / clip.video)]
    if clip.audio:
        if not has_audio(root / clip.audio):
            donor = next((s for s in manifest.stimuli if s.file == clip.audio), None)
            raise StudyDefinitionError(f"{clip.audio!r} has no sound; an audio_mismatch block needs clips with "
                                       "their speech (render them with the audio)", path=manifest.path,
                                       line=donor.line if donor else None, field="file")
        seconds = clip.seconds or probe_seconds(root / clip.video)
        cmd += ["-i", str(root / clip.audio), "-map", "0:v:0", "-map", "1:a:0", "-c:v", "copy",
                "-c:a", "aac", "-b:a", AUDIO_BITRATE, "-af", "apad"]
        cmd += ["-t", f"{seconds:.6f}"] if seconds else ["-shortest"]
    else:
        cmd += ["-map", "0:v:0", "-c:v", "copy", "-an"]
    cmd += ["-map_metadata", "-1", "-movflags", "+faststart", "-f", "mp4", str(tmp)]
    proc = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    if proc.returncode != 0:
        tmp.unlink(missing_ok=True)
        last = (proc.stderr.strip().splitlines() or ["no message"])[-1]
        raise StudyDefinitionError(f"ffmpeg could not make {name} from {clip.video!r}"
                                   + (f" and {clip.audio!r}" if clip.audio else "") + f": {last}",
                                   path=manifest.path)
    os.replace(tmp, out)


def audio_balance(plans: dict, by_file: dict[str, Stimulus],
                  is_audio_block: Callable[[str], bool]) -> Counter:
    """``(block, speech segment, "matched" | "mismatched") -> pages`` over every plan's trial pages of the
    audio-mismatch blocks (training and check pages not counted): how often each segment's speech is heard
    with its own motion and with another segment's."""
    counts: Counter = Counter()
    for plan in plans["plans"]:
        for p in plan["pages"]:
            if p.get("training") or p.get("check") or not is_audio_block(p.get("block", "")):
                continue
            a, b = by_file[p["a"]], by_file[p["b"]]
            counts[(p["block"], a.segment, "matched")] += 1
            counts[(p["block"], b.audio_segment, "mismatched")] += 1
    return counts


def audio_balance_lines(plans: dict, study: Any) -> list[str]:
    """What ``study build`` prints per audio-mismatch block: each speech segment heard matched / mismatched."""
    blocks = {b for b, page in study.blocks.items() if page.cfg.get("audio_mismatch")}
    counts = audio_balance(plans, study.manifest.by_file(), blocks.__contains__)
    lines = []
    for block in sorted(blocks):
        segs = sorted({k[1] for k in counts if k[0] == block})
        lines.append(f"audio mismatch {block}: speech heard matched / mismatched: " + ", ".join(
            f"{s} {counts[(block, s, 'matched')]}/{counts[(block, s, 'mismatched')]}" for s in segs))
    return lines
