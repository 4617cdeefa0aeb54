"""Balanced session plans: what each participant sees, page by page.

``build_plans(study)`` turns the study's blocks (conditions x segments) into
``study.sessions`` plans. Conventions:

* block pages get a global index ``g = session * pages + j``; pairwise page ``g`` shows pair
  ``pairs[g % len(pairs)]`` (so over ``n * pages`` pages every comparison occurs
  ``n * pages / len(pairs)`` times when that divides);
* segments cycle with ``g`` (distinct within a session while ``pages <= len(segments)``), and
  shift by one every ``lcm(len(items), len(segments))`` pages so that every item meets every
  segment;
* orders are random per page and participant, seeded from the study's seed, and balanced over
  the study (:mod:`study_app.ordering`): a session's block pages are placed so that each item
  (comparison, MUSHRA segment, Likert condition) takes each position about equally often; a
  MUSHRA page's slot order is a row of a random Latin square (each condition in each slot equally
  often within one); pairwise A goes left or right at random, each comparison and each condition
  on each side equally often within one;
* attention-check pages are inserted near the block positions the definition names: each
  session moves each check by up to ``attention_window`` pages (default 2; seeded per session
  from the study's seed), never to position 0; training pages where the definition places them, flagged and excluded from
  analysis; a training page never shows material the participant rates for real (the same
  stimuli, e.g. the same pair on the same segment on either side): it takes the next balanced
  page whose material the session's rated pages do not use;
* a ``headphone_check`` page gets its own shuffled tone orders per session (the quiet tone in
  each position equally often, see :mod:`study_app.headphones`);
* ``mismatched: true`` pairwise blocks pair each condition's matched video with its
  mismatched one (same speech, motion from another segment); A is always the matched one;
  ``audio_mismatch: true`` blocks pair it with the same motion under another segment's speech of the same
  speaker (:mod:`study_app.derived`); A is the matched one, and each segment donates its speech once per
  condition, so every speech segment is heard matched and mismatched equally often over the study.

The plans refer to stimuli by manifest file name; they stay on the server.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
import random
from collections import Counter

from study_app.derived import missing_derived
from study_app.errors import StudyDefinitionError
from study_app.model import Study
from study_app.ordering import PositionBalancer, order_rng
from study_app.pages import get_block_kind, get_kind

PLANS_FORMAT = "evalsuite-study-plans/1"


class _Lookup:
    def __init__(self, study: Study):
        self.matched: dict[tuple[str, str], str] = {}
        self.mismatched: dict[tuple[str, str], str] = {}
        for s in study.manifest.stimuli:
            if s.kind != "stimulus":
                continue
            target = self.mismatched if s.mismatched else self.matched
            target.setdefault((s.condition, s.segment), s.file)

    def file(self, condition, segment, mismatched=False):
        return (self.mismatched if mismatched else self.matched)[(condition, segment)]


class _PlanBuilder:
    """What page kinds need to expand a definition page: the study, the stimulus lookup, the kinds, and
    (for practice pages) the material the session rates for real."""

    def __init__(self, study: Study):
        self.study = study
        self.lookup = _Lookup(study)
        self.kind = get_block_kind
        self.rated: set[frozenset[str]] = set()     # material of the current session's rated pages

    def material(self, spec: dict) -> frozenset[str]:
        return get_block_kind(spec["type"]).material(self.study, spec)


def build_plans(study: Study) -> dict:
    """Session plans for ``study`` as a JSON-serialisable dict (see module docstring)."""
    builder = _PlanBuilder(study)
    blocks = study.blocks
    by_file = study.manifest.by_file()
    kinds = {bid: get_block_kind(b.type) for bid, b in blocks.items()}
    pools = {bid: kinds[bid].attention_pool(study.manifest, bid, b.cfg) for bid, b in blocks.items()}
    # Every trial page of a block over all sessions (global index g = session * pages + j), its within-page
    # orders drawn over the whole study, and a balancer for the page positions (study_app.ordering).
    trials: dict[str, list[dict]] = {}
    positions: dict[str, PositionBalancer] = {}
    for bid, b in blocks.items():
        k = b.cfg["pages"]
        trials[bid] = [kinds[bid].regular_page(b, g, builder.lookup, b.cfg["segments"])
                       for g in range(study.sessions * k)]
        kinds[bid].arrange(b, trials[bid], order_rng(study.seed, bid, "within-page"), by_file)
        positions[bid] = PositionBalancer(k, order_rng(study.seed, bid, "page-order"))
    check_counter: Counter = Counter()
    plans = []
    for s in range(study.sessions):
        # Rated pages first: practice pages (placed before them) must use other material.
        rated: dict[str, list[dict]] = {}
        for page in study.pages:
            if not get_kind(page.type).block:
                continue
            kind = kinds[page.id]
            k = page.cfg["pages"]
            regular = [dict(p) for p in trials[page.id][s * k:(s + 1) * k]]
            order = positions[page.id].arrange([kind.order_item(p, by_file) for p in regular])
            ordered = [regular[i] for i in order]
            rng = session_rng(study.seed, page.id, s)
            checks = [kind.session_check_page(page, check_counter[page.id] + i, pools[page.id], builder.lookup,
                                              ordered, rng) for i in range(len(page.cfg["attention_checks"]))]
            check_counter[page.id] += len(checks)
            for pos, check in zip(check_positions(page.cfg["attention_checks"], k, page.cfg["attention_window"],
                                                  rng), checks):
                ordered.insert(pos, check)
            rated[page.id] = [{"page": f"{page.id}-{j + 1:02d}", "block": page.id, "training": False,
                               "check": bool(p.pop("check", False) or "check_slot" in p), **p}
                              for j, p in enumerate(ordered)]
        builder.rated = {builder.material(p) for block_pages in rated.values() for p in block_pages}
        pages = []
        for page in study.pages:
            if get_kind(page.type).block:
                pages.extend(rated[page.id])
            else:
                pages.extend(get_kind(page.type).plan_pages(page, s, builder))
        plans.append({"key": f"plan-{s:04d}", "pages": pages})
    return {"format": PLANS_FORMAT, "study": study.id, "definition_sha256": study.sha256,
            "manifest_sha256": study.manifest.sha256, "plans": plans}


def session_rng(seed: int, block_id: str, session: int) -> random.Random:
    """A generator for one session and block, seeded from the study's seed (the same plans on every build)."""
    digest = hashlib.sha256(f"evalsuite-plan|{seed}|{block_id}|{session}".encode()).digest()
    return random.Random(int.from_bytes(digest[:8], "big"))


