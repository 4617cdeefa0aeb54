"""``training``: practice pages of a rating block (``of``), flagged and excluded from analysis."""
from __future__ import annotations

from typing import Any

from study_app.errors import StudyDefinitionError
from study_app.ordering import order_rng
from study_app.pages.base import PageKind


class TrainingKind(PageKind):
    name = "training"
    keys = ("of", "count", "segments")

    def load(self, chk: Any, page: dict, where: str, study: Any) -> dict:
        return {"of": chk.ident(page, "of", where),
                "count": chk.int_range(page, "count", where, 1, 100, default=1),
                "segments": chk.str_list(page, "segments", where, default=None, min_len=1)}

    def check_order(self, chk: Any, study: Any, index: int) -> None:
        page, blocks = study.pages[index], study.blocks
        if page.cfg["of"] not in blocks:
            chk.fail(f"pages[{index}].of", f"expected the id of a pairwise, mushra or likert page, "
                     f"got {page.cfg['of']!r}")
        target = blocks[page.cfg["of"]]
        kind = study.kind_of(target)
        stimuli = [st for st in study.manifest.stimuli if st.kind == "stimulus"]
        have = {(st.condition, st.segment, st.mismatched) for st in stimuli}
        needed = kind.shown_conditions(target.cfg)
        for j, s in enumerate(page.cfg["segments"] or []):
            if target.cfg.get("audio_mismatch") and s not in target.cfg["segments"]:
                chk.fail(f"pages[{index}].segments[{j}]", f"segment {s!r} is not one of {target.id!r}'s segments; "
                         "practice of an audio_mismatch block uses its segments (their speakers are known)")
            # Practice may use segments the block itself does not rate, as long as they have its stimuli.
            ok = all((c, s, False) in have for c in needed)
            if kind.needs_mismatched(target.cfg):
                ok = ok and all((c, s, True) in have for c in needed)
            if not ok:
                chk.fail(f"pages[{index}].segments[{j}]", f"segment {s!r} has no stimulus for every "
                         f"condition of {target.id!r}")

    def plan_pages(self, page: Any, session: int, plan: Any) -> list[dict]:
        """``count`` practice pages of the block, balanced like its pages, skipping any page whose material
        the session rates for real (``plan.rated``) or already practises."""
        block = plan.study.blocks[page.cfg["of"]]
        n = page.cfg["count"]
        segments = page.cfg["segments"] or block.cfg["segments"]
        kind = plan.kind(block.type)
        out: list[dict] = []
        used = set(plan.rated)
        g = session * n
        for _ in range(MAX_CANDIDATES):
            if len(out) == n:
                break
            cand = kind.regular_page(block, g, plan.lookup, segments)
            kind.arrange(block, [cand], order_rng(plan.study.seed, page.id, session, g), plan.study.manifest.by_file())
            g += 1
            material = kind.material(plan.study, cand)
            if material in used:
                continue
            used.add(material)
            out.append({"page": f"{page.id}-{len(out) + 1:02d}", "block": block.id, "training": True,
                        "check": False, **cand})
        if len(out) < n:
            raise StudyDefinitionError(
                f"session {session}: no practice material left that the participant does not rate for real "
                f"in {block.id!r}; give the training page segments of its own (segments: [...])",
                path=plan.study.path, field=f"pages[{plan.study.pages.index(page)}].segments")
        return out


MAX_CANDIDATES = 10_000
KIND = TrainingKind()
