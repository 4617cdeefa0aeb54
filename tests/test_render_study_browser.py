"""Stimulus sets of each body style (stick, mannequin, character) rendered with ``evalsuite render stimuli``, built
into a pairwise study with ``evalsuite study build`` and played in headless Chromium: every video on a participant's
page reaches ``readyState >= 3``, plays past 0.3 s, has the render size and no media error, and shows the served
file's picture at that time (drawn on a canvas, compared with ffmpeg's decoding); the admin page and the raw export
say the embodiment the manifest records (style, character, framing, face). The mannequin's block is muted, as the
GENEA Leaderboard's realism pairs: its pages play the video-only copies ``study build`` derives, with no sound."""
from __future__ import annotations

import csv
import functools
import json
import os
import time

import numpy as np
import pytest
import study_helpers as h
import yaml
from browser_helpers import Server, chromium
from click.testing import CliRunner
from render_helpers import RATE, decode, genea2023_standin
from test_study_browser import ARGS

from evalsuite.cli import main as evalsuite_cli
from evalsuite.motion.io import save_motion
from renderers.audio import speech_like_audio, write_wav
from study_app import create_app
from study_app.cli import study as study_cli

pytestmark = [pytest.mark.browser, pytest.mark.slow]

STYLES = ("stick", "mannequin", "character")
WIDTH, HEIGHT, SECONDS, FPS = 160, 120, 1.0, 30
SEGMENTS = ("seg01", "seg02")
CONDITIONS = {"natural": 1.0, "system": 0.5}   # condition -> scale of the motion's rotations
EMBODIMENT = {"stick": "stick body; framing above-knees; face visible",
              "mannequin": "mannequin body; framing above-knees; face blank",
              "character": "character body; character mpfb2_neutral.glb; framing upper; face blank"}
# the mannequin's study is muted as the GENEA Leaderboard's realism pairs: study build derives video-only copies
MUTED = {"stick": False, "mannequin": True, "character": False}
RENDER = {"stick": {"framing": "above-knees"}, "mannequin": {"framing": "above-knees", "face": "blank"},
          "character": {"framing": "upper", "face": "blank"}}

STUDY_YAML = """\
id: styles-{style}
title: Body style {style}
stimuli: stim/manifest.csv
platform: anonymous
sessions: 1
seed: 1
min_width: 800
pages:
  - type: pairwise
    id: hl
    conditions: [natural, system]
    questions:
      - {{id: human_likeness, text: "In which video does the character gesture more like a real person?"}}
    pages: 2
    muted: {muted}
  - type: finish
    id: finish
    text: Thank you for taking part.
"""

# what the test reads from the videos: plain expressions evaluated from Python (no string predicates, which the
# pages' Content Security Policy refuses)
STATE = ("Array.from(document.querySelectorAll('video[data-slot]')).map(v => ({ready: v.readyState, "
         "time: v.currentTime, width: v.videoWidth, height: v.videoHeight, error: v.error ? v.error.code : null, "
         "audio: v.webkitAudioDecodedByteCount}))")
# the frame a video shows, drawn on a canvas, as grey levels (0.299 R + 0.587 G + 0.114 B), and its time
FRAME = ("(() => {{ const v = document.querySelector('video[data-slot=\"{slot}\"]'); const c = document.createElement("
         "'canvas'); c.width = v.videoWidth; c.height = v.videoHeight; const g = c.getContext('2d'); "
         "g.drawImage(v, 0, 0); const t = v.currentTime; const d = g.getImageData(0, 0, c.width, c.height).data; "
         "const grey = []; for (let i = 0; i < d.length; i += 4) grey.push(0.299 * d[i] + 0.587 * d[i + 1] + "
         "0.114 * d[i + 2]); return {{time: t, grey: grey}}; }})()")


