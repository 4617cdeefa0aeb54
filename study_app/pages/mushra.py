"""``mushra``: several videos of one segment rated on 0-100 sliders (MUSHRA-style, ITU-R BS.1534), with
an optional hidden reference and anchor; the slot order is random per page and participant, each condition
in each slot equally often within one over the study (:mod:`study_app.ordering`). Displayed side by side
(``layout: grid``) or as HEMVIP does (``layout: hemvip``: one player, a button per video above vertical
sliders on one labelled scale); ``slider_numbers: false`` hides the numbers."""
from __future__ import annotations

from typing import Any

from study_app.ordering import latin_slot_orders
from study_app.pages.base import BlockKind, Media, Outcome, export_condition
from study_app.payload import PayloadError, int_in, only_keys

DEFAULT_BANDS = ["Bad", "Poor", "Fair", "Good", "Excellent"]
# How a page shows its videos: "grid" (every video with its own horizontal slider, side by side) or
# "hemvip" (one player; a button per video above vertical sliders side by side on one labelled scale).
LAYOUTS = ("grid", "hemvip")


def expected_interval(expected: str, bands: list[str]) -> tuple[float, float] | None:
    """(lo, hi) interval an attentive rating falls in before tolerance, or None: a number 0-100, or the
    name of a band (``Bad`` .. ``Excellent``: equal fifths of the scale)."""
    if expected.isdigit() and 0 <= int(expected) <= 100:
        return (int(expected), int(expected))
    names = [b.lower() for b in bands]
    if expected.lower() in names:
        k = names.index(expected.lower())
        width = 100 / len(bands)
        return (k * width, (k + 1) * width)
    return None


def check_passes(expected: str, rating: int, bands: list[str], tolerance: int) -> bool:
    interval = expected_interval(expected, bands)
    if interval is None:
        return False
    return interval[0] - tolerance <= rating <= interval[1] + tolerance


