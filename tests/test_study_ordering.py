"""Orders that do not confound (issue 37): MUSHRA slot orders, pairwise sides and page positions are random
per page and participant, seeded, and balanced over all plans of a study (each within one of equal)."""
from __future__ import annotations

import random
from collections import Counter

import pytest
import study_helpers as h
import yaml

from study_app.definition import load_study
from study_app.design import balance_report, build_plans, position_spread
from study_app.ordering import PositionBalancer, balanced_sides, latin_slot_orders


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    f = tmp_path_factory.mktemp("ordering")
    h.make_study(f)
    return f


def _study(folder, sessions, mutate=lambda d: None, name="order.yaml"):
    data = yaml.safe_load((folder / "study.yaml").read_text())
    data["sessions"] = sessions
    mutate(data)
    (folder / name).write_text(yaml.safe_dump(data))
    return load_study(folder / name)


def _positions(study, plans):
    """Counts taken from the plans themselves: (block, condition, slot), (block, A, B, side), (condition, side),
    (block, item, page position)."""
    by_file = study.manifest.by_file()
    slots, sides, cond_sides, pages = Counter(), Counter(), Counter(), Counter()
    for plan in plans["plans"]:
        at = Counter()
        for p in plan["pages"]:
            if "block" not in p or p["training"] or p["check"]:
                continue
            if p["type"] == "mushra":
                for k, f in enumerate(p["slots"]):
                    slots[(p["block"], by_file[f].condition, k)] += 1
                item = p["segment"]
            elif p["type"] == "pairwise":
                a, b = by_file[p["a"]], by_file[p["b"]]
                a_name, b_name = a.condition, b.condition + (":mismatched" if b.mismatched else "")
                other = "right" if p["position_a"] == "left" else "left"
                sides[(p["block"], a_name, b_name, p["position_a"])] += 1
                cond_sides[(p["block"], a_name, p["position_a"])] += 1
                cond_sides[(p["block"], b_name, other)] += 1
                item = (a_name, b_name)
            else:
                item = by_file[p["stimulus"]].condition
            pages[(p["block"], item, at[p["block"]])] += 1
            at[p["block"]] += 1
    return slots, sides, cond_sides, pages


def _within_one(counts: Counter) -> None:
    for block, spread in position_spread(counts).items():
        assert spread <= 1, (block, spread, counts)


@pytest.mark.parametrize("sessions", [6, 13, 60])
def test_every_position_is_taken_equally_often_within_one(folder, sessions):
    study = _study(folder, sessions)
    plans = build_plans(study)
    slots, sides, cond_sides, pages = _positions(study, plans)
    for counts in (slots, sides, cond_sides, pages):
        assert counts
        _within_one(counts)
    report = balance_report(plans, study)
    assert report["page_positions"] == pages                  # the report build prints counts the same
    assert sum(report["mushra_slots"].values()) == sum(slots.values())


def test_mushra_orders_are_random_per_page_not_a_rotation(folder):
    study = _study(folder, 60)
    orders = Counter()
    for plan in build_plans(study)["plans"]:
        for p in plan["pages"]:
            if p.get("block") == "ratings" and not p["training"] and not p["check"]:
                orders[tuple(p["roles"].index("reference") if r == "reference" else
                             study.manifest.by_file()[f].condition for r, f in zip(p["roles"], p["slots"]))] += 1
    assert len(orders) == 6                                     # all 3! orders; a rotation gives only 3


def test_orders_are_seeded_and_stored(folder):
    study = _study(folder, 12)
    plans = build_plans(study)
    assert build_plans(study) == plans
    other = build_plans(_study(folder, 12, lambda d: d.update(seed=11), "seed11.yaml"))
    mine = [[p.get("slots") or p.get("position_a") for p in plan["pages"]] for plan in plans["plans"]]
    theirs = [[p.get("slots") or p.get("position_a") for p in plan["pages"]] for plan in other["plans"]]
    assert mine != theirs


def test_pairwise_sides_are_random_within_a_session(folder):
    study = _study(folder, 60, lambda d: next(p for p in d["pages"] if p["id"] == "hl").update(pages=3),
                   "sides.yaml")
    patterns = Counter()
    for plan in build_plans(study)["plans"]:
        patterns[tuple(p["position_a"] for p in plan["pages"] if p.get("block") == "hl" and not p["check"]
                       and not p["training"])] += 1
    assert len(patterns) >= 6                                   # not one fixed left/right pattern


def test_the_demo_study_is_balanced(tmp_path):
    from study_app.demo import _stimuli, study_definition

    target = tmp_path / "study"
    target.mkdir()
    manifest = _stimuli(tmp_path, target, lambda *a: None)
    (target / "study.yaml").write_text(yaml.safe_dump(study_definition(manifest, target), sort_keys=False))
    study = load_study(target / "study.yaml")
    for sessions in (study.sessions, 17):
        study.sessions = sessions
        for counts in _positions(study, build_plans(study)):
            assert counts
            _within_one(counts)


def test_latin_slot_orders_balance_every_cycle():
    rng = random.Random(1)
    orders = latin_slot_orders(rng, 20, 4)
    assert all(sorted(o) == [0, 1, 2, 3] for o in orders)
    for cycle in range(5):
        square = orders[4 * cycle:4 * cycle + 4]
        for pos in range(4):
            assert sorted(o[pos] for o in square) == [0, 1, 2, 3]
    assert len({tuple(o) for o in orders}) > 4


@pytest.mark.parametrize("seed", range(20))
def test_balanced_sides_on_random_designs(seed):
    rng = random.Random(seed)
    conds = [f"c{i}" for i in range(rng.randint(2, 7))]
    pairs = [(a, b) for i, a in enumerate(conds) for b in conds[i + 1:]]
    items = [rng.choice(pairs) for _ in range(rng.randint(1, 60))]
    left = balanced_sides(random.Random(seed), items)
    per_pair, per_cond = Counter(), Counter()
    for (a, b), a_left in zip(items, left):
        per_pair[(a, b, a_left)] += 1
        per_cond[(a, a_left)] += 1
        per_cond[(b, not a_left)] += 1
    for (a, b) in set(items):
        assert abs(per_pair[(a, b, True)] - per_pair[(a, b, False)]) <= 1
    for c in conds:
        assert abs(per_cond[(c, True)] - per_cond[(c, False)]) <= 1


def test_position_balancer_keeps_items_within_one():
    for k, n, sessions in ((4, 6, 30), (3, 3, 10), (5, 8, 24), (2, 7, 21)):
        bal = PositionBalancer(k, random.Random(0))
        counts = Counter()
        for s in range(sessions):
            items = [(s * k + j) % n for j in range(k)]
            for q, j in enumerate(bal.arrange(items)):
                counts[("b", items[j], q)] += 1
        _within_one(counts)
