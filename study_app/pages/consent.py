"""``consent``: the information sheet, an agree box and an "I do not agree" exit (the session ends with the
``no_consent`` outcome code, :mod:`study_app.outcomes`); an invisible honeypot field catches bots."""
from __future__ import annotations

from typing import Any

from study_app.pages.base import Outcome, PageKind
from study_app.payload import PayloadError, only_keys


class ConsentKind(PageKind):
    name = "consent"
    keys = ("honeypot", "agree_label", "decline_label")
    script = "pages/consent.js"
    position = "first"

    def load(self, chk: Any, page: dict, where: str, study: Any) -> dict:
        return {"honeypot": chk.get(page, "honeypot", where, bool, default=True),
                "agree_label": chk.get(page, "agree_label", where, str,
                                       default="I have read the information above and agree to take part."),
                "decline_label": chk.get(page, "decline_label", where, str, default="I do not agree")}

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        cfg = study.page(spec["page"]).cfg
        only_keys(answer, ("agree", "website"), "answer")
        if answer.get("agree") is False:
            return {"agree": False}            # "I do not agree": the session ends (no_consent)
        if answer.get("agree") is not True:
            raise PayloadError("answer.agree: you must agree to take part to continue")
        website = answer.get("website", "")
        if not isinstance(website, str) or len(website) > 500:
            raise PayloadError("answer.website: expected a string")
        data = {"agree": True, "honeypot": bool(website.strip()) and cfg["honeypot"]}
        width = fields.get("width")
        if isinstance(width, int) and not isinstance(width, bool):
            if width < study.min_width:
                raise PayloadError(f"please use a browser window at least {study.min_width} pixels wide")
            data["width"] = width
        return data

    def outcome(self, study: Any, spec: dict, data: dict) -> Outcome:
        if data.get("agree") is False:
            return Outcome(end_reason="no_consent")
        return Outcome(honeypot=bool(data.get("honeypot")))


KIND = ConsentKind()
