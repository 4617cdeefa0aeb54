"""Bad input that used to break the study server (issue 11's review): each now gets a precise answer and
stores nothing wrong. Every test failed before its fix (500s, stored NaN, events after the end, a later
page answered "already answered", unlimited admin guessing)."""
from __future__ import annotations

import json
import re

import pytest
import study_helpers as h

from study_app import create_app
from study_app.context import store_of
from study_app.storage import Answer, Event


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hardening")
    h.make_study(folder)
    return folder


@pytest.fixture()
def app(study_dir, tmp_path):
    return create_app({"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": f"sqlite:///{tmp_path / 'h.db'}",
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                       "INSTANCE_PATH": str(tmp_path / "inst")})


def _entered(app, pid="5f3a1c9e8b7d6a5f4e3d2c1f"):
    p = h.Participant(app.test_client(), pid)
    assert p.enter().status_code == 302
    return p


def _post_raw(p, url, raw: bytes, csrf):
    return p.client.post(url, data=raw, headers={"X-CSRFToken": csrf, "Content-Type": "application/json"})


@pytest.mark.parametrize("endpoint", ["answer_url", "events_url", "draft_url"])
def test_deeply_nested_json_is_a_422_not_a_server_error(app, endpoint):
    p = _entered(app)
    _, data, csrf = p.page()
    raw = b'{"answer": ' + b"[" * 50_000 + b"]" * 50_000 + b"}"
    r = _post_raw(p, data[endpoint], raw, csrf)
    assert r.status_code == 422
    assert "nested too deeply" in r.get_json()["error"]


def test_nan_and_infinity_are_refused_and_nothing_is_stored(app):
    p = _entered(app)
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True}).status_code == 200      # consent
    _, data, csrf = p.page()
    raw = json.dumps({"token": "tok-nan-0001", "answer": {"age": float("nan"), "gender": "male",
                                                          "comments": ""}}).encode()
    assert b"NaN" in raw
    r = _post_raw(p, data["answer_url"], raw, csrf)
    assert r.status_code == 422
    assert "NaN" in r.get_json()["error"]
    with store_of(app).Session() as db:
        assert db.query(Answer).filter_by(session_id=p.sid, page_index=data["index"]).count() == 0


def test_a_later_page_is_not_open_yet(app):
    p = _entered(app)
    _, data, csrf = p.page()
    later = data["answer_url"].rsplit("/", 1)[0] + f"/{data['index'] + 2}"
    r = p.post(later, {"token": "tok-later-001", "answer": {}}, csrf)
    assert r.status_code == 409
    assert "not open yet" in r.get_json()["error"]


def _csrf(client) -> str:
    """A CSRF token for this client's session (the admin login form carries one)."""
    m = re.search(r'name="csrf_token" value="([^"]+)"', client.get("/admin/login").get_data(as_text=True))
    assert m is not None
    return m.group(1)


def test_events_after_the_session_ended_are_refused(app):
    rng = __import__("numpy").random.default_rng(0)
    p, _ = h.run_participant(app, app.test_client(), "pdone00001", rng)
    before = _count_events(app, p.sid)
    event = {"id": "ev-after-end-01", "kind": "play", "slot": None, "t": None, "ms": 1, "detail": ""}
    r = p.client.post(f"/s/{p.sid}/events/0", json={"events": [event]}, headers={"X-CSRFToken": _csrf(p.client)})
    assert r.status_code == 409
    assert "ended" in r.get_json()["error"]
    assert _count_events(app, p.sid) == before


def _count_events(app, sid):
    with store_of(app).Session() as db:
        return db.query(Event).filter_by(session_id=sid).count()


def test_admin_token_guessing_is_throttled_per_address(app):
    client = app.test_client()
    for _ in range(10):
        assert client.get("/admin/export/results.csv", headers={"Authorization": "Bearer wrong-token-xxxx"}).status_code == 403
    r = client.get("/admin/export/results.csv", headers={"Authorization": "Bearer wrong-token-xxxx"})
    assert r.status_code == 429
    # the form is throttled for the same address too, with Retry-After
    r = client.post("/admin/login", data={"token": "wrong", "csrf_token": _csrf(client)})
    assert r.status_code == 429
    assert int(r.headers["Retry-After"]) > 0


