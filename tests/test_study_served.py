"""The bytes served per media request (study_app.served) and the playback judgement built on them: scripted
clients that fetch 1 byte per video, fake playback events without fetching, or answer before the clips could
have played are flagged on every row with the reason, and `evalsuite analyze` excludes them by default."""
from __future__ import annotations

import csv
import io
import time

import numpy as np
import pandas as pd
import study_helpers as h
from click.testing import CliRunner

from evalsuite.cli import main
from study_app import create_app
from study_app.context import study_of
from study_app.served import coverage


def test_coverage_is_the_union_of_inclusive_ranges():
    assert coverage([]) == 0
    assert coverage([(0, 0)]) == 1
    assert coverage([(0, 99), (50, 149), (200, 209)]) == 160
    assert coverage([(10, 19), (0, 9)]) == 20
    assert coverage([(0, 99), (10, 20)]) == 100


def _walk(app, pid, rng, mode: str, dwell: float = 0.0):
    """A scripted participant that posts 'ended' for every video; ``mode`` says what it fetches:
    'none', 'byte' (1 byte per video by a Range request) or 'full'."""
    study = study_of(app)
    p = h.Participant(app.test_client(), h.valid_pid(f"served{pid:04d}"))
    assert p.enter().status_code == 302
    while True:
        r, data, csrf = p.page()
        if data is None:
            return p, r
        spec = h.plan_pages(app, p.sid)[data["index"]]
        for url in data["videos"]:
            if mode == "byte":
                assert p.client.get(url, headers={"Range": "bytes=0-0"}).status_code == 206
            elif mode == "full":
                assert p.client.get(url).status_code == 200
        if data["videos"] and dwell:
            time.sleep(dwell)
        assert p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code == 200


def test_scripted_clients_are_flagged_on_every_row_and_excluded(tmp_path):
    text = h.STUDY_YAML.format(sessions=4).replace("min_width: 800", "min_width: 800\nplayback_min_fraction: 0.2")
    path = h.make_study(tmp_path, yaml_text=text)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{tmp_path / 'p.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    rng = np.random.default_rng(3)
    byte, _ = _walk(app, 1, rng, "byte", dwell=0.25)      # 1 byte per video, stays long enough
    faker, _ = _walk(app, 2, rng, "none", dwell=0.25)     # playback events only, nothing fetched
    hasty, _ = _walk(app, 3, rng, "full")                 # every byte, but answers at once
    honest, _ = _walk(app, 4, rng, "full", dwell=0.25)    # every byte, and >= 0.2 x the 1 s clips

    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    export = app.test_client().get("/admin/export/results.csv", headers=auth).get_data(as_text=True)
    rows = [r for r in csv.DictReader(io.StringIO(export)) if r["playback_implausible"] != ""]
    by = {s: [r for r in rows if r["session"] == s] for s in (byte.sid, faker.sid, hasty.sid, honest.sid)}
    assert all(by.values())
    assert all(r["playback_implausible"] == "1" for s in (byte.sid, faker.sid, hasty.sid) for r in by[s])
    assert all(r["playback_implausible"] == "0" and r["playback_reason"] == "" for r in by[honest.sid])
    for r in by[byte.sid]:
        assert "unwatched: bytes 1/" in r["playback_reason"]
        assert "playback events inconsistent with served bytes" in r["playback_reason"]
        assert "answered" not in r["playback_reason"]
    assert all("unwatched: slot 0 never fetched" in r["playback_reason"] for r in by[faker.sid])
    for r in by[hasty.sid]:
        assert "unwatched" not in r["playback_reason"]
        assert "s after the page for 1.0 s of video" in r["playback_reason"]

    results = tmp_path / "results.csv"
    results.write_text(export)
    out = tmp_path / "analysis"
    res = CliRunner().invoke(main, ["analyze", str(results), "-o", str(out), "--no-figures", "--bootstrap", "0",
                                    "--no-mushra-screening"])
    assert res.exit_code == 0, res.output
    excl = pd.read_csv(out / "exclusions.csv", keep_default_na=False)
    pb = excl[excl["reason"] == "implausible_playback"]
    assert set(pb["session"]) == {byte.sid, faker.sid, hasty.sid}
    assert "unwatched: bytes 1/" in pb.set_index("session").loc[byte.sid, "detail"]


SHORT_YAML = h.STUDY_YAML.split("  - type: questionnaire")[0] + """\
  - type: pairwise
    id: hl
    conditions: [SYSALPHA, SYSBETA, NATURALGT]
    questions:
      - {{id: human_likeness, text: "Which one moves more like a real person?"}}
    pages: 2
  - type: finish
    id: finish
    text: Thank you.
"""


def test_waiting_less_than_the_clips_at_the_default_fraction_is_flagged(tmp_path):
    """playback_min_fraction left at its default (1.0): a client that fetches every byte and posts 'ended' for
    each video but answers after half the 1 s clips is flagged on every row; one that stays a whole clip is not."""
    path = h.make_study(tmp_path, yaml_text=SHORT_YAML.format(sessions=2))
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{tmp_path / 'p.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    assert study_of(app).playback_min_fraction == 1.0
    rng = np.random.default_rng(5)
    half, _ = _walk(app, 21, rng, "full", dwell=0.5)
    whole, _ = _walk(app, 22, rng, "full", dwell=1.05)
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    export = app.test_client().get("/admin/export/results.csv", headers=auth).get_data(as_text=True)
    rows = list(csv.DictReader(io.StringIO(export)))
    by = {s: [r for r in rows if r["session"] == s] for s in (half.sid, whole.sid)}
    assert len(by[half.sid]) == len(by[whole.sid]) == 2
    for r in by[half.sid]:
        assert r["playback_implausible"] == "1"
        assert "s after the page for 1.0 s of video" in r["playback_reason"]
        assert "unwatched" not in r["playback_reason"]
    assert all(r["playback_implausible"] == "0" and r["playback_reason"] == "" for r in by[whole.sid])