def check_positions(configured: list[int], n_pages: int, window: int, rng: random.Random) -> list[int]:
    """Where a session's attention checks go in a block of ``n_pages`` trial pages: each configured position
    moved by up to ``window`` pages (uniformly), never to position 0, in order, none past the block's end.
    Returned as insertion indices, in order (the ``i``-th check ends up at its index)."""
    out: list[int] = []
    for i, p in enumerate(configured):
        lo = max(1, p - window, out[-1] + 1 if out else 1)
        hi = min(n_pages + i, p + window)
        out.append(rng.randint(lo, max(lo, hi)))
    return out


def entry_pages(plans: dict) -> list[dict] | None:
    """The pages a session shows before it holds a plan, or None.

    When the first page is the same in every plan (a consent page, instructions, a questionnaire), a session
    starts without a plan and reserves one when that page is answered (``study_app.storage``): visitors who
    never start do not hold a plan. The list returned is the first plan's pages, of which only the first is
    ever shown before the reservation.
    """
    items = plans["plans"]
    if not items or not items[0]["pages"]:
        return None
    first = items[0]["pages"][0]
    if any(not p["pages"] or p["pages"][0] != first for p in items):
        return None
    return items[0]["pages"]


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
    missing = missing_derived(study.manifest)
    if missing:
        raise StudyDefinitionError(f"{len(missing)} derived clip(s) (audio-mismatched or video-only, e.g. "
                                   f"{missing[0]}) are missing or older than their sources; run `evalsuite study "
                                   "build` again", path=study.manifest.root)
    return plans


def balance_report(plans: dict, study: Study) -> dict:
    """Counts that show the balance: per compared pair (with left/right), per MUSHRA slot, and per page
    position (``page_positions[(block, item, position)]``: trial pages, position among the session's trial
    pages of the block, checks not counted)."""
    by_file = study.manifest.by_file()
    counts: dict = {"pairs": Counter(), "mushra_slots": Counter(), "page_positions": Counter()}
    for plan in plans["plans"]:
        position: Counter = Counter()
        for p in plan["pages"]:
            if p.get("training") or not get_kind(p["type"]).block:
                continue
            kind = get_block_kind(p["type"])
            kind.balance(p, by_file, counts)
            if not p.get("check"):
                counts["page_positions"][(p["block"], kind.order_item(p, by_file), position[p["block"]])] += 1
                position[p["block"]] += 1
    return counts


def position_spread(counts: Counter) -> dict:
    """Per block: the largest distance of a count from its row's mean, over rows ``(block, item, ...)`` x the
    last key (a position or side): 0 is perfect balance, up to 1 is "equally often within one"."""
    rows: dict = {}
    for key, n in counts.items():
        rows.setdefault(key[:-1], {})[key[-1]] = n
    cols: dict = {}
    for key in counts:
        cols.setdefault(key[0], set()).add(key[-1])
    spread: dict = {}
    for row, values in rows.items():
        full = [values.get(c, 0) for c in cols[row[0]]]
        mean = sum(full) / len(full)
        spread[row[0]] = max(spread.get(row[0], 0.0), max(abs(v - mean) for v in full))
    return spread


SIZE_TOLERANCE = 0.10   # files of one page may differ by this share of the smallest before build warns


def size_spread(plans: dict, study: Study) -> list[dict]:
    """Pages whose media files differ in size by more than :data:`SIZE_TOLERANCE` (``max / min - 1``): a
    participant watching the browser's network panel could tell the clips apart. One entry per page:
    ``plan, page, smallest, largest, ratio``; largest ratio first."""
    sizes: dict[str, int] = {}
    out = []
    for plan in plans["plans"]:
        for p in plan["pages"]:
            if not get_kind(p["type"]).block:
                continue
            kind = get_block_kind(p["type"])
            files = {f for k in range(kind.n_slots(p)) if (f := kind.media(study, p, k).file)}
            if len(files) < 2:
                continue
            for f in files - sizes.keys():
                sizes[f] = (study.manifest.root / f).stat().st_size
            lo, hi = min(sizes[f] for f in files), max(sizes[f] for f in files)
            if hi > lo * (1 + SIZE_TOLERANCE):
                out.append({"plan": plan["key"], "page": p["page"], "smallest": lo, "largest": hi,
                            "ratio": hi / max(lo, 1)})
    return sorted(out, key=lambda r: -r["ratio"])
