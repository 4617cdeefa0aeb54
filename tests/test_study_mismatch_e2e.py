"""End to end, the GENEA Leaderboard's two designs: an audio-mismatch block (same motion, own vs another segment's
speech of the same speaker) and muted realism pairs. `evalsuite study build` derives the clips from a tiny stimulus
set with sound, a real server serves it, one participant walks it in headless Chromium (Playwright), `evalsuite
study export` writes results.csv and `evalsuite analyze` reports the audio-mismatch table and the realism
comparisons with the counts the participant gave."""
from __future__ import annotations

import csv
import json

import pandas as pd
import pytest
import study_helpers as h
from av_helpers import make_av_stimuli
from browser_helpers import ARGS, Server, chromium
from click.testing import CliRunner

from study_app import create_app
from study_app.context import study_of

pytestmark = [pytest.mark.browser, pytest.mark.slow]

CONDITIONS = ["SYSA", "SYSB"]
SEGMENTS = ["s1", "s2", "s3", "s4"]
STUDY = """\
id: leaderboard-protocol
stimuli: stim/manifest.csv
platform: prolific
completion_code: DONE1234
sessions: 2
seed: 11
min_width: 800
pages:
  - {type: instructions, id: intro, text: "Watch both videos to the end."}
  - type: pairwise
    id: align
    conditions: [SYSA, SYSB]
    audio_mismatch: true
    speakers: {s1: anna, s2: anna, s3: ben, s4: ben}
    levels: 5
    questions: [{id: alignment, text: "Both videos have the same motion, but different speech. In which video do the character's movements fit the speech better?"}]
    pages: 4
  - type: pairwise
    id: realism
    conditions: [SYSA, SYSB]
    muted: true
    questions: [{id: realism, text: "In which video does the character gesture more like a real person?"}]
    pages: 2
  - {type: finish, id: finish, text: Thank you.}
"""


def _cli(*args):
    from evalsuite.cli import main

    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return result.output


def test_audio_mismatch_and_muted_pairs_from_build_to_analyze_in_chromium(tmp_path):
    make_av_stimuli(tmp_path / "stim", CONDITIONS, SEGMENTS, seconds=0.5)
    (tmp_path / "study.yaml").write_text(STUDY)
    db = f"sqlite:///{tmp_path / 'study.db'}"
    built = _cli("study", "build", tmp_path / "study.yaml")
    assert "16 derived clip(s) written" in built      # 8 audio-mismatched + 8 video-only copies
    assert "audio mismatch align: speech heard matched / mismatched: s1 2/2, s2 2/2, s3 2/2, s4 2/2" in built

    server = Server(lambda: create_app({"STUDY": str(tmp_path / "study.yaml"), "DATABASE_URL": db,
                                        "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN,
                                        "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "inst")}))
    study = study_of(server.app)
    by_file = study.manifest.by_file()
    given: dict[str, list[str]] = {"align": [], "realism": []}
    from playwright.sync_api import sync_playwright
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=chromium(), headless=True,
                                         args=[*ARGS, "--autoplay-policy=no-user-gesture-required"])
            page = browser.new_context(viewport={"width": 1280, "height": 900}).new_page()
            page.set_default_timeout(20000)
            page.goto(server.url + h.prolific_url("7b1c2d3e4f5a6b7c8d9e0f1a", study.id))
            sid = page.url.split("/s/")[1].strip("/")
            while page.locator("#page-data").count():
                data = json.loads(page.locator("#page-data").text_content())
                spec = h.plan_pages(server.app, sid)[data["index"]] if data["index"] else {"type": "instructions"}
                if spec["type"] == "pairwise":
                    n = page.locator("video[data-slot]").count()
                    for k in range(n):
                        page.click(f"button.play[data-slot='{k}']")
                        page.wait_for_selector(f".status[data-slot='{k}'].ok")
                    # what the browser decoded: sound on both audio-mismatch videos, none in the muted pairs
                    sound = page.eval_on_selector_all("video[data-slot]",
                                                      "vs => vs.map(v => [v.muted, v.webkitAudioDecodedByteCount])")
                    if spec["block"] == "realism":
                        assert all(muted and decoded == 0 for muted, decoded in sound), sound
                    else:
                        assert all(not muted and decoded > 0 for muted, decoded in sound), sound
                    a, b = by_file[spec["a"]], by_file[spec["b"]]
                    if spec["block"] == "align":
                        assert a.segment == b.segment and b.audio_segment != a.segment and a.condition == b.condition
                    # own speech preferred (clearly) except on every third alignment page: the other one
                    own = spec["position_a"]
                    other = "right" if own == "left" else "left"
                    choice = (own if len(given["align"]) % 3 else other) + "_strong" if spec["block"] == "align" \
                        else ("left" if len(given["realism"]) % 2 == 0 else "equal")
                    given[spec["block"]].append("a" if choice.startswith(own) else "tie" if choice == "equal" else "b")
                    qid = study.page(spec["block"]).cfg["questions"][0]["id"]
                    page.check(f"input[name='q-{qid}'][value='{choice}']")
                page.wait_for_selector("#next:not([disabled])")
                with page.expect_navigation():
                    page.click("#next")
            assert page.locator("#completion-code").text_content() == "DONE1234"
            browser.close()
    finally:
        server.stop()

    out = tmp_path / "results.csv"
    _cli("study", "export", tmp_path / "study.yaml", "--db", db, "-o", out)
    rows = list(csv.DictReader(out.open()))
    align = [r for r in rows if r["question"] == "alignment"]
    realism = [r for r in rows if r["question"] == "realism"]
    assert [r["answer"] for r in align] == given["align"] and len(align) == 4
    assert [r["answer"] for r in realism] == given["realism"] and len(realism) == 2
    speakers = {"s1": "anna", "s2": "anna", "s3": "ben", "s4": "ben"}
    for r in align:
        assert r["condition_b"] == r["condition_a"] + ":audio_mismatched"
        assert r["audio_a"] == r["segment"] and r["audio_b"] != r["audio_a"]
        assert speakers[r["audio_b"]] == speakers[r["audio_a"]]
        assert r["playback_implausible"] == "0", r["playback_reason"]
    assert all(r["audio_a"] == r["audio_b"] == "" for r in realism)
    assert {r["condition_a"] for r in realism} | {r["condition_b"] for r in realism} <= set(CONDITIONS)

    report = _cli("analyze", out, "-o", tmp_path / "analysis", "--no-figures", "--bootstrap", "20")
    assert "Report:" in report
    table = pd.read_csv(tmp_path / "analysis" / "audio_mismatch.csv", keep_default_na=False)
    for system in CONDITIONS:
        mine = [r["answer"] for r in align if r["condition_a"] == system]
        row = table[table["condition"] == system].iloc[0]
        assert (row["n_matched"], row["n_mismatched"], row["n_tie"], row["n"]) == \
            (mine.count("a"), mine.count("b"), mine.count("tie"), len(mine))
    assert sorted(table["rank"]) in ([1, 2], [1, 1])
    pairwise = pd.read_csv(tmp_path / "analysis" / "pairwise.csv", keep_default_na=False)
    real = pairwise[pairwise["question"] == "realism"]
    assert int((real["n_a"] + real["n_b"] + real["n_tie"]).sum()) == 2
    assert int(real["n_tie"].sum()) == given["realism"].count("tie")
    elo = pd.read_csv(tmp_path / "analysis" / "elo.csv", keep_default_na=False)
    assert not elo["condition"].str.contains("audio_mismatched").any()