def render_set(root, style):
    """Motion of 2 conditions x 2 segments on the GENEA 2023 stand-in skeleton (a skeleton every style draws, the
    character through its shipped joint map), speech, a stimuli config, and ``evalsuite render stimuli`` on it."""
    base = genea2023_standin(SECONDS, FPS)
    for cond, scale in CONDITIONS.items():
        for k, seg in enumerate(SEGMENTS):
            values = base.values.copy()
            values[:, 12:] *= scale + 0.2 * k         # joint rotations; the two roots' channels stay
            (root / cond).mkdir(parents=True, exist_ok=True)
            save_motion(type(base)(base.skeleton, values, base.fps, name=seg), root / cond / f"{seg}.bvh")
    for k, seg in enumerate(SEGMENTS):
        write_wav(root / f"{seg}.wav", speech_like_audio(SECONDS, RATE, seed=k), RATE)
    cfg = {"output": "stim", "segments": list(SEGMENTS), "audio": "{segment}.wav",
           "conditions": {c: f"{c}/{{segment}}.bvh" for c in CONDITIONS},
           "render": {"width": WIDTH, "height": HEIGHT, "fps": FPS, "msaa": 0, "style": style, **RENDER[style]}}
    (root / "stimuli.yaml").write_text(yaml.safe_dump(cfg))
    res = CliRunner().invoke(evalsuite_cli, ["render", "stimuli", str(root / "stimuli.yaml")])
    assert res.exit_code == 0, res.output
    study = root / "study.yaml"
    study.write_text(STUDY_YAML.format(style=style, muted=str(MUTED[style]).lower()))
    res = CliRunner().invoke(study_cli, ["build", str(study)])
    assert res.exit_code == 0, res.output
    return study


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    """The three rendered and built studies, made once for the module (rendering is the slow part)."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    return {style: render_set(tmp_path_factory.mktemp(style), style) for style in STYLES}


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)
        yield b
        b.close()


@pytest.fixture()
def served(sets, tmp_path):
    def make(style):
        return create_app({"STUDY": str(sets[style]), "DATABASE_URL": f"sqlite:///{tmp_path / 'study.db'}",
                           "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                           "INSTANCE_PATH": str(tmp_path / "inst")})
    servers = []

    def start(style):
        servers.append(Server(lambda: make(style)))
        return servers[-1]
    yield start
    for s in servers:
        s.stop()


@functools.cache
def decoded_grey(path):
    """The frames of a video file as ffmpeg decodes them, in grey levels ``(T, H, W)``."""
    _, frames = decode(path)
    return frames.astype(float) @ np.array([0.299, 0.587, 0.114])


def play_every_video(page):
    """Click each video's play button and poll (from Python) until it has played past 0.3 s; returns each
    slot's state at that moment, with the frame it shows then."""
    seen = {}
    for k in range(page.locator("video[data-slot]").count()):
        page.click(f"button.play[data-slot='{k}']")
        deadline = time.monotonic() + 20.0
        while True:
            state = page.evaluate(STATE)[k]
            if state["time"] > 0.3 or state["error"] is not None or time.monotonic() > deadline:
                break
            page.wait_for_timeout(50)
        frame = page.evaluate(FRAME.format(slot=k))
        state.update(frame_time=frame["time"], grey=np.reshape(frame["grey"], (state["height"], state["width"])))
        seen[k] = state
        page.wait_for_selector(f".status[data-slot='{k}'].ok")   # played to the end, as the study requires
        state["audio"] = page.evaluate(STATE)[k]["audio"]
    return seen


@pytest.mark.parametrize("style", STYLES)
def test_stimulus_set_plays_in_a_study(style, sets, served, browser):
    with open(sets[style].parent / "stim" / "manifest.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["style"] for r in rows} == {style}
    server = served(style)
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    page.set_default_timeout(20000)
    page.goto(f"{server.url}/start/styles-{style}")
    pages = 0
    while page.locator("#page-data").count():
        sid = page.url.split("/s/")[1].split("/")[0]
        spec = h.plan_pages(server.app, sid)[json.loads(page.text_content("#page-data"))["index"]]
        states = play_every_video(page)
        assert len(states) == 2
        for k, s in states.items():
            assert s["error"] is None, f"{style} slot {k}: media error {s['error']}"
            assert s["ready"] >= 3, f"{style} slot {k}: readyState {s['ready']}"
            assert s["time"] > 0.3, f"{style} slot {k}: stopped at {s['time']:.2f} s"
            assert (s["width"], s["height"]) == (WIDTH, HEIGHT)
            # speech decoded, except in the muted block, whose video-only copies carry none
            assert (s["audio"] == 0) == MUTED[style], f"{style} slot {k}: {s['audio']} bytes of sound decoded"
            # the picture is the served file's at that time, as ffmpeg decodes it (within 3 frames)
            file = spec["a"] if (k == 0) == (spec["position_a"] == "left") else spec["b"]
            assert file.startswith("derived/") == MUTED[style]
            frames = decoded_grey(str(sets[style].parent / "stim" / file))
            at = int(s["frame_time"] * FPS)
            diff = min(np.abs(frames[i] - s["grey"]).mean() for i in range(max(at - 3, 0), min(at + 4, len(frames))))
            assert diff < 1.5, f"{style} slot {k}: the frame at {s['frame_time']:.2f} s differs by {diff:.2f} levels"
            # ... which is not the first frame any more (measured: 4.5 to 10 levels from it, 0.2 to 0.9 from the
            # file's frame at that time), and not blank
            assert np.abs(frames[0] - s["grey"]).mean() > diff + 2.0, f"{style} slot {k}: still the first frame"
            assert np.ptp(s["grey"]) > 50, f"{style} slot {k}: a blank frame"
        page.check("input[name='q-human_likeness'][value='left']")
        page.wait_for_selector("#next:not([disabled])")
        with page.expect_navigation():
            page.click("#next")
        pages += 1
    assert pages == 2
    assert "Thank you" in page.content()
    context.close()
    # the researcher sees the embodiment on the admin page (its CSP allows no string predicates: read from Python)
    admin = browser.new_context(extra_http_headers={"Authorization": f"Bearer {h.ADMIN}"})
    board = admin.new_page()
    board.goto(server.url + "/admin/")
    assert board.text_content("#embodiment") == f"Stimuli: {EMBODIMENT[style]}"
    raw = json.loads(admin.request.get(server.url + "/admin/export/raw.json").text())
    admin.close()
    expected = {col: [rows[0][col]] for col in ("style", "character", "framing", "face") if rows[0][col]}
    assert raw["embodiment"] == expected
    # both answers stored, each page's clips fetched whole and watched long enough (the playback check)
    assert [a["page"] for a in raw["answers"]] == ["hl-01", "hl-02"]
    for a in raw["answers"]:
        assert not a["playback"]["implausible"], a["playback"]["reasons"]
