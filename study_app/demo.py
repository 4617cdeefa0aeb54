"""Demo step: build a small perceptual study from the sample stimuli and say how to serve it.

Uses the blinded videos + ``manifest.csv`` the render step wrote to
``out_dir/render/stimuli``; without them it writes tiny placeholder clips (imageio-ffmpeg)
for the sample conditions. Writes ``out_dir/study/study.yaml`` and its session plans.
"""
from __future__ import annotations

import csv
import itertools
import os
import pathlib

import yaml

MAX_MUSHRA = 8


def _stimuli(out_dir: pathlib.Path, target: pathlib.Path, echo) -> pathlib.Path:
    rendered = out_dir / "render" / "stimuli" / "manifest.csv"
    if rendered.is_file():
        echo(f"  using the rendered stimuli {rendered}")
        return silent_manifest(rendered, echo)
    from study_app.samples import make_sample_stimuli
    root = out_dir / "conditions"
    conditions = sorted(p.name for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
    conditions = conditions or ["natural", "baseline", "system"]
    segments = ["seg01", "seg02", "seg03"]
    path = make_sample_stimuli(target / "stimuli", conditions, segments, seconds=2.0,
                               attention=[(segments[0], "this"), (segments[1], "70")])
    echo(f"  no rendered stimuli found: wrote placeholder clips for {', '.join(conditions)} -> {path}")
    return path


def silent_manifest(path: pathlib.Path, echo) -> pathlib.Path:
    """The manifest for the demo's muted blocks: ``path`` itself, or, when it holds attention checks that
    only sound reveals (``check = distorted_audio``), a copy without them beside it (``study-manifest.csv``):
    in a muted block nobody could pass them, and ``study build`` refuses them there."""
    from evalsuite.contracts.manifest import AUDIO_CHECKS

    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        fields, rows = list(reader.fieldnames or []), list(reader)
    keep = [r for r in rows if not (r.get("kind") == "attention" and r.get("check") in AUDIO_CHECKS)]
    if len(keep) == len(rows):
        return path
    out = path.with_name("study-manifest.csv")
    with open(out, "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        writer.writerows(keep)
    echo(f"  the study's blocks are muted: left out {len(rows) - len(keep)} attention check(s) that need sound "
         f"-> {out.name}")
    return out


def study_definition(manifest_path: pathlib.Path, study_dir: pathlib.Path) -> dict:
    """A small pairwise + MUSHRA study over every condition of the manifest."""
    from study_app.definition import load_manifest
    from study_app.pages import get_block_kind

    manifest = load_manifest(manifest_path)
    stimuli = [s for s in manifest.stimuli if s.kind == "stimulus" and not s.mismatched]
    conditions = sorted({s.condition for s in stimuli})
    have = {(s.condition, s.segment) for s in stimuli}
    segments = sorted({s.segment for s in stimuli if all((c, s.segment) in have for c in conditions)})
    pairs = [list(p) for p in itertools.combinations(conditions, 2)]
    hl_pages = min(len(pairs), 4)
    pairwise = {"type": "pairwise", "id": "human_likeness",
                "title": "Which character moves more like a real person?",
                "conditions": conditions, "segments": segments, "levels": 3,
                "questions": [{"id": "human_likeness", "text": "In which video does the character's "
                               "motion look more like a real person's?"}],
                "pages": hl_pages, "muted": True}
    mushra = {"type": "mushra", "id": "ratings", "conditions": conditions[:MAX_MUSHRA],
              "segments": segments, "pages": len(segments), "muted": True,
              "question": {"id": "human_likeness_rating",
                           "text": "How human-like does the gesture motion appear?"}}
    for block, ptype, n_pages in ((pairwise, "pairwise", hl_pages), (mushra, "mushra", len(segments))):
        cfg = {"levels": 3, "bands": ["Bad", "Poor", "Fair", "Good", "Excellent"], "segments": segments}
        if get_block_kind(ptype).attention_pool(manifest, str(block["id"]), cfg) and n_pages >= 2:
            block["attention_checks"] = [n_pages - 1 if ptype == "pairwise" else 1]
    return {
        "id": "evalsuite-demo",
        "title": "Gesture study (evalsuite demo)",
        "stimuli": os.path.relpath(manifest_path, study_dir),
        "platform": "prolific",
        "completion_code": "DEMODONE",
        "failure_code": "DEMOFAIL",
        "sessions": 2 * len(pairs),
        "pages": [
            {"type": "consent", "id": "consent", "title": "Consent",
             "text": "You will watch short silent videos of an animated character and answer "
                     "questions about its gestures. It takes about five minutes.\n\n"
                     "Your answers are stored with your Prolific ID only."},
            {"type": "questionnaire", "id": "demographics", "title": "About you",
             "questions": [{"id": "age", "type": "number", "text": "Your age", "min": 18, "max": 99},
                           {"id": "gender", "type": "choice", "text": "Gender",
                            "options": ["female", "male", "other", "prefer not to say"]}]},
            {"type": "instructions", "id": "intro", "title": "Instructions",
             "text": "Watch both videos to the end, then answer. Some videos ask you to give a "
                     "particular answer: please do as they say."},
            # Practice needs a pair on a segment the session does not rate (one segment of three conditions has none).
            *([{"type": "training", "id": "training", "of": "human_likeness", "count": 1}]
              if len(pairs) * len(segments) > hl_pages else []),
            pairwise,
            mushra,
            {"type": "finish", "id": "finish", "text": "Thank you for taking part!"},
        ],
    }


def run(out_dir: pathlib.Path, echo) -> None:
    from study_app.definition import load_study
    from study_app.derived import write_derived
    from study_app.design import balance_report, build_plans, default_plans_path, write_plans

    target = out_dir / "study"
    target.mkdir(parents=True, exist_ok=True)
    manifest = _stimuli(out_dir, target, echo)
    study_path = target / "study.yaml"
    study_path.write_text(yaml.safe_dump(study_definition(manifest, target), sort_keys=False))
    study = load_study(study_path)
    write_derived(study.manifest, progress=False)     # video-only copies for the muted blocks, as `study build`
    plans = build_plans(study)
    plans_path = write_plans(plans, default_plans_path(study))
    pairs = balance_report(plans, study)["pairs"]
    per_pair = sorted({n for n in pairs.values()})
    n_pages = len(plans["plans"][0]["pages"])
    echo(f"  study {study_path}: {len(study.conditions)} conditions, {len(plans['plans'])} session "
         f"plans of {n_pages} pages -> {plans_path.name}")
    echo(f"  every comparison shown {'/'.join(map(str, per_pair))} times with A left (and as often right)")
    echo("  serve it locally:")
    echo(f"    evalsuite study serve {study_path} --admin-token $(evalsuite study admin-token)")
    echo(f"    participant link: http://127.0.0.1:5000/start/{study.id}?PROLIFIC_PID=5f00000000000000000000a1"
         "&STUDY_ID=5e00000000000000000000d0&SESSION_ID=s1   admin: http://127.0.0.1:5000/admin/")
    echo(f"    results: evalsuite study export {study_path} -o results.csv")
