"""``pairwise``: two videos side by side, one or more questions with 3 or 5 answer levels, optional
reasons (required when a side is preferred, as HEMVIP/GENEA 2023 ask), matched-vs-mismatched blocks."""
from __future__ import annotations

import re
from typing import Any

from study_app.ordering import balanced_sides
from study_app.pages.base import BlockKind, Media, Outcome, ab, check_cols, export_condition, segment_for
from study_app.payload import PayloadError, only_keys, require_dict
from study_app.schema import load_text_items

# Screen answers of a pairwise question, 3-level and 5-level.
PAIRWISE_ANSWERS = {3: ("left", "equal", "right"),
                    5: ("left_strong", "left_weak", "equal", "right_weak", "right_strong")}
PAIRWISE_LABELS = {
    3: ("Left", "They are equal", "Right"),
    5: ("Left is clearly better", "Left is slightly better", "They are equal",
        "Right is slightly better", "Right is clearly better"),
}
# Expected answers of a pairwise attention-check stimulus: relative to the side showing the check video
# (this/other) or absolute (left/right/equal); optional strength suffix.
PAIRWISE_EXPECTED_RE = re.compile(r"^(this|other|left|right|equal)(_(strong|weak))?$")


def expected_screen(expected: str, position_check: str) -> tuple[str, str]:
    """(side, strength) an attentive participant picks; side in left/right/equal."""
    m = PAIRWISE_EXPECTED_RE.match(expected)
    if not m:
        raise PayloadError(f"bad pairwise attention expectation {expected!r}")
    word, strength = m.group(1), m.group(3) or ""
    other = "right" if position_check == "left" else "left"
    return {"this": position_check, "other": other}.get(word, word), strength


def screen_side(choice: str) -> tuple[str, str]:
    """'left_strong' -> ('left', 'strong'); 'equal' -> ('equal', '')."""
    side, _, strength = choice.partition("_")
    return side, strength


