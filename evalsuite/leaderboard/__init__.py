"""The GENEA Leaderboard: its objective metrics (``evalsuite score --preset genea-leaderboard``,
:func:`score_leaderboard`) and submission checks (``evalsuite validate-submission``)."""
from evalsuite.leaderboard.score import evaluate_leaderboard, score_leaderboard

__all__ = ["score_leaderboard", "evaluate_leaderboard"]
