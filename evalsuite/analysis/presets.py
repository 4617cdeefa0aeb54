"""Named sets of analysis options that reproduce a published procedure (``--preset``).

``leaderboard`` -- the GENEA Leaderboard's analysis (genea-workshop/leaderboard-statistical-analysis):

- ranking: unpenalised Bradley-Terry maximum likelihood (``elo_prior = 0``) on the Elo scale
  ``400 log10 p + 1000`` with the mean at 1000 (their ``SCALE=400, BASE=10, INIT_RATING=1000``;
  their logistic regression starts at zero, which keeps the mean there), weights strong win 4,
  weak win 2, tie 1 each way;
- CIs: 10,000 bootstrap rounds over participants, seed 42, drawn exactly as their
  ``np.random.seed(42)`` / ``np.random.choice(users, len(users))`` does (``bootstrap_sampler =
  "leaderboard"``), 2.5 / 97.5 percentiles; the median of the rounds is in ``boot_median`` (the
  value their figure plots);
- exclusions: a session failing any attention check is dropped (``attention_fails = 1``);
- preference shares: ties count half a win each way (``tie_policy = "half"``).

``mushra-itu`` -- a listening test by ITU-R BS.1534-3 (MUSHRA): its post-screening of assessors
(exclude a session that rates the hidden reference below 90 on more than 15 % of its items). Off
otherwise: in gesture studies natural motion is no ceiling and participants are not told it is
there (``analyze`` says how many sessions the rule would exclude).

Options given explicitly on the command line override the preset's values.
"""
from __future__ import annotations

PRESETS: dict[str, dict] = {
    "leaderboard": {"elo_prior": 0.0, "n_boot": 10_000, "seed": 42, "bootstrap_sampler": "leaderboard",
                    "attention_fails": 1, "tie_policy": "half"},
    "mushra-itu": {"mushra_screening": True},
}


def preset_values(name: str | None) -> dict:
    """The option values of preset ``name`` (``{}`` for None)."""
    if name is None:
        return {}
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; expected one of {', '.join(PRESETS)}")
    return dict(PRESETS[name])
