"""``likert``: one video and statements rated on a 2-11 point scale."""
from __future__ import annotations

from typing import Any

from study_app.pages.base import BlockKind, Media, Outcome, check_cols, export_condition, segment_for
from study_app.payload import int_in, only_keys, require_dict
from study_app.schema import load_text_items


class LikertKind(BlockKind):
    name = "likert"
    keys = BlockKind.keys + ("statements", "points", "labels")
    script = "pages/likert.js"

    def min_conditions(self, page: dict) -> int:
        return 1

    def load_options(self, chk: Any, page: dict, where: str, cfg: dict, known: list[str]) -> None:
        cfg["points"] = chk.int_range(page, "points", where, 2, 11, default=7)
        cfg["statements"] = load_text_items(chk, page, "statements", where, required=True, extra=("scale",))
        labels = chk.str_list(page, "labels", where, default=None)
        if labels is not None and len(labels) not in (2, cfg["points"]):
            chk.fail(f"{where}.labels", f"expected 2 labels (ends) or {cfg['points']} (one per "
                     f"point), got {len(labels)}")
        cfg["labels"] = labels or ["Strongly disagree", "Strongly agree"]

    def attention_fits(self, stim: Any, cfg: dict) -> bool:
        return stim.expected.isdigit() and 1 <= int(stim.expected) <= cfg["points"]

    def regular_page(self, block: Any, g: int, lookup: Any, segments: list[str]) -> dict:
        conds = block.cfg["conditions"]
        cond = conds[g % len(conds)]
        seg = segment_for(g, len(conds), segments)
        return {"type": "likert", "segment": seg, "stimulus": lookup.file(cond, seg)}

    def check_page(self, block: Any, k: int, pool: list, lookup: Any) -> dict:
        check = pool[k % len(pool)]
        return {"type": "likert", "segment": check.segment, "stimulus": check.file, "check": True}

    def order_item(self, spec: dict, by_file: dict) -> object:
        return export_condition(by_file[spec["stimulus"]])

    def n_slots(self, spec: dict) -> int:
        return 1

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        return Media(file=spec["stimulus"])

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        block = study.page(spec["block"]).cfg
        only_keys(answer, ("ratings",), "answer")
        ratings = require_dict(answer.get("ratings"), "answer.ratings")
        ids = [s["id"] for s in block["statements"]]
        only_keys(ratings, ids, "answer.ratings")
        return {"ratings": {sid: int_in(ratings.get(sid), 1, block["points"], f"answer.ratings.{sid}")
                            for sid in ids}}

    def outcome(self, study: Any, spec: dict, data: dict) -> Outcome:
        if not spec.get("check"):
            return Outcome()
        expected = int(study.manifest.by_file()[spec["stimulus"]].expected)
        return Outcome(attention=all(v == expected for v in data["ratings"].values()))

    def export_rows(self, study: Any, spec: dict, answer: Any, base: dict) -> list[dict]:
        stim = study.manifest.by_file()[spec["stimulus"]]
        block = study.page(spec["block"]).cfg
        return [{**base, "question": st["id"], "scale": st["scale"], "condition": export_condition(stim),
                 "answer": answer.data["ratings"][st["id"]],
                 **check_cols(spec, answer, stim.expected if spec.get("check") else "")}
                for st in block["statements"]]


KIND = LikertKind()
