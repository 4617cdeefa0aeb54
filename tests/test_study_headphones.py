"""Headphone screening page (Woods et al. 2017): the sounds, the plans, scoring and what a
failed screening does to the session."""
from __future__ import annotations

import csv
import hashlib
import io
import json
import random
import time
import wave
from collections import Counter

import numpy as np
import pytest
import study_helpers as h

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.headphones import (
    FREQUENCY,
    GAP_SECONDS,
    LEVEL_JITTER_DB,
    ORDERS,
    RATE,
    TONE_SECONDS,
    TRIAL_SECONDS,
    correct_choice,
    trial_orders,
    trial_samples,
    trial_wav,
)
from study_app.storage import ParticipantSession, Plan

# ------------------------------------------------------------------------------ the sounds

def _tones(order):
    """The three tones of a trial, cut at their known places: list of (n, 2) arrays."""
    x = trial_samples(order)
    n, gap = int(RATE * TONE_SECONDS), int(RATE * GAP_SECONDS)
    assert len(x) == 3 * n + 2 * gap
    return [x[k * (n + gap): k * (n + gap) + n] for k in range(3)]


@pytest.mark.parametrize("order", range(len(ORDERS)))
def test_each_trial_has_a_plain_a_6db_quieter_and_an_antiphase_tone(order):
    tones = _tones(order)
    rms = [np.sqrt(np.mean(t ** 2)) for t in tones]
    kinds = ORDERS[order]
    plain, quiet, anti = (tones[kinds.index(k)] for k in ("plain", "quiet", "antiphase"))
    p_rms, q_rms, a_rms = (rms[kinds.index(k)] for k in ("plain", "quiet", "antiphase"))
    assert 20 * np.log10(q_rms / p_rms) == pytest.approx(-6.0, abs=1e-9)
    assert a_rms == pytest.approx(p_rms, rel=1e-12)             # as loud in each ear ...
    np.testing.assert_array_equal(plain[:, 0], plain[:, 1])
    np.testing.assert_array_equal(anti[:, 0], -anti[:, 1])        # ... but in antiphase
    # over loudspeakers the channels add in the air: the antiphase tone cancels and sounds
    # quietest, which is how the test tells loudspeakers from headphones
    mono = [np.sqrt(np.mean(t.sum(axis=1) ** 2)) for t in tones]
    assert int(np.argmin(mono)) == kinds.index("antiphase")
    assert int(np.argmin(rms)) + 1 == correct_choice(order)
    # a 200 Hz tone, silent between tones, within [-1, 1]
    spectrum = np.abs(np.fft.rfft(plain[:, 0]))
    assert np.fft.rfftfreq(len(plain), 1 / RATE)[np.argmax(spectrum)] == pytest.approx(FREQUENCY)
    x = trial_samples(order)
    n = int(RATE * TONE_SECONDS)
    assert not x[n:n + int(RATE * GAP_SECONDS)].any()
    assert np.abs(x).max() <= 0.25 + 1e-12
    # ramps: starts and ends at zero
    assert abs(plain[0, 0]) < 1e-12
    assert abs(plain[-1, 0]) < 1e-3


def test_wav_file_holds_the_samples():
    with wave.open(io.BytesIO(trial_wav(4))) as w:
        assert (w.getnchannels(), w.getsampwidth(), w.getframerate()) == (2, 2, RATE)
        pcm = np.frombuffer(w.readframes(w.getnframes()), "<i2").reshape(-1, 2)
    np.testing.assert_allclose(pcm / 32767, trial_samples(4), atol=0.5 / 32767 + 1e-12)
    with pytest.raises(ValueError, match="0..5"):
        trial_wav(6)


def test_trial_orders_put_the_quiet_tone_everywhere_equally_often():
    orders = trial_orders(12, random.Random(1))
    assert Counter(orders) == {k: 2 for k in range(6)}
    assert Counter(correct_choice(o) for o in orders) == {1: 4, 2: 4, 3: 4}
    assert trial_orders(12, random.Random(1)) == orders
    assert trial_orders(12, random.Random(2)) != orders


# ------------------------------------------------------------------------ in the study app

