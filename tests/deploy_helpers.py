"""A small study and an HTTP participant (requests) for the tests that run the real nginx and gunicorn."""
from __future__ import annotations

import json
import pathlib
import re

import requests

from study_app.definition import load_study
from study_app.design import build_plans, default_plans_path, write_plans
from study_app.samples import make_sample_stimuli
from study_app.storage import init_db, make_engine

SECRET = "deploy-secret-key-0123456789"
ADMIN = "deploy-admin-token-0123456789"
PAGE_DATA_RE = re.compile(r'<script id="page-data" type="application/json">(.*?)</script>', re.S)
CSRF_RE = re.compile(r'name="csrf_token" id="csrf_token" value="([^"]+)"')
STUDY = """\
id: deploy-test
title: Deployment test
stimuli: stim/manifest.csv
platform: prolific
completion_code: DEPLOYDONE
sessions: {sessions}
reservation_minutes: 100
new_sessions_per_address: 0
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


def make_study(folder: pathlib.Path, db_url: str, sessions: int = 20, pad_bytes: int = 0) -> pathlib.Path:
    """Stimuli, definition, plans and database of the test study; ``pad_bytes`` makes every clip that
    much larger (an MP4 ``free`` box at the end, which players skip)."""
    manifest = make_sample_stimuli(folder / "stim", ["SYSA", "SYSB", "SYSC"], ["seg01", "seg02", "seg03"],
                                   seconds=0.5)
    if pad_bytes:
        for clip in manifest.parent.glob("*.mp4"):
            with open(clip, "ab") as fh:
                fh.write((pad_bytes + 8).to_bytes(4, "big") + b"free" + bytes(pad_bytes))
    study = folder / "study.yaml"
    study.write_text(STUDY.format(sessions=sessions))
    st = load_study(study)
    plans = build_plans(st)
    write_plans(plans, default_plans_path(st))
    init_db(make_engine(db_url), st, plans)
    return study


def app_env(study: pathlib.Path, db_url: str, **extra: str) -> dict[str, str]:
    return {"EVALSUITE_STUDY": str(study), "EVALSUITE_DATABASE_URL": db_url, "EVALSUITE_SECRET_KEY": SECRET,
            "EVALSUITE_ADMIN_TOKEN": ADMIN, "EVALSUITE_TRUSTED_PROXIES": "1", **extra}


class WebParticipant:
    """A participant's browser over HTTP: its own cookies, the page's data and CSRF token."""

    def __init__(self, base: str, pid: str):
        self.base, self.pid, self.http, self.sid = base, pid, requests.Session(), None

    def enter(self, timeout: float = 30) -> requests.Response:
        r = self.http.get(f"{self.base}/start/deploy-test?PROLIFIC_PID={self.pid}&STUDY_ID={'5e' * 12}"
                          f"&SESSION_ID=s{self.pid}", allow_redirects=False, timeout=timeout)
        assert r.status_code == 302, r.status_code
        self.sid = r.headers["Location"].split("/s/")[1].strip("/")
        return r

    def page(self) -> tuple[str, dict | None, str | None]:
        r = self.http.get(f"{self.base}/s/{self.sid}/", timeout=30)
        assert r.status_code == 200, r.status_code
        m, c = PAGE_DATA_RE.search(r.text), CSRF_RE.search(r.text)
        return r.text, json.loads(m.group(1)) if m else None, c.group(1) if c else None

    def video(self, url: str, first: int | None = None, last: int | None = None) -> requests.Response:
        headers = {} if first is None else {"Range": f"bytes={first}-{'' if last is None else last}"}
        return self.http.get(self.base + url, headers=headers, timeout=60)

    def answer(self, data: dict, csrf: str, answer: dict) -> requests.Response:
        events = [{"id": f"ev{self.pid[:8]}-{data['index']}-{s}-{k}", "kind": k, "slot": s, "t": 0.0, "ms": 1}
                  for s in range(len(data["videos"])) for k in ("play", "ended")]     # the player's log
        r = self.http.post(self.base + data["answer_url"], json={"token": f"t{self.pid}{data['index']}",
                           "answer": answer, "events": events}, headers={"X-CSRFToken": csrf}, timeout=30)
        assert r.status_code == 200, (r.status_code, r.text[:300])
        return r

    def consent(self) -> None:
        _, data, csrf = self.page()
        assert data is not None and csrf is not None
        self.answer(data, csrf, {"agree": True, "website": ""})


def admin_get(base: str, path: str):
    r = requests.get(base + path, headers={"Authorization": f"Bearer {ADMIN}"}, timeout=60)
    assert r.status_code == 200, r.status_code
    return r
