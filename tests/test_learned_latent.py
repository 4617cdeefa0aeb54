"""NSD and codebook diversity (Gesture2Vec) against analytic oracles."""
from __future__ import annotations

import numpy as np
import pytest
from learned_helpers import natural, trained
from scipy.spatial.distance import pdist

from evalsuite.errors import InputError
from evalsuite.learned.latent import (
    code_histogram,
    fit_codebook,
    hellinger,
    mean_pairwise_distance,
    nsd,
    perplexity,
    score_latent,
)


def test_nsd_of_latents_moving_at_constant_speed_on_a_line():
    # z_i = i v: n_k(i) = k |v|; the mean pairwise distance of N equally spaced points is |v| (N + 1) / 3.
    n, speed = 60, 0.7
    direction = np.random.default_rng(0).normal(size=32)
    z = np.arange(n)[:, None] * speed * direction / np.linalg.norm(direction)
    res = nsd([z], ks=(1, 2))
    assert res["mean_pairwise_distance"] == pytest.approx(speed * (n + 1) / 3)
    assert res["nsd_k1_raw"] == pytest.approx(speed)
    assert res["nsd_k2_raw"] == pytest.approx(2 * speed)
    assert res["nsd_k1"] == pytest.approx(3 / (n + 1))
    assert res["nsd_k2"] == pytest.approx(6 / (n + 1))
    assert res["nsd_k1_std"] == pytest.approx(0.0, abs=1e-12)
    assert res["n_neighbourhoods"] == n - 4  # i in [2, N-2), as the reference


def test_nsd_neighbours_never_cross_sequences_and_mean_distance_matches_pdist():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(10, 3)), rng.normal(size=(12, 3)) + 5
    res = nsd([a, b], ks=(1,))
    assert res["mean_pairwise_distance"] == pytest.approx(pdist(np.concatenate([a, b])).mean())
    expected = np.concatenate([0.5 * (np.linalg.norm(s[:-2] - s[1:-1], axis=1) + np.linalg.norm(s[2:] - s[1:-1], axis=1))
                               for s in (a, b)])
    assert res["nsd_k1_raw"] == pytest.approx(expected.mean())
    big = rng.normal(size=(3000, 4))
    assert mean_pairwise_distance(big, max_windows=5000) == pytest.approx(pdist(big).mean())
    with pytest.raises(InputError):
        nsd([rng.normal(size=(4, 3))], ks=(1, 2))


def test_hellinger_and_perplexity_oracles():
    assert hellinger([1, 2, 3], [2, 4, 6]) == pytest.approx(0.0, abs=1e-12)
    assert hellinger([1, 0, 0], [0, 3, 1]) == pytest.approx(1.0)
    assert perplexity(np.ones(16)) == pytest.approx(16.0, rel=1e-8)
    assert perplexity([5, 0, 0, 0]) == pytest.approx(1.0, rel=1e-8)


def test_codebook_is_seeded_and_finds_well_separated_clusters():
    rng = np.random.default_rng(2)
    centres = np.eye(4) * 20
    z = np.concatenate([c + rng.normal(size=(100, 4)) for c in centres])
    a = fit_codebook(z, 4, seed=7)
    np.testing.assert_array_equal(a, fit_codebook(z, 4, seed=7))
    hist = code_histogram(z, a)
    assert sorted(hist) == [100, 100, 100, 100]
    # A condition using only two of the four clusters, equally: Hellinger = sqrt(1 - 2 sqrt(1/4 * 1/2)).
    half = np.concatenate([centres[0] + rng.normal(size=(50, 4)), centres[1] + rng.normal(size=(50, 4))])
    assert hellinger(hist, code_histogram(half, a)) == pytest.approx(np.sqrt(1 - 2 * np.sqrt(0.25 * 0.5)))
    assert perplexity(code_histogram(half, a)) == pytest.approx(2.0, rel=1e-6)


def test_score_latent_rows_for_reference_and_conditions():
    model = trained()
    nat = natural()
    names = sorted(nat)
    ref = {n: nat[n] for n in names[:4]}
    static = {n: nat[n].with_positions(np.broadcast_to(nat[n].positions().mean(0), nat[n].positions().shape))
              for n in names[4:]}
    rows = score_latent(model, ref, {"natural": {n: nat[n] for n in names[4:]}, "static": static}, n_codes=8)
    table = {(r["condition"], r["metric"]): r["value"] for r in rows}
    assert table[("reference", "codebook_hellinger")] == 0.0
    # A static pose has identical latents in every window: zero neighbour distance, one code.
    assert table[("static", "codebook_perplexity")] == pytest.approx(1.0, rel=1e-6)
    assert table[("static", "codebook_hellinger")] > table[("natural", "codebook_hellinger")]
    assert all(np.isfinite(table[(c, f"nsd_k{k}")]) and table[(c, f"nsd_k{k}")] > 0
               for c in ("reference", "natural") for k in (1, 2))
    assert all(r["model_hash"] == model.content_hash for r in rows)
