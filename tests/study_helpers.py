"""Shared fixtures for the study-app tests: a small study with real MP4 stimuli."""
from __future__ import annotations

import pathlib

from study_app.context import store_of, study_of

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
  - type: headphone_check
    id: headphones
    trials: 2
    pass: 2
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
    reasons_required: true
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


def make_study(folder, sessions: int = 6, seconds: float = 1.0, yaml_text: str | None = None,
               name: str = "study.yaml"):
    """Write stimuli + study.yaml + plans into ``folder``; returns the study path."""
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    from study_app.samples import make_sample_stimuli

    folder = pathlib.Path(folder)
    stim = folder / "stim"
    if not (stim / "manifest.csv").exists():
        make_sample_stimuli(stim, CONDITIONS, SEGMENTS, mismatched=True, attention=ATTENTION,
                            seconds=seconds)
    path = folder / name
    path.write_text(yaml_text or STUDY_YAML.format(sessions=sessions))
    study = load_study(path)
    write_plans(build_plans(study), default_plans_path(study))
    return path


# ------------------------------------------------------------------ driving the app like a browser

import json as _json
import re as _re
import secrets as _secrets

from study_app.definition import PAIRWISE_ANSWERS
from study_app.headphones import correct_choice

PAGE_DATA_RE = _re.compile(r'<script id="page-data" type="application/json">(.*?)</script>', _re.S)
CSRF_RE = _re.compile(r'name="csrf_token" id="csrf_token" value="([^"]+)"')


PROLIFIC_STUDY = "5e0000000000000000000001"
_HEX24 = _re.compile(r"^[0-9a-f]{24}$")


def valid_pid(name: str) -> str:
    """A well-formed Prolific id (24 hex characters) for a test participant name (the name itself when it
    is one already; short names stay readable: their bytes in hex, padded with zeros)."""
    if _HEX24.match(name):
        return name
    if len(name) <= 12:
        return name.encode().hex().ljust(24, "0")
    import hashlib
    return hashlib.sha256(name.encode()).hexdigest()[:24]


def prolific_url(pid, study_id="gesture-test"):
    pid = valid_pid(pid)
    return f"/start/{study_id}?PROLIFIC_PID={pid}&STUDY_ID={PROLIFIC_STUDY}&SESSION_ID=se{pid}"


class Participant:
    """A participant driving the Flask test client; records every answer it sent."""

    def __init__(self, client, pid, study_id="gesture-test"):
        self.client, self.pid, self.sid, self.study_id = client, valid_pid(pid), None, study_id
        self.responses = []          # every response body seen (for leak checks)
        self.urls = []
        self.sent = []               # (page index, answer) acknowledged by the server

    def get(self, url, **kw):
        r = self.client.get(url, **kw)
        self.urls.append(url)
        self.responses.append(r)
        return r

    def post(self, url, body, csrf=None):
        headers = {"X-CSRFToken": csrf} if csrf else {}
        r = self.client.post(url, json=body, headers=headers)
        self.urls.append(url)
        self.responses.append(r)
        return r

    def enter(self):
        r = self.get(prolific_url(self.pid, self.study_id))
        if r.status_code == 302:
            self.sid = r.headers["Location"].split("/s/")[1].strip("/")
        return r

    def consent(self):
        """Answer the first page (the consent page): the session starts and reserves its plan."""
        _, data, csrf = self.page()
        return self.submit(data, csrf, {"agree": True, "website": ""})

    def page(self):
        r = self.get(f"/s/{self.sid}/")
        html = r.get_data(as_text=True)
        m = PAGE_DATA_RE.search(html)
        data = _json.loads(m.group(1)) if m else None
        csrf = CSRF_RE.search(html)
        return r, data, csrf.group(1) if csrf else None

    def submit(self, data, csrf, answer, token=None, events=None, played=True):
        if events is None:
            events = [{"id": _secrets.token_hex(8), "kind": "ended", "slot": k, "t": 1.0, "ms": 1}
                      for k in range(len(data["videos"]))] if played else []
        body = {"token": token or _secrets.token_hex(10), "answer": answer, "events": events}
        r = self.post(data["answer_url"], body, csrf)
        if r.status_code == 200 and r.get_json()["status"] == "stored":
            self.sent.append((data["index"], answer))
        return r