HEADPHONES = "  - type: headphone_check\n    id: headphones\n    trials: 2\n    pass: 2\n"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    f = tmp_path_factory.mktemp("headphones")
    h.make_study(f)
    for name, on_fail in (("end", "end"), ("cont", "continue")):
        text = h.STUDY_YAML.format(sessions=4).replace(
            HEADPHONES, f"  - type: headphone_check\n    id: headphones\n    on_fail: {on_fail}\n"
        ).replace("id: gesture-test", f"id: hp-{name}")
        assert f"on_fail: {on_fail}" in text
        h.make_study(f, yaml_text=text, name=f"{name}.yaml")
    return f


def make_app(folder, tmp_path, name):
    return create_app({"STUDY": str(folder / f"{name}.yaml"), "DATABASE_URL": f"sqlite:///{tmp_path / 'hp.db'}",
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                       "INSTANCE_PATH": str(folder / "inst")})


def walk_to_screening(app, pid, study_id):
    p = h.Participant(app.test_client(), pid, study_id)
    assert p.enter().status_code == 302
    study = study_of(app)
    while True:
        r, data, csrf = p.page()
        pages = h.plan_pages(app, p.sid)     # reserved with the first answer
        if data["type"] == "headphone_check":
            return p, r, data, csrf, pages[data["index"]]
        assert p.submit(data, csrf, h.make_answer(study, pages[data["index"]], np.random.default_rng(0))).status_code == 200


def n_correct_answer(spec, n_correct):
    right = [correct_choice(o) for o in spec["trials"]]
    return [c if k < n_correct else c % 3 + 1 for k, c in enumerate(right)]


def test_defaults_follow_woods_et_al(folder):
    from study_app.definition import load_study
    cfg = load_study(folder / "end.yaml").page("headphones").cfg
    assert (cfg["trials"], cfg["pass"], cfg["on_fail"]) == (6, 5, "end")
    assert cfg["title"] == "Headphone check"
    assert "headphones" in cfg["text"]


def test_page_and_sounds_do_not_give_the_answer_away(folder, tmp_path):
    app = make_app(folder, tmp_path, "end")
    p, r, data, csrf, spec = walk_to_screening(app, "phpleak01", "hp-end")
    html = r.get_data(as_text=True)
    assert len(data["videos"]) == 6
    assert data["play_once"] is True
    assert "trials" not in data
    assert "antiphase" not in html
    assert "plain" not in html
    assert html.count("<audio data-slot=") == 6         # the trials (besides the calibration noise)
    assert "Which tone was the quietest?" in html
    part = p.client.get(data["videos"][0], headers={"Range": "bytes=0-43"})
    assert part.status_code == 206
    assert part.data == trial_wav(spec["trials"][0], spec["sounds"][0])[:44]
    for k, url in enumerate(data["videos"]):
        assert url.endswith(f"/media/{data['index']}/{k}")
        snd = p.client.get(url)
        assert snd.status_code == 200
        assert snd.mimetype == "audio/wav"
        assert snd.data == trial_wav(spec["trials"][k], spec["sounds"][k])
        assert snd.headers["Cache-Control"] == "private, no-store"
    # heard once: a sound whose every byte was sent is refused to the session afterwards
    assert p.client.get(data["videos"][0]).status_code == 410
    assert p.client.get(data["videos"][1], headers={"Range": "bytes=0-43"}).status_code == 410
    assert p.client.get(data["videos"][0][:-1] + "6").status_code == 404


@pytest.mark.parametrize("answer,fragment", [
    ({"choices": [1, 2, 3]}, "expected a list of 6 answers"),
    ({"choices": [1, 2, 3, 1, 2, 4]}, "answer.choices[5]: expected an integer in 1..3"),
    ({"choices": [1, 2, 3, 1, 2, True]}, "answer.choices[5]"),
    ({"choices": [1] * 6, "extra": 1}, "unexpected field 'extra'"),
])
def test_answers_are_validated(folder, tmp_path, answer, fragment):
    app = make_app(folder, tmp_path, "end")
    p, _, data, csrf, _ = walk_to_screening(app, "phpvalid1", "hp-end")
    r = p.submit(data, csrf, answer)
    assert r.status_code == 422 and fragment in r.get_json()["error"], r.get_json()