class PairwiseKind(BlockKind):
    name = "pairwise"
    keys = BlockKind.keys + ("pairs", "mismatched", "levels", "questions", "reasons", "reasons_required")
    script = "pages/pairwise.js"

    def min_conditions(self, page: dict) -> int:
        return 1 if page.get("mismatched") else 2

    def needs_mismatched(self, cfg: dict) -> bool:
        return bool(cfg["mismatched"])

    def load_options(self, chk: Any, page: dict, where: str, cfg: dict, known: list[str]) -> None:
        conditions = cfg["conditions"]
        cfg["mismatched"] = chk.get(page, "mismatched", where, bool, default=False)
        cfg["levels"] = chk.get(page, "levels", where, int, default=3, expected="3 or 5")
        if cfg["levels"] not in (3, 5):
            chk.fail(f"{where}.levels", f"expected 3 or 5, got {cfg['levels']}")
        cfg["questions"] = load_text_items(chk, page, "questions", where, required=True)
        cfg["reasons"] = load_text_items(chk, page, "reasons", where, required=False)
        # HEMVIP (GENEA 2023) asks for at least one reason whenever a side is preferred.
        cfg["reasons_required"] = chk.get(page, "reasons_required", where, bool, default=False)
        if cfg["reasons_required"] and not cfg["reasons"]:
            chk.fail(f"{where}.reasons_required", "needs a list of reasons to choose from")
        pairs = chk.get(page, "pairs", where, list, default=None, expected="a list of [condition, condition]")
        if cfg["mismatched"]:
            if pairs is not None:
                chk.fail(f"{where}.pairs", "not allowed with mismatched: true (each page pairs one "
                         "condition's matched and mismatched video)")
            return
        if pairs is None:
            pairs = [[a, b] for i, a in enumerate(conditions) for b in conditions[i + 1:]]
        for i, pair in enumerate(pairs):
            if (not isinstance(pair, list) or len(pair) != 2 or pair[0] == pair[1]
                    or any(c not in conditions for c in pair)):
                chk.fail(f"{where}.pairs[{i}]", f"expected two different conditions of this block, got {pair!r}")
        cfg["pairs"] = [list(p) for p in pairs]

    def attention_fits(self, stim: Any, cfg: dict) -> bool:
        m = PAIRWISE_EXPECTED_RE.match(stim.expected)
        return m is not None and not (m.group(2) and cfg["levels"] == 3)

    def regular_page(self, block: Any, g: int, lookup: Any, segments: list[str]) -> dict:
        cfg = block.cfg
        if cfg["mismatched"]:
            conds = cfg["conditions"]
            cond = conds[g % len(conds)]
            seg = segment_for(g, len(conds), segments)
            a, b = lookup.file(cond, seg), lookup.file(cond, seg, mismatched=True)
            occurrence = g // len(conds)
        else:
            pairs = cfg["pairs"]
            x, y = pairs[g % len(pairs)]
            seg = segment_for(g, len(pairs), segments)
            a, b = lookup.file(x, seg), lookup.file(y, seg)
            occurrence = g // len(pairs)
        # Alternates for every item (balance) and differs between neighbouring items (so one session
        # does not show every A on the same side).
        n_items = len(cfg["conditions"] if cfg["mismatched"] else cfg["pairs"])
        flip = (occurrence + g % n_items) % 2
        return {"type": "pairwise", "segment": seg, "a": a, "b": b, "position_a": "left" if flip == 0 else "right"}

    def check_page(self, block: Any, k: int, pool: list, lookup: Any) -> dict:
        cfg = block.cfg
        check = pool[k % len(pool)]
        conds = cfg["conditions"]
        partner_seg = check.segment if check.segment in cfg["segments"] else cfg["segments"][0]
        partner = lookup.file(conds[k % len(conds)], partner_seg)
        return {"type": "pairwise", "segment": check.segment, "a": check.file, "b": partner,
                "position_a": "left" if (k // len(pool)) % 2 == 0 else "right", "check": True}

    def arrange(self, block: Any, pages: list[dict], rng: Any, by_file: dict) -> None:
        """A left or right per page: random, each comparison and each condition on each side equally often
        within one over the study (:func:`study_app.ordering.balanced_sides`)."""
        items = [(export_condition(by_file[p["a"]]), export_condition(by_file[p["b"]])) for p in pages]
        for p, left in zip(pages, balanced_sides(rng, items)):
            p["position_a"] = "left" if left else "right"

    def order_item(self, spec: dict, by_file: dict) -> object:
        a, b = by_file[spec["a"]], by_file[spec["b"]]
        return (export_condition(a), export_condition(b))

    def balance(self, spec: dict, by_file: dict, counts: dict) -> None:
        if spec["check"]:
            return
        a, b = by_file[spec["a"]], by_file[spec["b"]]
        key = (spec["block"], a.condition, b.condition + (":mismatched" if b.mismatched else ""))
        counts["pairs"][key + (spec["position_a"],)] += 1

    def n_slots(self, spec: dict) -> int:
        return 2

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        return Media(file=spec["a"] if (slot == 0) == (spec["position_a"] == "left") else spec["b"])

    def page_data(self, study: Any, spec: dict, cfg: dict) -> dict:
        levels = cfg["levels"]
        return {**super().page_data(study, spec, cfg),
                "options": [{"value": v, "label": lbl} for v, lbl in
                            zip(PAIRWISE_ANSWERS[levels], PAIRWISE_LABELS[levels])],
                "reasons_required": cfg["reasons_required"]}

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        block = study.page(spec["block"]).cfg
        only_keys(answer, ("choices", "reasons"), "answer")
        choices = require_dict(answer.get("choices"), "answer.choices")
        allowed = PAIRWISE_ANSWERS[block["levels"]]
        qids = [q["id"] for q in block["questions"]]
        only_keys(choices, qids, "answer.choices")
        for qid in qids:
            if choices.get(qid) not in allowed:
                raise PayloadError(f"answer.choices.{qid}: expected one of {', '.join(allowed)}")
        reasons = answer.get("reasons", [])
        reason_ids = {r["id"] for r in block["reasons"]}
        if not isinstance(reasons, list) or any(not isinstance(r, str) or r not in reason_ids for r in reasons):
            raise PayloadError("answer.reasons: expected a list of reason ids of this page")
        if block["reasons_required"] and not reasons and any(c != "equal" for c in choices.values()):
            raise PayloadError("answer.reasons: please tick at least one reason for your preference")
        return {"choices": {q: choices[q] for q in qids}, "reasons": sorted(set(reasons))}

    def outcome(self, study: Any, spec: dict, data: dict) -> Outcome:
        if not spec.get("check"):
            return Outcome()
        side, strength = expected_screen(study.manifest.by_file()[spec["a"]].expected, spec["position_a"])
        for choice in data["choices"].values():
            got_side, got_strength = screen_side(choice)
            if got_side != side or (strength and got_strength != strength):
                return Outcome(attention=False)
        return Outcome(attention=True)

    def export_rows(self, study: Any, spec: dict, answer: Any, base: dict) -> list[dict]:
        by_file = study.manifest.by_file()
        block = study.page(spec["block"]).cfg
        a, b = by_file[spec["a"]], by_file[spec["b"]]
        expected = ""
        if spec.get("check"):
            side, strength = expected_screen(a.expected, spec["position_a"])
            expected = ab(side, spec["position_a"]) + (f"/{strength}" if strength else "")
        rows = []
        for q in block["questions"]:
            side, strength = screen_side(answer.data["choices"][q["id"]])
            rows.append({**base, "question": q["id"], "condition_a": export_condition(a),
                         "condition_b": export_condition(b), "position_a": spec["position_a"],
                         "answer": ab(side, spec["position_a"]), "strength": strength,
                         "reasons": ";".join(answer.data.get("reasons", [])),
                         **check_cols(spec, answer, expected)})
        return rows

    def comparison_label(self, row: dict) -> str:
        return f"{row['condition_a']} vs {row['condition_b']}"


KIND = PairwiseKind()
