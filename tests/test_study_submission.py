"""The answer POST body (study_app.submission): its fields, token and response time, each page kind's
answer, the events and the playback they must show, and the window width."""
from __future__ import annotations

import numpy as np
import pytest
import study_helpers as h
from study_fixtures import make_app, walk_to

from study_app.context import study_of
from study_app.payload import PayloadError
from study_app.submission import AnswerBody, parse_answer_body


def test_videos_must_be_played_before_answering(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pplay0001")
    p.enter()
    rng = np.random.default_rng(0)
    data, csrf, spec = walk_to(app, p, "pairwise", rng)              # the first video page
    answer = h.make_answer(study_of(app), spec, rng)
    r = p.submit(data, csrf, answer, played=False)
    assert r.status_code == 422
    assert "play every video to the end" in r.get_json()["error"]
    only_one = [{"id": "evt-only-one", "kind": "ended", "slot": 0, "t": 1.0, "ms": 1}]
    assert p.submit(data, csrf, answer, events=only_one).status_code == 422
    # the second video's end arrives through the periodic event log: now the answer is accepted
    # (a refused answer stores nothing, not even its events: the browser sends them again)
    logged = [{"id": "evt-first01", "kind": "ended", "slot": 0}, {"id": "evt-second1", "kind": "ended", "slot": 1}]
    assert p.post(data["events_url"], {"events": logged}, csrf).status_code == 200
    assert p.submit(data, csrf, answer, events=[]).status_code == 200


BAD_PAYLOADS = [
    ("not json", None, "expected a JSON object"),
    ("extra field", {"token": "tok-000001", "answer": {}, "admin": 1}, "unexpected field"),
    ("no token", {"answer": {}}, "token"),
    ("short token", {"token": "abc", "answer": {}}, "token"),
    ("token chars", {"token": "tok/../../x", "answer": {}}, "token"),
    ("answer not object", {"token": "tok-000001", "answer": [1]}, "expected an object"),
    ("rt negative", {"token": "tok-000001", "answer": {}, "client_rt_ms": -5}, "client_rt_ms"),
    ("events not list", {"token": "tok-000001", "answer": {"agree": True}, "events": "x"}, "events"),
    ("event kind", {"token": "tok-000001", "answer": {"agree": True}, "events": [{"id": "evt-000001", "kind": "hack"}]}, "kind"),
    ("event slot", {"token": "tok-000001", "answer": {"agree": True}, "events": [{"id": "evt-000001", "kind": "play", "slot": 7}]}, "slot"),
]


@pytest.mark.parametrize("desc,body,fragment", BAD_PAYLOADS, ids=[b[0] for b in BAD_PAYLOADS])
def test_answer_payloads_are_validated(study_dir, sqlite_url, desc, body, fragment):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pvalid001")
    p.enter()
    _, data, csrf = p.page()
    if body is None:
        r = p.client.post(data["answer_url"], data="x", content_type="application/json",
                          headers={"X-CSRFToken": csrf})
    else:
        r = p.post(data["answer_url"], body, csrf)
    assert r.status_code == 422
    assert fragment in r.get_json()["error"]


@pytest.mark.parametrize("page_type,answer,fragment", [
    ("consent", {"agree": "yes"}, "must agree"),      # agree: false is "I do not agree"
    ("consent", {"agree": True, "extra": 1}, "unexpected field"),
    ("questionnaire", {"age": 12, "gender": "male"}, "answer.age: expected a number in 18..99"),
    ("questionnaire", {"age": "old", "gender": "male"}, "answer.age: expected a number"),
    ("questionnaire", {"age": 30, "gender": "robot"}, "answer.gender: expected one of the options"),
    ("questionnaire", {"gender": "male"}, "answer.age: this question needs an answer"),
    ("questionnaire", {"age": 30, "gender": "male", "comments": "x" * 1001}, "at most 1000"),
    ("pairwise", {"choices": {"human_likeness": "up"}}, "expected one of left, equal, right"),
    ("pairwise", {"choices": {}}, "answer.choices.human_likeness"),
    ("pairwise", {"choices": {"human_likeness": "left", "other": "left"}}, "unexpected field"),
    ("pairwise", {"choices": {"human_likeness": "left"}, "reasons": ["bogus"]}, "reason ids"),
    ("pairwise", {"choices": {"human_likeness": "right"}, "reasons": []}, "at least one reason"),
    ("pairwise", {"choices": {"human_likeness": "left"}}, "at least one reason"),
    ("mushra", {"ratings": [1, 2]}, "expected a list of 3 ratings"),
    ("mushra", {"ratings": [1, 2, 101]}, "answer.ratings[2]: expected an integer in 0..100"),
    ("mushra", {"ratings": [1, 2, True]}, "answer.ratings[2]"),
    ("likert", {"ratings": {"natural": 6, "fits": 1}}, "answer.ratings.natural: expected an integer in 1..5"),
    ("likert", {"ratings": {"natural": 2}}, "answer.ratings.fits"),
])
def test_answers_are_validated_per_page_type(study_dir, sqlite_url, page_type, answer, fragment):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "ptype0001")
    p.enter()
    data, csrf, spec = walk_to(app, p, page_type, np.random.default_rng(0))
    r = p.submit(data, csrf, answer)
    assert r.status_code == 422 and fragment in r.get_json()["error"], r.get_json()
    assert p.page()[1]["index"] == data["index"]          # nothing was stored


def test_required_reasons_are_not_asked_for_an_equal_judgement(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    assert study_of(app).page("hl").cfg["reasons_required"]
    p = h.Participant(app.test_client(), "preason01")
    p.enter()
    data, csrf, spec = walk_to(app, p, "pairwise", np.random.default_rng(0))
    assert spec["block"] == "hl"
    assert data["reasons_required"] is True
    r = p.submit(data, csrf, {"choices": {"human_likeness": "equal"}, "reasons": []})
    assert r.status_code == 200, r.get_json()
    assert p.page()[1]["index"] == data["index"] + 1


def test_consent_from_a_too_narrow_window_is_refused(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pnarrow01")
    p.enter()
    _, data, csrf = p.page()
    body = {"token": "tok-narrow-01", "answer": {"agree": True, "website": ""}, "width": 640}
    r = p.post(data["answer_url"], body, csrf)
    assert r.status_code == 422
    assert "at least 800 pixels" in r.get_json()["error"]
    body["width"], body["token"] = 1280, "tok-narrow-02"
    assert p.post(data["answer_url"], body, csrf).status_code == 200


def test_the_answer_body_is_checked_in_one_place():
    body = parse_answer_body({"token": "tok-000001", "answer": {"agree": True}, "events": [],
                              "client_rt_ms": 12, "width": 1280})
    assert body == AnswerBody(token="tok-000001", answer={"agree": True}, events=[], client_rt_ms=12,
                              fields={"width": 1280})
    assert parse_answer_body({"token": "tok-000001"}) == AnswerBody(token="tok-000001")
    for bad, message in (({"admin": 1}, "unexpected field 'admin'"),          # before the missing token
                         ({"answer": {}}, "token: expected 8-64 characters"),
                         ({"token": "tok-000001", "client_rt_ms": True}, "client_rt_ms: expected a non-negative"),
                         ({"token": "tok-000001", "client_rt_ms": 10**9 + 1}, "client_rt_ms: expected")):
        with pytest.raises(PayloadError, match=message):
            parse_answer_body(bad)