def test_every_sound_must_be_heard_to_the_end(folder, tmp_path):
    app = make_app(folder, tmp_path, "end")
    p, _, data, csrf, spec = walk_to_screening(app, "phplay001", "hp-end")
    r = p.submit(data, csrf, {"choices": n_correct_answer(spec, 6)}, played=False)
    assert r.status_code == 422
    assert "please play every sound to the end" in r.get_json()["error"]


def test_five_of_six_pass_and_the_study_goes_on(folder, tmp_path):
    app = make_app(folder, tmp_path, "end")
    p, _, data, csrf, spec = walk_to_screening(app, "phpass001", "hp-end")
    assert p.submit(data, csrf, {"choices": n_correct_answer(spec, 5)}).status_code == 200
    _, nxt, _ = p.page()
    assert nxt["index"] == data["index"] + 1
    with store_of(app).Session() as db:
        sess = db.get(ParticipantSession, p.sid)
        assert sess.status == "active"
        assert sess.failed_checks == 0


def test_a_failed_screening_ends_the_session_with_the_failure_code(folder, tmp_path):
    app = make_app(folder, tmp_path, "end")
    p, _, data, csrf, spec = walk_to_screening(app, "phpfail01", "hp-end")
    r = p.submit(data, csrf, {"choices": n_correct_answer(spec, 4)})
    assert r.status_code == 200
    assert r.get_json()["session_status"] == "failed"
    page, nothing, _ = p.page()
    html = page.get_data(as_text=True)
    assert nothing is None
    assert "not listening over" in html
    assert "FAIL5678" in html
    with store_of(app).Session() as db:
        sess = db.get(ParticipantSession, p.sid)
        assert (sess.status, sess.end_reason) == ("failed", "headphone_check")
        assert db.get(Plan, sess.plan_id).status == "free"        # the plan goes to someone else
    # the stored answer says what happened; the admin page lists the participant
    client = app.test_client()
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    raw = json.loads(client.get("/admin/export/raw.json", headers=auth).get_data(as_text=True))
    stored = [a["data"] for a in raw["answers"] if a["page"] == "headphones"]
    assert stored == [{"choices": n_correct_answer(spec, 4), "correct": 4, "passed": False}]
    admin = client.get("/admin/", headers=auth).get_data(as_text=True)
    assert h.valid_pid("phpfail01") in admin
    assert "headphone_check" in admin
    # a second try cannot start over: the same link shows the screened-out code again
    again = h.Participant(app.test_client(), "phpfail01", "hp-end").enter()
    assert again.status_code == 200
    assert 'id="failure-code">FAIL5678<' in again.get_data(as_text=True)
    assert again.headers.get("Location") is None


def test_on_fail_continue_only_records_the_outcome(folder, tmp_path):
    app = make_app(folder, tmp_path, "cont")
    p, _, data, csrf, spec = walk_to_screening(app, "phpcont01", "hp-cont")
    assert p.submit(data, csrf, {"choices": n_correct_answer(spec, 0)}).status_code == 200
    assert p.page()[1]["index"] == data["index"] + 1
    client = app.test_client()
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    raw = json.loads(client.get("/admin/export/raw.json", headers=auth).get_data(as_text=True))
    stored = [a["data"] for a in raw["answers"] if a["page"] == "headphones"]
    assert stored[0]["correct"] == 0
    assert stored[0]["passed"] is False
    # results.csv holds judgements only: no screening rows
    rows = list(csv.DictReader(io.StringIO(client.get("/admin/export/results.csv", headers=auth)
                                           .get_data(as_text=True))))
    assert not any(r["page_type"] == "headphone_check" for r in rows)


# ------------------------------------------------------------ bytes that do not give the answer away

