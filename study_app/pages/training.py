"""``training``: practice pages of a rating block (``of``), flagged and excluded from analysis."""
from __future__ import annotations

from typing import Any

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
        for j, s in enumerate(page.cfg["segments"] or []):
            if s not in target.cfg["segments"]:
                chk.fail(f"pages[{index}].segments[{j}]", f"segment {s!r} has no stimulus for every "
                         f"condition of {target.id!r}")

    def plan_pages(self, page: Any, session: int, plan: Any) -> list[dict]:
        block = plan.study.blocks[page.cfg["of"]]
        n = page.cfg["count"]
        segments = page.cfg["segments"] or block.cfg["segments"]
        kind = plan.kind(block.type)
        return [{"page": f"{page.id}-{j + 1:02d}", "block": block.id, "training": True, "check": False,
                 **kind.regular_page(block, session * n + j, plan.lookup, segments)} for j in range(n)]


KIND = TrainingKind()
