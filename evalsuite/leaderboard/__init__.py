"""The GENEA Leaderboard: its objective metrics and submission checks (``evalsuite validate-submission``)."""
