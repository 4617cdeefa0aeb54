"""Balanced session plans: what each participant sees, page by page.

``build_plans(study)`` turns the study's blocks (conditions x segments) into
``study.sessions`` plans. Conventions:

* block pages get a global index ``g = session * pages + j``; pairwise page ``g`` shows pair
  ``pairs[g % len(pairs)]`` (so over ``n * pages`` pages every comparison occurs
  ``n * pages / len(pairs)`` times when that divides), condition A goes left on even and
  right on odd occurrences of its pair (left/right counterbalanced);
* segments cycle with ``g`` (distinct within a session while ``pages <= len(segments)``), and
  shift by one every ``lcm(len(items), len(segments))`` pages so that every item meets every
  segment;
* the order of a session's block pages is a row of a Williams balanced Latin square (each
  page in each position equally often, first-order carry-over balanced);
* MUSHRA pages rotate the slot order (each condition in each slot equally often);
* attention-check pages are inserted at the block positions the definition names (never
  position 0), training pages where the definition places them, flagged and excluded from
  analysis;
* a ``headphone_check`` page gets its own shuffled tone orders per session (the quiet tone in
  each position equally often, see :mod:`study_app.headphones`);
* ``mismatched: true`` pairwise blocks pair each condition's matched video with its
  mismatched one (same speech, motion from another segment); A is always the matched one.

The plans refer to stimuli by manifest file name; they stay on the server.
"""
from __future__ import annotations

import hashlib
import json
import math
import pathlib
import random
from collections import Counter

from study_app.definition import BLOCK_TYPES, Study, attention_pool
from study_app.errors import StudyDefinitionError
from study_app.headphones import trial_orders

PLANS_FORMAT = "evalsuite-study-plans/1"


def williams_rows(n: int) -> list[list[int]]:
    """Rows of a Williams balanced Latin square of order ``n`` (``2n`` rows when n is odd)."""
    if n == 1:
        return [[0]]
    first, lo, hi = [0], 1, n - 1
    while len(first) < n:
        first.append(lo)
        lo += 1
        if len(first) < n:
            first.append(hi)
            hi -= 1
    rows = [[(v + r) % n for v in first] for r in range(n)]
    if n % 2:
        rows += [list(reversed(r)) for r in rows]
    return rows


class _Lookup:
    def __init__(self, study: Study):
        self.matched, self.mismatched = {}, {}
        for s in study.manifest.stimuli:
            if s.kind != "stimulus":
                continue
            target = self.mismatched if s.mismatched else self.matched
            target.setdefault((s.condition, s.segment), s.file)

    def file(self, condition, segment, mismatched=False):
        return (self.mismatched if mismatched else self.matched)[(condition, segment)]