def test_a_participant_id_alone_does_not_open_someone_elses_session(app):
    victim = _entered(app, "5f3a1c9e8b7d6a5f4e3d2c10")
    # a fresh browser with the victim's Prolific id but another study session id
    attacker = h.Participant(app.test_client(), "5f3a1c9e8b7d6a5f4e3d2c10")
    r = attacker.get("/start/gesture-test?PROLIFIC_PID=5f3a1c9e8b7d6a5f4e3d2c10&STUDY_ID=5e0000000000000000000001"
                     "&SESSION_ID=forged")
    assert r.status_code == 409
    assert "already in progress" in r.get_data(as_text=True)
    assert attacker.client.get(f"/s/{victim.sid}/").status_code == 403
    # the same platform attempt (same SESSION_ID) from another browser resumes, as Prolific's own links do
    same = h.Participant(app.test_client(), "5f3a1c9e8b7d6a5f4e3d2c10")
    assert same.enter().status_code == 302
    assert same.sid == victim.sid


def test_media_responses_carry_nothing_derived_from_the_stimulus_file(app):
    """No file name (Content-Disposition), no modification time (Last-Modified, or an ETag made of mtime and
    size): sorting clips by such headers gave the render order, i.e. the condition. Ranges still work."""
    rng = __import__("numpy").random.default_rng(5)
    study = app.extensions["evalsuite_study"]
    by_file = study.manifest.by_file()
    p = _entered(app, "5f3a1c9e8b7d6a5f4e3d2c12")
    checked = 0
    while True:
        _, data, csrf = p.page()
        if data is None:
            break
        spec = h.plan_pages(app, p.sid)[data["index"]]
        for url in data["videos"]:
            part = p.client.get(url, headers={"Range": "bytes=0-9"})     # first: headphone sounds are sent once
            assert part.status_code == 206
            assert len(part.data) == 10
            r = p.client.get(url)
            assert r.status_code == 200
            assert "Content-Disposition" not in r.headers
            assert "Last-Modified" not in r.headers
            etag = r.headers.get("ETag", "")
            assert all(name not in etag and name not in str(r.headers) for name in by_file)
            assert "-" not in etag.strip('"')          # werkzeug's file ETag is "mtime-size-hash"
            checked += 1
        if p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code != 200:
            break
    assert checked >= 5


@pytest.mark.parametrize("kind", ["deep-yaml", "deep-json", "laughs", "nan-yaml", "nan-json", "mixed-keys",
                                  "nul-stimuli", "long-stimuli"])
def test_hostile_definitions_give_one_precise_error(tmp_path, kind):
    from study_app.definition import load_study
    from study_app.errors import StudyDefinitionError

    base = h.STUDY_YAML.format(sessions=2)
    name, text = "s.yaml", base
    if kind == "deep-yaml":
        text = base + "extra: " + "[" * 3000 + "]" * 3000 + "\n"
    elif kind == "deep-json":
        name, text = "s.json", '{"id": "x", "pages": ' + "[" * 3000 + "]" * 3000 + "}"
    elif kind == "laughs":
        lol = ["a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
        for i in range(1, 9):
            prev = chr(ord("a") + i - 1)
            lol.append(f"{chr(ord('a') + i)}: &{chr(ord('a') + i)} [" + ", ".join([f"*{prev}"] * 9) + "]")
        text = "\n".join(lol) + "\n" + base
    elif kind == "nan-yaml":
        text = base.replace("reservation_minutes: 100", "reservation_minutes: .nan")
    elif kind == "nan-json":
        name, text = "s.json", '{"id": "x", "reservation_minutes": NaN, "stimuli": "m.csv", "pages": []}'
    elif kind == "mixed-keys":
        text = base + "1: one\n"
    elif kind == "nul-stimuli":
        text = base.replace("stimuli: stim/manifest.csv", 'stimuli: "stim/\\0manifest.csv"')
    elif kind == "long-stimuli":
        text = base.replace("stimuli: stim/manifest.csv", "stimuli: " + "x" * 5000 + ".csv")
    (tmp_path / name).write_text(text)
    start = __import__("time").perf_counter()
    with pytest.raises(StudyDefinitionError) as err:
        load_study(tmp_path / name)
    assert __import__("time").perf_counter() - start < 5
    message = str(err.value)
    expected = {"deep-yaml": "nested too deeply", "deep-json": "nested too deeply", "laughs": "aliases",
                "nan-yaml": "finite number", "nan-json": "NaN", "mixed-keys": "field names as text",
                "nul-stimuli": "not a usable file name", "long-stimuli": "not a usable file name"}[kind]
    assert expected in message
