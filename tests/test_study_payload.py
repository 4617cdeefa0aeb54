"""Checks of what a participant's browser sends (study_app.payload)."""
from __future__ import annotations

import pytest

from study_app.payload import PayloadError, int_in


def test_payload_errors_are_value_errors_with_the_field():
    with pytest.raises(PayloadError, match="answer.energy: expected an integer in 1..3"):
        int_in(True, 1, 3, "answer.energy")