def _segment_for(g: int, n_items: int, segments: list[str]) -> str:
    period = math.lcm(max(n_items, 1), len(segments))
    return segments[(g + g // period) % len(segments)]


def _regular_page(block, g: int, lookup: _Lookup, segments: list[str]) -> dict:
    cfg = block.cfg
    if block.type == "pairwise":
        if cfg["mismatched"]:
            conds = cfg["conditions"]
            cond = conds[g % len(conds)]
            seg = _segment_for(g, len(conds), segments)
            a, b = lookup.file(cond, seg), lookup.file(cond, seg, mismatched=True)
            occurrence = g // len(conds)
        else:
            pairs = cfg["pairs"]
            x, y = pairs[g % len(pairs)]
            seg = _segment_for(g, len(pairs), segments)
            a, b = lookup.file(x, seg), lookup.file(y, seg)
            occurrence = g // len(pairs)
        # Alternates for every item (balance) and differs between neighbouring items (so one
        # session does not show every A on the same side).
        n_items = len(cfg["conditions"] if cfg["mismatched"] else cfg["pairs"])
        flip = (occurrence + g % n_items) % 2
        return {"type": "pairwise", "segment": seg, "a": a, "b": b,
                "position_a": "left" if flip == 0 else "right"}
    if block.type == "mushra":
        seg = segments[g % len(segments)]
        slots = [(c, "") for c in cfg["conditions"]]
        slots += [(cfg[r], r) for r in ("reference", "anchor") if cfg.get(r)]
        # Each condition in each slot equally often over len(slots) consecutive pages; the
        # shift moves every lcm(...) pages so slots and segments are not confounded.
        shift = (g + g // math.lcm(len(segments), len(slots))) % len(slots)
        slots = slots[shift:] + slots[:shift]
        return {"type": "mushra", "segment": seg, "slots": [lookup.file(c, seg) for c, _ in slots],
                "roles": [r for _, r in slots]}
    conds = cfg["conditions"]
    cond = conds[g % len(conds)]
    seg = _segment_for(g, len(conds), segments)
    return {"type": "likert", "segment": seg, "stimulus": lookup.file(cond, seg)}


def _check_page(block, k: int, pool, lookup: _Lookup) -> dict:
    """The k-th attention-check page of this block (over all sessions)."""
    cfg = block.cfg
    check = pool[k % len(pool)]
    if block.type == "pairwise":
        conds = cfg["conditions"]
        partner_seg = check.segment if check.segment in cfg["segments"] else cfg["segments"][0]
        partner = lookup.file(conds[k % len(conds)], partner_seg)
        return {"type": "pairwise", "segment": check.segment, "a": check.file, "b": partner,
                "position_a": "left" if (k // len(pool)) % 2 == 0 else "right", "check": True}
    if block.type == "mushra":
        page = _regular_page(block, k, lookup, [check.segment])
        replaceable = [i for i, r in enumerate(page["roles"]) if not r]
        slot = replaceable[k % len(replaceable)]
        page["slots"][slot] = check.file
        page["check_slot"] = slot
        return page
    return {"type": "likert", "segment": check.segment, "stimulus": check.file, "check": True}


def build_plans(study: Study) -> dict:
    """Session plans for ``study`` as a JSON-serialisable dict (see module docstring)."""
    lookup = _Lookup(study)
    blocks = study.blocks
    pools = {bid: attention_pool(study.manifest, bid, b.type, b.cfg) for bid, b in blocks.items()}
    check_counter = Counter()
    plans = []
    for s in range(study.sessions):
        pages = []
        for page in study.pages:
            if page.type in BLOCK_TYPES:
                k = page.cfg["pages"]
                regular = [_regular_page(page, s * k + j, lookup, page.cfg["segments"]) for j in range(k)]
                rows = williams_rows(k)
                ordered = [regular[i] for i in rows[s % len(rows)]]
                for pos in page.cfg["attention_checks"]:
                    ordered.insert(pos, _check_page(page, check_counter[page.id], pools[page.id], lookup))
                    check_counter[page.id] += 1
                for j, p in enumerate(ordered):
                    pages.append({"page": f"{page.id}-{j + 1:02d}", "block": page.id, "training": False,
                                  "check": bool(p.pop("check", False) or "check_slot" in p), **p})
            elif page.type == "training":
                block = blocks[page.cfg["of"]]
                n = page.cfg["count"]
                segments = page.cfg["segments"] or block.cfg["segments"]
                for j in range(n):
                    p = _regular_page(block, s * n + j, lookup, segments)
                    pages.append({"page": f"{page.id}-{j + 1:02d}", "block": block.id, "training": True,
                                  "check": False, **p})
            elif page.type == "headphone_check":
                rng = random.Random(f"{study.seed}:{s}:{page.id}")   # str seeds are stable across Pythons
                pages.append({"page": page.id, "type": page.type,
                              "trials": trial_orders(page.cfg["trials"], rng)})
            else:
                pages.append({"page": page.id, "type": page.type})
        plans.append({"key": f"plan-{s:04d}", "pages": pages})
    return {"format": PLANS_FORMAT, "study": study.id, "definition_sha256": study.sha256,
            "manifest_sha256": study.manifest.sha256, "plans": plans}


def plans_digest(plans: dict) -> str:
    return hashlib.sha256(json.dumps(plans["plans"], sort_keys=True).encode()).hexdigest()


def default_plans_path(study: Study) -> pathlib.Path:
    return study.path.with_name(f"{study.id}.plans.json")


def write_plans(plans: dict, path) -> pathlib.Path:
    path = pathlib.Path(path)
    path.write_text(json.dumps(plans, indent=1, sort_keys=True))
    return path


def read_plans(path, study: Study) -> dict:
    path = pathlib.Path(path)
    if not path.is_file():
        raise StudyDefinitionError("session plans not found; run `evalsuite study build` first",
                                   path=path)
    try:
        plans = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise StudyDefinitionError(f"not a plans JSON file ({exc})", path=path) from None
    if not isinstance(plans, dict) or plans.get("format") != PLANS_FORMAT:
        raise StudyDefinitionError(f"expected format {PLANS_FORMAT!r}", path=path, field="format")
    if plans.get("study") != study.id:
        raise StudyDefinitionError(f"plans are for study {plans.get('study')!r}, expected {study.id!r}",
                                   path=path, field="study")
    if (plans.get("definition_sha256") != study.sha256
            or plans.get("manifest_sha256") != study.manifest.sha256):
        raise StudyDefinitionError("plans were built from another version of the study definition or "
                                   "manifest; run `evalsuite study build` again", path=path)
    return plans


def balance_report(plans: dict, study: Study) -> dict:
    """Counts that show the balance: per compared pair (with left/right), per MUSHRA slot."""
    by_file = study.manifest.by_file()
    pairs, slots, positions = Counter(), Counter(), Counter()
    for plan in plans["plans"]:
        for i, p in enumerate(plan["pages"]):
            if p.get("training") or p.get("type") not in BLOCK_TYPES:
                continue
            if p["type"] == "pairwise" and not p["check"]:
                a, b = by_file[p["a"]], by_file[p["b"]]
                key = (p["block"], a.condition, b.condition + (":mismatched" if b.mismatched else ""))
                pairs[key + (p["position_a"],)] += 1
            elif p["type"] == "mushra":
                for k, f in enumerate(p["slots"]):
                    if k != p.get("check_slot"):
                        slots[(p["block"], by_file[f].condition, k)] += 1
            positions[(p["block"], p["page"])] += 1
    return {"pairs": pairs, "mushra_slots": slots}
