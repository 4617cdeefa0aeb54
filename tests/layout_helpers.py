"""A study for the layout tests: a 5-level pairwise page, MUSHRA pages with 5 and 6 videos (side by side
and the HEMVIP display), Likert pages with 7 and 5 points; phones allowed; 16:9 clips."""
from __future__ import annotations

import pathlib

CONDITIONS = ["SYSA", "SYSB", "SYSC", "SYSD", "SYSE", "NATURALGT"]

LAYOUT_YAML = """\
id: layout-test
title: Gesture study
stimuli: stim/manifest.csv
platform: prolific
sessions: 4
seed: 1
completion_code: DONE1234
failure_code: FAIL5678
min_width: 320
block_mobile: false
pages:
  - type: pairwise
    id: hl
    title: Which character moves more like a real person?
    text: Watch both videos to the end, then answer the question below.
    conditions: [SYSA, SYSB]
    levels: 5
    questions:
      - {id: human_likeness, text: "In which video does the character gesture more like a real person?"}
    reasons:
      - {id: smooth, text: Smoother motion}
      - {id: rhythm, text: Better rhythm}
      - {id: shape, text: More natural hand shapes}
    reasons_required: true
    pages: 1
    muted: true
  - type: mushra
    id: m5
    conditions: [SYSA, SYSB, SYSC, SYSD]
    reference: NATURALGT
    question: {id: hl5, text: "How human-like does the gesture motion appear?"}
    pages: 1
    muted: true
  - type: mushra
    id: m6
    conditions: [SYSA, SYSB, SYSC, SYSD, SYSE]
    reference: NATURALGT
    question: {id: hl6, text: "How human-like does the gesture motion appear?"}
    slider_numbers: false
    pages: 1
    muted: true
  - type: mushra
    id: hv
    layout: hemvip
    conditions: [SYSA, SYSB, SYSC, SYSD, SYSE]
    reference: NATURALGT
    question: {id: hlhv, text: "How human-like does the gesture motion appear?"}
    slider_numbers: false
    pages: 1
    muted: true
  - type: likert
    id: lk7
    conditions: [SYSA]
    points: 7
    statements:
      - {id: natural, text: The motion looks natural., scale: naturalness}
      - {id: fits, text: "The motion fits the speech, both in its rhythm and in what is said.", scale: appropriateness}
      - {id: calm, text: The character seems calm., scale: calm}
    pages: 1
  - type: likert
    id: lk5
    conditions: [SYSB]
    points: 5
    labels: [Strongly disagree, Disagree, Neither agree nor disagree, Agree, Strongly agree]
    statements:
      - {id: natural5, text: The motion looks natural., scale: naturalness}
    pages: 1
  - type: finish
    id: finish
    text: Thank you.
"""


def make_layout_study(folder, yaml_text=LAYOUT_YAML):
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    from study_app.samples import make_sample_stimuli

    folder = pathlib.Path(folder)
    if not (folder / "stim" / "manifest.csv").exists():
        # 16:9 clips, as the render step's widescreen output and most GENEA material
        make_sample_stimuli(folder / "stim", CONDITIONS, ["seg01", "seg02"], seconds=0.4, size=(256, 144))
    path = folder / "layout.yaml"
    path.write_text(yaml_text)
    study = load_study(path)
    write_plans(build_plans(study), default_plans_path(study))
    return path


MORE_CONDITIONS = ["SYSA", "SYSB", "SYSC", "SYSD", "SYSE", "SYSF", "SYSG", "NATURALGT"]

# Siblings of what the review tried: two questions on a pairwise page with longer instructions, 8 videos
# on a MUSHRA page (two rows; and the HEMVIP display), an 11-point Likert scale.
MORE_YAML = """\
id: layout-more
title: Gesture study with a rather long title that needs to be shortened on a phone
stimuli: stim/manifest.csv
platform: prolific
sessions: 2
seed: 1
completion_code: DONE1234
failure_code: FAIL5678
min_width: 320
block_mobile: false
pages:
  - type: pairwise
    id: two
    title: Compare the two characters
    text: "Watch both videos to the end. Then answer both questions below.\\n\\nThere are no right or wrong answers."
    conditions: [SYSA, SYSB, SYSC]
    levels: 3
    questions:
      - {id: human_likeness, text: "In which video does the character gesture more like a real person?"}
      - {id: appropriateness, text: "In which video does the motion fit the speech better?"}
    reasons:
      - {id: smooth, text: Smoother motion}
      - {id: rhythm, text: Better rhythm}
    pages: 1
    muted: true
  - type: mushra
    id: m8
    conditions: [SYSA, SYSB, SYSC, SYSD, SYSE, SYSF, SYSG]
    reference: NATURALGT
    question: {id: hl8, text: "How human-like does the gesture motion appear?"}
    pages: 1
    muted: true
  - type: mushra
    id: hv8
    layout: hemvip
    conditions: [SYSA, SYSB, SYSC, SYSD, SYSE, SYSF, SYSG]
    reference: NATURALGT
    question: {id: hlhv8, text: "How human-like does the gesture motion appear?"}
    pages: 1
    muted: true
  - type: likert
    id: lk11
    conditions: [SYSA]
    points: 11
    labels: [Not at all, Completely]
    statements:
      - {id: natural, text: The motion looks natural., scale: naturalness}
      - {id: fits, text: The motion fits the speech., scale: appropriateness}
      - {id: calm, text: The character seems calm., scale: calm}
      - {id: lively, text: The character seems lively., scale: lively}
    pages: 1
  - type: finish
    id: finish
    text: Thank you.
"""


def make_more_study(folder):
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    from study_app.samples import make_sample_stimuli

    folder = pathlib.Path(folder)
    make_sample_stimuli(folder / "stim", MORE_CONDITIONS, ["seg01"], seconds=0.4, size=(256, 144))
    path = folder / "more.yaml"
    path.write_text(MORE_YAML)
    study = load_study(path)
    write_plans(build_plans(study), default_plans_path(study))
    return path