def test_a_seeded_trial_keeps_the_levels_and_the_antiphase_and_is_reproducible():
    for order, seed in ((0, 11), (3, 2**40 + 5), (5, 987654321)):
        x = trial_samples(order, seed)
        n, gap = int(RATE * TONE_SECONDS), int(RATE * GAP_SECONDS)
        tones = [x[k * (n + gap): k * (n + gap) + n] for k in range(3)]
        kinds = ORDERS[order]
        rms = {kind: np.sqrt(np.mean(t ** 2)) for kind, t in zip(kinds, tones)}
        assert 20 * np.log10(rms["quiet"] / rms["plain"]) == pytest.approx(-6.0, abs=0.01)
        assert rms["antiphase"] == pytest.approx(rms["plain"], rel=1e-3)
        anti = tones[kinds.index("antiphase")]
        np.testing.assert_array_equal(anti[:, 0], -anti[:, 1])
        # level jitter of at most LEVEL_JITTER_DB around the unjittered trial's level
        jitter_db = 20 * np.log10(rms["plain"] / np.sqrt(np.mean(_tones(order)[kinds.index("plain")] ** 2)))
        assert abs(jitter_db) <= LEVEL_JITTER_DB + 0.01
        # phases differ from the unseeded trial; the same seed makes the same bytes (range requests)
        assert not np.allclose(x, trial_samples(order))
        assert trial_wav(order, seed) == trial_wav(order, seed)
        assert trial_wav(order, seed) != trial_wav(order, seed + 1)


def test_sizes_headers_and_hashes_of_the_sounds_do_not_reveal_the_answer():
    """Over 120 sessions' plans (720 trials): every file has the same size and header, and no file is sent
    twice, so a lookup table of hashes learnt from half the sessions answers no trial of the other half;
    a guess from size or header is at chance (each answer position a third of the time)."""
    from types import SimpleNamespace

    from study_app.pages.headphone_check import KIND
    page = SimpleNamespace(id="headphones", type="headphone_check", cfg={"trials": 6})
    plan = SimpleNamespace(study=SimpleNamespace(seed=3))
    trials = []
    for session in range(120):
        spec = KIND.plan_pages(page, session, plan)[0]
        assert len(spec["sounds"]) == 6
        for slot, order in enumerate(spec["trials"]):
            body = KIND.media(None, spec, slot).body
            trials.append((hashlib.sha256(body).hexdigest(), len(body), body[:44], correct_choice(order)))
    assert len({size for _, size, _, _ in trials}) == 1
    assert len({head for _, _, head, _ in trials}) == 1
    assert len({digest for digest, _, _, _ in trials}) == len(trials)
    learnt = {digest: answer for digest, _, _, answer in trials[:360]}
    assert sum(digest in learnt for digest, _, _, _ in trials[360:]) == 0
    answers = Counter(answer for _, _, _, answer in trials)
    assert answers == {1: 240, 2: 240, 3: 240}


def test_a_screening_answered_faster_than_a_trial_lasts_is_flagged(folder, tmp_path):
    """The playback judgement of the headphone page (raw JSON): every sound fetched in full, but answered before
    one trial's sound (TRIAL_SECONDS) could have played, is implausible; staying that long is not."""
    app = make_app(folder, tmp_path, "cont")
    judged = {}
    for pid, dwell in (("phphasty1", 0.0), ("phpslow01", TRIAL_SECONDS + 0.2)):
        p, _, data, csrf, spec = walk_to_screening(app, pid, "hp-cont")
        for url in data["videos"]:
            assert p.client.get(url).status_code == 200
        time.sleep(dwell)
        assert p.submit(data, csrf, {"choices": n_correct_answer(spec, 6)}).status_code == 200
        judged[p.sid] = dwell
    raw = json.loads(app.test_client().get("/admin/export/raw.json", headers={"Authorization": f"Bearer {h.ADMIN}"})
                     .get_data(as_text=True))
    pb = {a["session"]: a["playback"] for a in raw["answers"] if a["page"] == "headphones"}
    hasty, slow = (sid for sid, d in sorted(judged.items(), key=lambda kv: kv[1]))
    assert pb[hasty]["implausible"] and pb[hasty]["min_ms"] == int(1000 * TRIAL_SECONDS)
    assert any(f"for {TRIAL_SECONDS:.1f} s of video" in r for r in pb[hasty]["reasons"])
    assert not pb[slow]["implausible"] and pb[slow]["reasons"] == []
