"""Demo step: a side-by-side video of the sample conditions and a tiny set of study stimuli.

Uses the condition folders an earlier step wrote (``out_dir/conditions/<condition>/<segment>.bvh|.npz``) and
their speech (``out_dir/speech/<segment>.wav``) or, if there are none, the bundled BVH samples with synthesised
speech-like audio (tone bursts).
Writes ``out_dir/render/compare.mp4``, ``compare.png`` and ``out_dir/render/stimuli/``
(blinded videos + ``manifest.csv``), all drawn with the mannequin body style.
"""
from __future__ import annotations

import pathlib

import yaml

from renderers.audio import speech_like_audio, write_wav

PREFERRED_ORDER = ("natural", "mismatched", "static", "jitter", "smoothed")
SECONDS = 3.0
RATE = 16000


def find_conditions(out_dir: pathlib.Path) -> tuple[dict[str, str], list[str]]:
    """``({condition: path pattern with {segment}}, segments)`` from the condition folders,
    or from the bundled samples (each sample one 'condition', one segment 'sample')."""
    root = out_dir / "conditions"
    folders = sorted(p for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
    suffix = {p.name: next((s for s in (".bvh", ".npz") if any(p.glob(f"*{s}"))), ".bvh") for p in folders}
    stems = [{f.stem for f in p.glob(f"*{suffix[p.name]}")} for p in folders]
    common = sorted(set.intersection(*stems)) if stems else []
    if folders and common:
        names = sorted((p.name for p in folders),
                       key=lambda n: (PREFERRED_ORDER.index(n) if n in PREFERRED_ORDER else len(PREFERRED_ORDER), n))
        return {n: str(root / n / ("{segment}" + suffix[n])) for n in names}, common
    from evalsuite.motion.samples import sample_paths

    samples = [p for p in sample_paths() if p.stem != "bvhio_example"] or sample_paths()
    return {p.stem.replace("_", "-"): str(p) for p in samples}, ["sample"]


def run(out_dir: pathlib.Path, echo) -> None:
    from renderers.render import prepare_motions, render_still, render_video
    from renderers.scene import RenderSettings
    from renderers.stimuli import build_stimuli

    target = out_dir / "render"
    target.mkdir(parents=True, exist_ok=True)
    conditions, segments = find_conditions(out_dir)
    source = "condition folders" if segments != ["sample"] else "bundled samples (no condition folders found)"
    audio_dir = out_dir / "speech"
    seconds = 6.0  # the corpus's own speech: a longer excerpt
    if not all((audio_dir / f"{seg}.wav").is_file() for seg in segments[:2]):
        seconds = SECONDS
        audio_dir = target / "audio"
        audio_dir.mkdir(exist_ok=True)
        for k, seg in enumerate(segments[:2]):
            write_wav(audio_dir / f"{seg}.wav", speech_like_audio(SECONDS, RATE, seed=k), RATE)

    seg = segments[0]
    settings = RenderSettings(width=240, height=180, framing="full", fps=30.0, body="mannequin")
    paths = [pattern.format(segment=seg) for pattern in conditions.values()]
    motions = prepare_motions(paths, settings, 0.0, seconds)
    names = list(conditions)
    layout = "grid" if len(names) > 3 else "side"
    info = render_video(motions, target / "compare.mp4", settings, audio=audio_dir / f"{seg}.wav",
                        captions=names, layout=layout, label="compare")
    render_still(motions, target / "compare.png", settings,
                 frame=info["n_frames"] // 2, captions=names, layout=layout)
    echo(f"  {source}: {', '.join(names)}; segment {seg!r}")
    echo(f"  side-by-side video {target / 'compare.mp4'} ({info['width']}x{info['height']}, "
         f"{info['n_frames']} frames at {info['fps']:g} fps, synthetic speech muxed) and still compare.png")

    config = {
        "output": "stimuli",
        "segments": {s: {"audio": str(audio_dir / f"{s}.wav")} for s in segments[:2]},
        "conditions": conditions,
        "start": 0.0,
        "end": seconds,
        "render": {"width": 192, "height": 144, "fps": 30.0, "framing": "full", "style": "mannequin"},
        "equal_size": "cbr",      # a file's size must not tell a participant which condition it shows
        "bitrate": "300k",
        "attention_checks": [
            {"check": "instruction", "segment": segments[0], "condition": names[0],
             "text": "Attention: please rate this video 73", "expected": "73", "appear_s": 1.0},
            {"check": "distorted_audio", "segment": segments[-1 if len(segments) < 2 else 1], "condition": names[0]},
            {"check": "distorted_video", "segment": segments[0], "condition": names[-1]},
        ],
    }
    config_path = target / "stimuli.yaml"
    config_path.write_text(yaml.safe_dump(config, sort_keys=False))
    result = build_stimuli(config_path, echo=echo)
    echo(f"  {len(result['rows'])} blinded study stimuli ({len(names)} conditions x {len(segments[:2])} segments "
         f"+ 3 attention checks) and the private manifest {result['manifest']}")
