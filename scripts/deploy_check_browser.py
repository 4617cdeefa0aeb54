"""The host side of scripts/deploy-check: the sample study, one participant in Chromium, the export's check.

    python scripts/deploy_check_browser.py make-study FOLDER
    python scripts/deploy_check_browser.py participant BASE_URL OUT.json
    python scripts/deploy_check_browser.py check-export PARTICIPANT.json RESULTS.csv RAW.json
"""
from __future__ import annotations

import csv
import json
import pathlib
import shutil

import click

STUDY_ID = "deploy-check"
CODE = "DEPLOYCHECK1"
STUDY = f"""\
id: {STUDY_ID}
title: Deployment check
stimuli: stim/manifest.csv
platform: prolific
completion_code: {CODE}
sessions: 4
pages:
  - {{type: consent, id: consent, text: Consent text.}}
  - type: pairwise
    id: hl
    conditions: [SYSA, SYSB, SYSC]
    questions: [{{id: human_likeness, text: "Which one is more human-like?"}}]
    pages: 2
    muted: true
  - {{type: finish, id: finish, text: Thanks.}}
"""
PID, PROLIFIC_STUDY = "5dc0" * 6, "5e" * 12
ARGS = ["--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-dev-shm-usage",
        "--autoplay-policy=no-user-gesture-required"]


@click.group()
def main():
    """Host-side steps of scripts/deploy-check."""


@main.command("make-study")
@click.argument("folder", type=click.Path(file_okay=False, path_type=pathlib.Path))
def make_study(folder: pathlib.Path) -> None:
    """Write the sample study (study.yaml, stim/ of placeholder clips) into FOLDER; plans are the recipe's job."""
    from study_app.samples import make_sample_stimuli

    folder.mkdir(parents=True, exist_ok=True)
    make_sample_stimuli(folder / "stim", ["SYSA", "SYSB", "SYSC"], ["seg01", "seg02", "seg03"], seconds=1.0)
    (folder / "study.yaml").write_text(STUDY)
    click.echo(f"sample study -> {folder}")


@main.command()
@click.argument("base_url")
@click.argument("out", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("--timeout-ms", default=30000, show_default=True, help="Playwright's timeout for each step.")
def participant(base_url: str, out: pathlib.Path, timeout_ms: int) -> None:
    """Complete the study at BASE_URL (nginx) in Chromium as one Prolific participant; write what it did."""
    from playwright.sync_api import sync_playwright

    chromium = next(p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p)
    answers, videos, sid = [], 0, None
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=ARGS, headless=True)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.set_default_timeout(timeout_ms)
        page.goto(f"{base_url}/start/{STUDY_ID}?PROLIFIC_PID={PID}&STUDY_ID={PROLIFIC_STUDY}&SESSION_ID=se{PID}")
        while page.locator("#page-data").count():
            sid = page.url.split("/s/")[1].split("/")[0]
            data = json.loads(page.locator("#page-data").text_content() or "{}")
            if data["type"] == "consent":
                page.check("#agree")
            elif data["type"] == "pairwise":
                slots = page.locator("video[data-slot]").count()
                for k in range(slots):
                    page.click(f"button.play[data-slot='{k}']")
                    page.wait_for_selector(f".status[data-slot='{k}'].ok")
                videos += slots
                choice = ("left", "right")[data["index"] % 2]
                page.check(f"input[name='q-human_likeness'][value='{choice}']")
                answers.append({"trial": data["index"], "choice": choice})
            page.wait_for_selector("#next:not([disabled])")
            with page.expect_navigation(), page.expect_response(lambda r: "/answer/" in r.url) as resp:
                page.click("#next")
            if resp.value.status != 200:
                raise click.ClickException(f"answer to page {data['index']} refused: {resp.value.status}")
        code = page.locator("#completion-code").text_content() if page.locator("#completion-code").count() else None
        browser.close()
    if code != CODE or not answers:
        raise click.ClickException(f"expected the completion code {CODE} after the pairwise pages, got {code!r}")
    out.write_text(json.dumps({"session": sid, "code": code, "videos": videos, "answers": answers}))
    click.echo(f"session {sid}: code {code}, {videos} videos played, {len(answers)} answers")


@main.command("check-export")
@click.argument("done", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.argument("results", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.argument("raw", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
def check_export(done: pathlib.Path, results: pathlib.Path, raw: pathlib.Path) -> None:
    """The export (RESULTS.csv, RAW.json) holds every answer of DONE (the participant's record), each page's
    videos judged watched (every byte sent by nginx)."""
    did = json.loads(done.read_text())
    with open(results, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["session"] == did["session"]]
    got = {int(r["trial"]): r for r in rows if r["question"] == "human_likeness"}
    problems = []
    for a in did["answers"]:
        row = got.get(a["trial"])
        if row is None:
            problems.append(f"trial {a['trial']}: no row in {results.name}")
            continue
        expected = "a" if a["choice"] == row["position_a"] else "b"
        if (row["answer"], row["session_status"], row["participant"]) != (expected, "finished", PID):
            problems.append(f"trial {a['trial']}: answer {row['answer']!r} ({row['session_status']}, "
                            f"{row['participant']}), expected {expected!r} (finished, {PID})")
        if row["playback_implausible"] != "0":
            problems.append(f"trial {a['trial']}: playback {row['playback_implausible']!r} {row['playback_reason']}")
    if len(got) != len(did["answers"]):
        problems.append(f"{len(got)} rows for {len(did['answers'])} answers")
    if did["session"] not in raw.read_text():
        problems.append(f"session {did['session']} missing from {raw.name}")
    if problems:
        raise click.ClickException("; ".join(problems))
    click.echo(f"export holds the {len(got)} answers of session {did['session']}, every video watched")


if __name__ == "__main__":
    main()