class MushraKind(BlockKind):
    name = "mushra"
    keys = BlockKind.keys + ("reference", "anchor", "question", "bands", "tolerance", "layout", "slider_numbers")
    script = "pages/mushra.js"
    attention_hint = ", segment of this block"

    def load_options(self, chk: Any, page: dict, where: str, cfg: dict, known: list[str]) -> None:
        for role in ("reference", "anchor"):
            r = chk.get(page, role, where, str, default="")
            if r and r not in known:
                chk.fail(f"{where}.{role}", f"unknown condition {r!r}; expected one of the manifest's "
                         f"conditions: {', '.join(known)}")
            if r and r in cfg["conditions"]:
                chk.fail(f"{where}.{role}", f"{r!r} is also in conditions; the hidden {role} is "
                         "added to the page by itself")
            cfg[role] = r
        q = chk.get(page, "question", where, dict, required=True, expected="a mapping with id and text")
        cfg["question"] = {"id": chk.ident(q, "id", f"{where}.question"),
                           "text": chk.get(q, "text", f"{where}.question", str, required=True)}
        cfg["bands"] = chk.str_list(page, "bands", where, default=list(DEFAULT_BANDS), min_len=2)
        cfg["tolerance"] = chk.int_range(page, "tolerance", where, 0, 50, default=3)
        layout = chk.get(page, "layout", where, str, default="grid", expected=" or ".join(LAYOUTS))
        if layout not in LAYOUTS:
            chk.fail(f"{where}.layout", f"expected one of {', '.join(LAYOUTS)}, got {layout!r}")
        cfg["layout"] = layout
        cfg["slider_numbers"] = chk.get(page, "slider_numbers", where, bool, default=True)

    def shown_conditions(self, cfg: dict) -> list[str]:
        return list(cfg["conditions"]) + [c for c in (cfg.get("reference"), cfg.get("anchor")) if c]

    def attention_fits(self, stim: Any, cfg: dict) -> bool:
        return expected_interval(stim.expected, cfg["bands"]) is not None and stim.segment in cfg["segments"]

    def regular_page(self, block: Any, g: int, lookup: Any, segments: list[str]) -> dict:
        cfg = block.cfg
        seg = segments[g % len(segments)]
        slots = [(c, "") for c in cfg["conditions"]]
        slots += [(cfg[r], r) for r in ("reference", "anchor") if cfg.get(r)]
        # In the block's own order; :meth:`arrange` draws each page's order.
        return {"type": "mushra", "segment": seg, "slots": [lookup.file(c, seg) for c, _ in slots],
                "roles": [r for _, r in slots]}

    def arrange(self, block: Any, pages: list[dict], rng: Any, by_file: dict) -> None:
        """A random slot order per page, from a random Latin square per cycle of pages (each condition in each
        slot equally often within one over the study, :func:`study_app.ordering.latin_slot_orders`)."""
        if not pages:
            return
        for p, order in zip(pages, latin_slot_orders(rng, len(pages), len(pages[0]["slots"]))):
            p["slots"] = [p["slots"][i] for i in order]
            p["roles"] = [p["roles"][i] for i in order]

    def check_page(self, block: Any, k: int, pool: list, lookup: Any) -> dict:
        check = pool[k % len(pool)]
        page = self.regular_page(block, k, lookup, [check.segment])
        replaceable = [i for i, r in enumerate(page["roles"]) if not r]
        slot = replaceable[k % len(replaceable)]
        page["slots"][slot] = check.file
        page["check_slot"] = slot
        return page

    def session_check_page(self, block: Any, k: int, pool: list, lookup: Any, rated: list[dict], rng: Any) -> dict:
        """A check page that is not a rated page with one clip swapped: the check clip of a segment the session
        does not rate in this block when the pool has one (else the next in turn), the other clips of that
        segment in a random order, the check clip in a random slot (never the hidden reference or anchor)."""
        rated_segments = {p["segment"] for p in rated}
        turn = pool[k % len(pool):] + pool[:k % len(pool)]
        check = next((c for c in turn if c.segment not in rated_segments), turn[0])
        cfg = block.cfg
        slots = [(c, "") for c in cfg["conditions"]] + [(cfg[r], r) for r in ("reference", "anchor") if cfg.get(r)]
        rng.shuffle(slots)
        slot = rng.choice([i for i, (_, role) in enumerate(slots) if not role])
        files = [lookup.file(c, check.segment) for c, _ in slots]
        files[slot] = check.file
        return {"type": "mushra", "segment": check.segment, "slots": files, "roles": [r for _, r in slots],
                "check_slot": slot}

    def balance(self, spec: dict, by_file: dict, counts: dict) -> None:
        if spec.get("check"):
            return          # an attention-check page is not analysed
        for k, f in enumerate(spec["slots"]):
            counts["mushra_slots"][(spec["block"], by_file[f].condition, k)] += 1

    def n_slots(self, spec: dict) -> int:
        return len(spec.get("slots", []))

    def media(self, study: Any, spec: dict, slot: int) -> Media:
        return Media(file=spec["slots"][slot])

    def parse_answer(self, study: Any, spec: dict, answer: dict, fields: dict) -> dict:
        only_keys(answer, ("ratings",), "answer")
        ratings = answer.get("ratings")
        n = len(spec["slots"])
        if not isinstance(ratings, list) or len(ratings) != n:
            raise PayloadError(f"answer.ratings: expected a list of {n} ratings")
        return {"ratings": [int_in(r, 0, 100, f"answer.ratings[{i}]") for i, r in enumerate(ratings)]}

    def outcome(self, study: Any, spec: dict, data: dict) -> Outcome:
        if not spec.get("check"):
            return Outcome()
        block = study.page(spec["block"]).cfg
        slot = spec["check_slot"]
        expected = study.manifest.by_file()[spec["slots"][slot]].expected
        return Outcome(attention=check_passes(expected, data["ratings"][slot], block["bands"], block["tolerance"]))

    def export_rows(self, study: Any, spec: dict, answer: Any, base: dict) -> list[dict]:
        by_file = study.manifest.by_file()
        block = study.page(spec["block"]).cfg
        rows = []
        for k, file in enumerate(spec["slots"]):
            stim = by_file[file]
            row = {**base, "question": block["question"]["id"], "condition": export_condition(stim),
                   "position_a": k, "answer": answer.data["ratings"][k], "role": spec["roles"][k]}
            if k == spec.get("check_slot"):
                lo, hi = expected_interval(stim.expected, block["bands"]) or (float("nan"), float("nan"))
                expected = str(stim.expected) if lo == hi else f"{lo:g}-{hi:g}"
                row.update(is_attention_check=1, attention_expected=expected,
                           attention_passed=int(bool(answer.attention_passed)))
            rows.append(row)
        return rows


KIND = MushraKind()
