"""``pairwise``: two videos side by side, one or more questions with 3 or 5 answer levels, optional
reasons (required when a side is preferred, as HEMVIP/GENEA 2023 ask), matched-vs-mismatched blocks (other
motion, this speech), audio-mismatch blocks (this motion, another segment's speech of the same speaker; the
GENEA Leaderboard's) and muted blocks served as video-only files (:mod:`study_app.derived`)."""
from __future__ import annotations

import re
from typing import Any

from study_app import derived
from study_app.adaptive import adaptive_options, adaptive_record
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
    keys = BlockKind.keys + ("pairs", "mismatched", "audio_mismatch", "speakers", "levels", "questions", "reasons",
                             "reasons_required", "adaptive", "exploration")
    script = "pages/pairwise.js"

    def min_conditions(self, page: dict) -> int:
        return 1 if page.get("mismatched") or page.get("audio_mismatch") else 2

    def load(self, chk: Any, page: dict, where: str, study: Any) -> dict:
        """The settings, then the clips ``study build`` derives (:mod:`study_app.derived`): audio-mismatched
        clips of an ``audio_mismatch`` block, video-only copies of a muted block's clips."""
        cfg = super().load(chk, page, where, study)
        block_id = page["id"] if isinstance(page.get("id"), str) else ""
        if cfg["audio_mismatch"]:
            groups = derived.load_speakers(chk, page.get("speakers"), where, cfg["segments"])
            cfg["audio_mismatched"] = derived.register_audio_mismatch(study.manifest, block_id, cfg["conditions"],
                                                                      groups, study.seed)
        elif "speakers" in page:
            chk.fail(f"{where}.speakers", "only used with audio_mismatch: true")
        cfg["silent"] = {}
        if cfg["muted"]:
            # every clip a page or a practice page of the block can show (any segment: practice may use others)
            files = [s.file for s in study.manifest.stimuli if s.kind == "stimulus" and s.condition in cfg["conditions"]]
            files += [s.file for s in self.attention_pool(study.manifest, block_id, cfg)]
            cfg["silent"] = derived.register_silent(study.manifest, files)
        return cfg

    def needs_mismatched(self, cfg: dict) -> bool:
        return bool(cfg["mismatched"])

    def load_options(self, chk: Any, page: dict, where: str, cfg: dict, known: list[str]) -> None:
        conditions = cfg["conditions"]
        cfg["mismatched"] = chk.get(page, "mismatched", where, bool, default=False)
        cfg["audio_mismatch"] = chk.get(page, "audio_mismatch", where, bool, default=False)
        if cfg["audio_mismatch"] and cfg["mismatched"]:
            chk.fail(f"{where}.audio_mismatch", "not with mismatched: true; expected one design per block "
                     "(mismatched: other motion, this speech; audio_mismatch: this motion, other speech)")
        if cfg["audio_mismatch"] and cfg["muted"]:
            chk.fail(f"{where}.muted", "not with audio_mismatch: true: the design compares speech, so it needs "
                     "sound")
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
        adaptive_options(chk, page, where, cfg)         # adaptive pair selection (study_app.adaptive)
        if cfg["mismatched"] or cfg["audio_mismatch"]:
            if pairs is not None:
                chk.fail(f"{where}.pairs", "not allowed with mismatched or audio_mismatch (each page pairs one "
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
        items = cfg["conditions"] if cfg["mismatched"] or cfg["audio_mismatch"] else cfg["pairs"]
        item = items[g % len(items)]
        seg = segment_for(g, len(items), segments)
        if cfg["mismatched"]:
            a, b = lookup.file(item, seg), lookup.file(item, seg, mismatched=True)
        elif cfg["audio_mismatch"]:
            a, b = lookup.file(item, seg), cfg["audio_mismatched"][(item, seg)]
        else:
            a, b = lookup.file(item[0], seg), lookup.file(item[1], seg)
        # Alternates for every item (balance) and differs between neighbouring items (so one session
        # does not show every A on the same side).
        flip = (g // len(items) + g % len(items)) % 2
        silent = cfg["silent"]
        return {"type": "pairwise", "segment": seg, "a": silent.get(a, a), "b": silent.get(b, b),
                "position_a": "left" if flip == 0 else "right"}

    def check_page(self, block: Any, k: int, pool: list, lookup: Any) -> dict:
        cfg = block.cfg
        check = pool[k % len(pool)]
        conds = cfg["conditions"]
        partner_seg = check.segment if check.segment in cfg["segments"] else cfg["segments"][0]
        partner = lookup.file(conds[k % len(conds)], partner_seg)
        silent = cfg["silent"]
        return {"type": "pairwise", "segment": check.segment, "a": silent.get(check.file, check.file),
                "b": silent.get(partner, partner),
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
        key = (spec["block"], a.condition, export_condition(b))
        counts["pairs"][key + (spec["position_a"],)] += 1

    def n_slots(self, spec: dict) -> int:
        return 2

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        """The slot's clip; in a muted block its video-only copy even where the plan names the clip itself
        (e.g. a pair chosen while the study runs)."""
        file = spec["a"] if (slot == 0) == (spec["position_a"] == "left") else spec["b"]
        silent = study.page(spec["block"]).cfg["silent"] if "block" in spec else {}
        return Media(file=silent.get(file, file))

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
        out = {"choices": {q: choices[q] for q in qids}, "reasons": sorted(set(reasons))}
        if "chosen" in spec:        # an adaptive page: what its estimate learns (study_app.adaptive)
            out["adaptive"] = adaptive_record(spec, study.manifest.by_file(), screen_side(choices[qids[0]])[0])
        return out

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
                         "audio_a": _audio(a, block), "audio_b": _audio(b, block),
                         **check_cols(spec, answer, expected)})
        return rows

    def comparison_label(self, row: dict) -> str:
        return f"{row['condition_a']} vs {row['condition_b']}"


def _audio(stim: Any, block: dict) -> str:
    """The speech segment a clip played (empty in a muted block): the audio-mismatched clip's donor, else
    the clip's own segment."""
    return "" if block["muted"] or stim.silent else (stim.audio_segment or stim.segment)


KIND = PairwiseKind()
