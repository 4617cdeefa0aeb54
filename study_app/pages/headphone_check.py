"""``headphone_check``: Woods et al. (2017) antiphase screening (see :mod:`study_app.headphones`).

``trials`` (default 6), ``pass`` = correct answers needed (default 5 of 6, their threshold), ``on_fail`` =
``end`` the session with the failure code (default) or ``continue`` and only record the outcome. Each
session gets its own shuffled tone orders and, per trial, a stored seed from which its sound is made
(random phases and level: the bytes differ between sessions); each sound is heard once.
"""
from __future__ import annotations

import random
from typing import Any

from study_app.headphones import TRIAL_SECONDS, correct_choice, trial_orders, trial_seeds, trial_wav
from study_app.pages.base import Media, Outcome, PageKind
from study_app.payload import PayloadError, int_in, only_keys

HEADPHONE_TEXT = (
    "Please put on headphones and set a comfortable volume. Each sound below has three tones. "
    "Play it once (it cannot be repeated) and choose the tone that was the quietest.")
HEADPHONE_ON_FAIL = ("end", "continue")


class HeadphoneCheckKind(PageKind):
    name = "headphone_check"
    keys = ("trials", "pass", "on_fail")
    script = "pages/headphone_check.js"
    media_word = "sound"
    done_word = "heard"
    default_title = "Headphone check"
    default_text = HEADPHONE_TEXT

    def load(self, chk: Any, page: dict, where: str, study: Any) -> dict:
        trials = chk.int_range(page, "trials", where, 1, 30, default=6)
        need = chk.int_range(page, "pass", where, 1, 30, default=max(1, round(trials * 5 / 6)))
        if need > trials:
            chk.fail(f"{where}.pass", f"expected at most trials ({trials}), got {need}")
        on_fail = chk.get(page, "on_fail", where, str, default="end",
                          expected=f"one of {', '.join(HEADPHONE_ON_FAIL)}")
        if on_fail not in HEADPHONE_ON_FAIL:
            chk.fail(f"{where}.on_fail", f"expected one of {', '.join(HEADPHONE_ON_FAIL)}, got {on_fail!r}")
        return {"trials": trials, "pass": need, "on_fail": on_fail}

    def plan_pages(self, page: Any, session: int, plan: Any) -> list[dict]:
        rng = random.Random(f"{plan.study.seed}:{session}:{page.id}")   # str seeds are stable across Pythons
        trials = trial_orders(page.cfg["trials"], rng)
        return [{"page": page.id, "type": page.type, "trials": trials, "sounds": trial_seeds(len(trials), rng)}]

    def n_slots(self, spec: dict) -> int:
        return len(spec.get("trials", []))

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        seeds = spec.get("sounds")     # plans built before the seeds existed: the fixed sounds
        return Media(body=trial_wav(spec["trials"][slot], seeds[slot] if seeds else None), mimetype="audio/wav")

    def generated_seconds(self, spec: dict, slot: int) -> float | None:
        return TRIAL_SECONDS            # the playback time check: the page stays open at least one trial

    def page_data(self, study: Any, spec: dict, cfg: dict) -> dict:
        return {"play_once": True}          # Woods et al.: each trial is heard once

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        only_keys(answer, ("choices",), "answer")
        choices, n = answer.get("choices"), len(spec["trials"])
        if not isinstance(choices, list) or len(choices) != n:
            raise PayloadError(f"answer.choices: expected a list of {n} answers (1, 2 or 3)")
        choices = [int_in(c, 1, 3, f"answer.choices[{i}]") for i, c in enumerate(choices)]
        correct = sum(c == correct_choice(o) for c, o in zip(choices, spec["trials"]))
        return {"choices": choices, "correct": correct,
                "passed": correct >= study.page(spec["page"]).cfg["pass"]}

    def outcome(self, study: Any, spec: dict, data: dict) -> Outcome:
        if not data["passed"] and study.page(spec["page"]).cfg["on_fail"] == "end":
            return Outcome(end_reason="headphone_check")
        return Outcome()


KIND = HeadphoneCheckKind()
