"""``instructions``: text only; the answer is empty."""
from __future__ import annotations

from typing import Any

from study_app.pages.base import PageKind
from study_app.payload import only_keys


class InstructionsKind(PageKind):
    name = "instructions"

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        only_keys(answer, (), "answer")
        return {}


KIND = InstructionsKind()
