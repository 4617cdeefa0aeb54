"""Orders that do not confound: random per page and participant, seeded, balanced over the study.

Three orders of a rating block are drawn here (:func:`study_app.design.build_plans` applies them; the plans
store them and ``results.csv`` exports them as ``position_a``):

* **MUSHRA slot order** (:func:`latin_slot_orders`): the block's pages, counted over all sessions, come in
  cycles of ``n`` pages (``n`` = slots per page); each cycle is a random Latin square (the cyclic square with
  its rows, columns and symbols shuffled), so within every cycle each condition takes each slot exactly once,
  and over the study each condition is in each slot equally often within one. The order of one page is a
  random row, not a rotation of a fixed order.
* **Pairwise sides** (:func:`balanced_sides`): the occurrences of each comparison are shuffled and dealt
  left, right, left, ...; a comparison shown an odd number of times has one occurrence left over, and those
  are oriented along walks of the graph conditions x comparisons, so each comparison shows A left and right
  equally often within one and each condition is on each side equally often within one.
* **Page order** (:class:`PositionBalancer`): a session's pages are placed by a minimum-cost assignment
  (:func:`scipy.optimize.linear_sum_assignment`) against how often each item (a comparison, a MUSHRA
  segment, a Likert condition) already took each position in earlier sessions, with a seeded random
  tie-break; items stay in each position equally often within about one over the study.
"""
from __future__ import annotations

import hashlib
import random
from collections import defaultdict
from collections.abc import Hashable, Sequence

import numpy as np

__all__ = ["order_rng", "latin_slot_orders", "balanced_sides", "PositionBalancer", "MAX_ASSIGNMENT"]

# Blocks with more pages than this per session are ordered at random (an assignment per session would grow
# as pages**3; real blocks have a few dozen pages).
MAX_ASSIGNMENT = 100


def order_rng(seed: int, *parts: object) -> random.Random:
    """A generator for one order decision, seeded from the study's ``seed`` and ``parts`` (block id, ...)."""
    text = "|".join(["evalsuite-order", str(seed), *map(str, parts)])
    return random.Random(int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big"))


def latin_slot_orders(rng: random.Random, n_pages: int, n_slots: int) -> list[list[int]]:
    """Slot orders of ``n_pages`` pages of ``n_slots`` slots: ``orders[g][p]`` is the index (in the block's
    own slot list) shown at position ``p`` of page ``g``.

    Cycle ``c`` (pages ``c*n .. c*n + n - 1``, ``n = n_slots``) is the square ``M[r][p] = Y[(R[r] + C[p]) mod n]``
    with random permutations ``R`` (rows), ``C`` (columns) and ``Y`` (symbols): a Latin square, so each index
    is at each position once per cycle.
    """
    n = n_slots
    orders: list[list[int]] = []
    while len(orders) < n_pages:
        rows, cols, symbols = (rng.sample(range(n), n) for _ in range(3))
        orders.extend([symbols[(rows[r] + cols[p]) % n] for p in range(n)] for r in range(n))
    return orders[:n_pages]


def balanced_sides(rng: random.Random, items: Sequence[tuple[str, str]]) -> list[bool]:
    """Whether A goes left, for each page showing comparison ``items[i] = (A, B)``.

    Each comparison's occurrences are shuffled and dealt left/right alternately; the one left over by a
    comparison shown an odd number of times is an edge A-B, and the edges are oriented along walks (starting
    at a condition with an odd number of edges left while there is one), which leaves every condition with
    as many left as right sides within one.
    """
    left = [True] * len(items)
    by_item: dict[tuple[str, str], list[int]] = defaultdict(list)
    for i, item in enumerate(items):
        by_item[item].append(i)
    leftover: list[tuple[int, str, str]] = []
    for item in sorted(by_item):
        idx = by_item[item]
        rng.shuffle(idx)
        for j, i in enumerate(idx):
            left[i] = j % 2 == 0
        if len(idx) % 2:
            leftover.append((idx[-1], item[0], item[1]))
    for i, a_on_left in _orient(rng, leftover).items():
        left[i] = a_on_left
    return left


def _orient(rng: random.Random, edges: list[tuple[int, str, str]]) -> dict[int, bool]:
    """Orient edges ``(key, a, b)`` so that every vertex has out- and in-degree within one of each other;
    returns key -> True when oriented a -> b (a on the left)."""
    adj: dict[str, list[int]] = defaultdict(list)
    for e, (_, a, b) in enumerate(edges):
        adj[a].append(e)
        adj[b].append(e)
    for v in adj:
        rng.shuffle(adj[v])
    degree = {v: len(es) for v, es in adj.items()}
    used = [False] * len(edges)
    out: dict[int, bool] = {}
    vertices = sorted(adj)
    while True:
        live = [v for v in vertices if degree[v]]
        if not live:
            return out
        odd = [v for v in live if degree[v] % 2]
        x = rng.choice(odd or live)
        while degree[x]:
            e = adj[x].pop()
            if used[e]:
                continue
            used[e] = True
            key, a, b = edges[e]
            y = b if x == a else a
            degree[x] -= 1
            degree[y] -= 1
            out[key] = x == a
            x = y


class PositionBalancer:
    """Places each session's pages of one block so that items take every position about equally often.

    ``arrange(items)`` returns the page indices in the order to show them. The cost of putting item ``i`` at
    position ``q`` is ``counts[i, q]`` plus a large penalty when that count would exceed the item's share
    ``(seen_i + 1) / k`` by more than zero, plus a seeded random tie-break below 0.001.
    """

    def __init__(self, n_positions: int, rng: random.Random):
        self.k = n_positions
        self.rng = np.random.default_rng(rng.getrandbits(63))
        self.counts: dict[Hashable, np.ndarray] = {}

    def arrange(self, items: Sequence[Hashable]) -> list[int]:
        k = len(items)
        if k != self.k:
            raise ValueError(f"expected {self.k} pages, got {k}")
        if k > MAX_ASSIGNMENT:
            order = list(self.rng.permutation(k))
        else:
            rows = np.array([self.counts.get(it, np.zeros(k)) for it in items])       # (k, k)
            share = (rows.sum(axis=1, keepdims=True) + 1) / k
            cost = rows + 1000.0 * np.maximum(rows + 1 - share, 0) ** 3 + self.rng.random((k, k)) * 1e-3
            from scipy.optimize import linear_sum_assignment  # here: 0.5 s of every app start otherwise

            pages, positions = linear_sum_assignment(cost)
            order = [0] * k
            for j, q in zip(pages, positions):
                order[int(q)] = int(j)
        for q, j in enumerate(order):
            self.counts.setdefault(items[j], np.zeros(k))[q] += 1
        return [int(j) for j in order]
