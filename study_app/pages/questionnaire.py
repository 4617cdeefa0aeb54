"""``questionnaire``: number, choice and free-text questions (demographics and the like)."""
from __future__ import annotations

from typing import Any

from study_app.pages.base import PageKind
from study_app.payload import PayloadError, only_keys
from study_app.schema import describe

QUESTION_TYPES = ("number", "choice", "text")


class QuestionnaireKind(PageKind):
    name = "questionnaire"
    keys = ("questions",)
    script = "pages/questionnaire.js"

    def load(self, chk: Any, page: dict, where: str, study: Any) -> dict:
        qs = chk.get(page, "questions", where, list, required=True, expected="a list of questions")
        if not qs:
            chk.fail(f"{where}.questions", "expected at least one question")
        out, ids = [], set()
        for j, q in enumerate(qs):
            qw = f"{where}.questions[{j}]"
            if not isinstance(q, dict):
                chk.fail(qw, f"expected a mapping with id, type and text, got {describe(q)}")
            chk.unknown_keys(q, ("id", "type", "text", "required", "min", "max", "options", "max_length"), qw)
            qid = chk.ident(q, "id", qw)
            if qid in ids:
                chk.fail(f"{qw}.id", f"duplicate question id {qid!r}")
            ids.add(qid)
            qtype = chk.get(q, "type", qw, str, required=True, expected=f"one of {', '.join(QUESTION_TYPES)}")
            if qtype not in QUESTION_TYPES:
                chk.fail(f"{qw}.type", f"expected one of {', '.join(QUESTION_TYPES)}, got {qtype!r}")
            item = {"id": qid, "type": qtype, "text": chk.get(q, "text", qw, str, required=True),
                    "required": chk.get(q, "required", qw, bool, default=True)}
            if qtype == "number":
                item["min"] = chk.get(q, "min", qw, (int, float), default=None)
                item["max"] = chk.get(q, "max", qw, (int, float), default=None)
                if item["min"] is not None and item["max"] is not None and item["min"] > item["max"]:
                    chk.fail(f"{qw}.min", f"expected min <= max, got {item['min']} > {item['max']}")
            elif qtype == "choice":
                item["options"] = chk.str_list(q, "options", qw, required=True, min_len=2)
            else:
                item["max_length"] = chk.int_range(q, "max_length", qw, 1, 10000, default=1000)
            out.append(item)
        return {"questions": out}

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        questions = study.page(spec["page"]).cfg["questions"]
        only_keys(answer, [q["id"] for q in questions], "answer")
        return {"responses": {q["id"]: _response(q, answer.get(q["id"])) for q in questions}}


def _response(q: dict, v: Any) -> Any:
    what = f"answer.{q['id']}"
    if v is None or v == "":
        if q["required"]:
            raise PayloadError(f"{what}: this question needs an answer")
        return None
    if q["type"] == "number":
        if isinstance(v, str):
            try:
                v = float(v) if "." in v else int(v)
            except ValueError:
                raise PayloadError(f"{what}: expected a number") from None
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise PayloadError(f"{what}: expected a number")
        if (q["min"] is not None and v < q["min"]) or (q["max"] is not None and v > q["max"]):
            raise PayloadError(f"{what}: expected a number in {q['min']}..{q['max']}")
    elif q["type"] == "choice":
        if v not in q["options"]:
            raise PayloadError(f"{what}: expected one of the options")
    elif not isinstance(v, str) or len(v) > q["max_length"]:
        raise PayloadError(f"{what}: expected text of at most {q['max_length']} characters")
    return v


KIND = QuestionnaireKind()
