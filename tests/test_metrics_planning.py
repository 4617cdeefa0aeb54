"""What `evalsuite score` is asked to compute: metric names resolved to families, with a useful error."""
from __future__ import annotations

import pytest

from evalsuite.errors import InputError, did_you_mean
from evalsuite.metrics.planning import resolve_metrics


def test_a_misspelt_metric_or_family_gets_the_closest_names_in_one_short_line():
    with pytest.raises(InputError, match=r"unknown metric 'jerkk'.*Did you mean 'jerk'\?") as exc:
        resolve_metrics("jerkk", audio=False)
    assert "\n" not in str(exc.value) and len(str(exc.value)) < 300
    with pytest.raises(InputError, match="Did you mean 'kinematics'"):
        resolve_metrics("kinematic", audio=False)


def test_did_you_mean_says_nothing_when_nothing_is_close():
    assert did_you_mean("zzz", ["jerk", "ape"]) == ""
    assert did_you_mean("ap", ["jerk", "ape"]) == ". Did you mean 'ape'?"


def test_issues_shared_by_conditions_are_printed_once_with_their_conditions():
    from evalsuite.metrics.report import grouped_issues

    issues = ["a: fd_g: 2 sequence(s) on a side", "a_b: fd_g: 2 sequence(s) on a side", "a: cca: not computed",
              "no audio for 3 sequences"]
    assert grouped_issues(issues, ["a", "a_b"]) == [
        "fd_g: 2 sequence(s) on a side (conditions a, a_b)", "a: cca: not computed", "no audio for 3 sequences"]
