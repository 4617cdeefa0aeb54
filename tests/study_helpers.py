"""Shared fixtures for the study-app tests: a small study with real MP4 stimuli."""
from __future__ import annotations

import pathlib
import textwrap

CONDITIONS = ["SYSALPHA", "SYSBETA", "NATURALGT"]
SEGMENTS = ["seg01", "seg02", "seg03"]
SECRET = "test-secret-key-0123456789"
ADMIN = "test-admin-token-0123456789"

STUDY_YAML = """\
id: gesture-test
title: Gesture test study
stimuli: stim/manifest.csv
platform: prolific
sessions: {sessions}
seed: 3
completion_code: DONE1234
failure_code: FAIL5678
max_failed_attention_checks: 2
reservation_minutes: 100
min_width: 800
pages:
  - type: consent
    id: consent
    title: Consent
    text: You will watch short videos and answer questions. Your answers are stored anonymously.
  - type: questionnaire
    id: demographics
    title: About you
    questions:
      - {{id: age, type: number, text: Your age, min: 18, max: 99}}
      - {{id: gender, type: choice, text: Gender, options: [female, male, other, prefer not to say]}}
      - {{id: comments, type: text, text: "Anything else?", required: false}}
  - type: instructions
    id: intro
    title: Instructions
    text: Compare the two videos.
  - type: training
    id: training
    of: hl
    count: 1
  - type: pairwise
    id: hl
    title: Which character moves more like a real person?
    conditions: [SYSALPHA, SYSBETA, NATURALGT]
    levels: 3
    questions:
      - {{id: human_likeness, text: "In which video does the character gesture more like a real person?"}}
    reasons:
      - {{id: smooth, text: Smoother motion}}
      - {{id: rhythm, text: Better rhythm}}
    pages: 3
    attention_checks: [2]
    muted: true
  - type: mushra
    id: ratings
    conditions: [SYSALPHA, SYSBETA]
    reference: NATURALGT
    question: {{id: human_likeness_rating, text: "How human-like does the gesture motion appear?"}}
    pages: 2
    attention_checks: [1]
    muted: true
  - type: pairwise
    id: app
    conditions: [SYSALPHA, SYSBETA]
    mismatched: true
    levels: 5
    questions:
      - {{id: appropriateness, text: "Which character's motion matches the speech better?"}}
    pages: 2
  - type: likert
    id: stmts
    conditions: [SYSALPHA, SYSBETA]
    points: 5
    statements:
      - {{id: natural, text: The motion looks natural., scale: naturalness}}
      - {{id: fits, text: The motion fits the speech., scale: appropriateness}}
    pages: 1
  - type: finish
    id: finish
    text: Thank you for taking part.
"""

ATTENTION = [("seg01", "this"), ("seg02", "equal"), ("seg01", "70"), ("seg02", "good")]


def make_study(folder, sessions: int = 6, seconds: float = 1.0, yaml_text: str | None = None):
    """Write stimuli + study.yaml + plans into ``folder``; returns the study path."""
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    from study_app.samples import make_sample_stimuli

    folder = pathlib.Path(folder)
    stim = folder / "stim"
    if not (stim / "manifest.csv").exists():
        make_sample_stimuli(stim, CONDITIONS, SEGMENTS, mismatched=True, attention=ATTENTION,
                            seconds=seconds)
    path = folder / "study.yaml"
    path.write_text(yaml_text or STUDY_YAML.format(sessions=sessions))
    study = load_study(path)
    write_plans(build_plans(study), default_plans_path(study))
    return path