def plan_pages(app, sid):
    store = store_of(app)
    return store.load(sid)[1]


def make_answer(study, spec, rng, pass_check=True):
    """An answer for plan page ``spec``; attention checks passed or failed on purpose."""
    t = spec["type"]
    if t == "consent":
        return {"agree": True, "website": ""}
    if t == "instructions":
        return {}
    if t == "questionnaire":
        return {"age": int(rng.integers(18, 80)), "gender": "other", "comments": "fine"}
    if t == "headphone_check":      # a participant on headphones (screening is tested on its own)
        return {"choices": [correct_choice(o) for o in spec["trials"]]}
    block = study.page(spec["block"]).cfg
    by_file = study.manifest.by_file()
    if t == "pairwise":
        opts = PAIRWISE_ANSWERS[block["levels"]]
        choices = {}
        for q in block["questions"]:
            c = opts[int(rng.integers(len(opts)))]
            if spec.get("check"):
                exp = by_file[spec["a"]].expected
                side = {"this": spec["position_a"], "equal": "equal"}.get(exp, exp)
                if not pass_check:
                    side = "right" if side == "left" else "left"
                c = side if block["levels"] == 3 or side == "equal" else side + "_strong"
            choices[q["id"]] = c
        return {"choices": choices, "reasons": [r["id"] for r in block["reasons"][:1]]}
    if t == "mushra":
        ratings = [int(v) for v in rng.integers(0, 101, size=len(spec["slots"]))]
        if "check_slot" in spec:
            exp = by_file[spec["slots"][spec["check_slot"]]].expected
            target = int(exp) if exp.isdigit() else 70  # "good" band is 60..80
            ratings[spec["check_slot"]] = target if pass_check else (target + 40) % 101
        return {"ratings": ratings}
    return {"ratings": {s["id"]: int(rng.integers(1, block["points"] + 1)) for s in block["statements"]}}


def run_participant(app, client, pid, rng, fail_checks=0, stop_after=None):
    """Go through a whole session; fails the first ``fail_checks`` attention checks."""
    study = study_of(app)
    p = Participant(client, pid)
    r = p.enter()
    assert r.status_code == 302, r.get_data(as_text=True)
    failed = 0
    while True:
        r, data, csrf = p.page()
        if data is None:
            return p, r
        pages = plan_pages(app, p.sid)      # the plan is reserved with the first answer
        spec = pages[data["index"]]
        ok = True
        if spec.get("check") and failed < fail_checks:
            ok = False
            failed += 1
        resp = p.submit(data, csrf, make_answer(study, spec, rng, pass_check=ok))
        assert resp.status_code == 200, resp.get_data(as_text=True)
        if stop_after is not None and len(p.sent) >= stop_after:
            return p, resp


def expected_rows(app, participants):
    """What the export must contain, computed from what the clients sent and their plans."""
    study = study_of(app)
    by_file = study.manifest.by_file()
    cond = lambda s: (s.condition or "attention_check") + (":mismatched" if s.mismatched else "")  # noqa: E731
    out = set()
    for p in participants:
        pages = plan_pages(app, p.sid)
        for index, answer in p.sent:
            spec = pages[index]
            if spec["type"] == "pairwise":
                block = study.page(spec["block"]).cfg
                for q in block["questions"]:
                    side, _, strength = answer["choices"][q["id"]].partition("_")
                    ab = "tie" if side == "equal" else ("a" if side == spec["position_a"] else "b")
                    out.add((p.pid, spec["page"], q["id"], "", cond(by_file[spec["a"]]),
                             cond(by_file[spec["b"]]), ab, strength))
            elif spec["type"] == "mushra":
                block = study.page(spec["block"]).cfg
                for k, f in enumerate(spec["slots"]):
                    out.add((p.pid, spec["page"], block["question"]["id"], cond(by_file[f]), "", "",
                             str(answer["ratings"][k]), ""))
            elif spec["type"] == "likert":
                for sid, v in answer["ratings"].items():
                    out.add((p.pid, spec["page"], sid, cond(by_file[spec["stimulus"]]), "", "", str(v), ""))
    return out


def as_keys(rows):
    return [(r["participant"], r["page"], r["question"], r["condition"], r["condition_a"],
             r["condition_b"], r["answer"], r["strength"]) for r in rows]
