"""The scoring options (:mod:`evalsuite.metrics.options`): one frozen ScoreOptions with every choice of a run,
and the per-sequence ScoreTask the workers receive."""
from __future__ import annotations

import dataclasses
import pathlib
import pickle

import pytest

from evalsuite.errors import InputError
from evalsuite.metrics.options import ScoreOptions, ScoreSetup, ScoreTask, parse_bins


def test_defaults_are_those_of_the_score_command():
    opts = ScoreOptions()
    assert (opts.joints, opts.metrics, opts.convention, opts.bootstrap, opts.jobs) == (None, None, "default", 0, 1)
    assert opts.groups == ("wrists", "forearms") and opts.sigma == 0.1 and opts.progress and opts.figures
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.bootstrap = 5


def test_lists_become_tuples_and_bins_strings_are_parsed_so_equal_choices_give_equal_options():
    a = ScoreOptions(joints=["b_l_wrist", "b_r_wrist"], metrics=["kinematics"], groups=["wrists"],
                     speed_bins="250:2.5")
    b = ScoreOptions(joints=("b_l_wrist", "b_r_wrist"), metrics=("kinematics",), groups=("wrists",),
                     speed_bins=(250.0, 2.5))
    assert a == b and hash(a) == hash(b)
    assert a.joints == ("b_l_wrist", "b_r_wrist") and a.speed_bins == (250.0, 2.5)
    assert a.bins("speed") == (250.0, 2.5) and a.bins("acceleration") is None
    assert ScoreOptions(joints="genea2020_upper").joints == "genea2020_upper"   # a preset name stays a name


def test_bad_bins_are_a_one_line_input_error():
    with pytest.raises(InputError, match=r"bins: expected bins as MAX:WIDTH \(e.g. 250:2.5\), got '250'"):
        ScoreOptions(acceleration_bins="250")
    assert parse_bins(None) is None and parse_bins("10:0.5") == (10.0, 0.5)


def test_replace_changes_options_and_names_the_closest_option_of_a_misspelt_one():
    opts = ScoreOptions(seed=3)
    assert opts.replace() is opts
    changed = opts.replace(bootstrap=100, metrics=["cca"])
    assert (changed.bootstrap, changed.seed, changed.metrics) == (100, 3, ("cca",))
    with pytest.raises(TypeError, match=r"unknown scoring option 'bootstap'.*Did you mean 'bootstrap'\?"):
        opts.replace(bootstap=100)


def test_a_task_pickles_for_the_process_pool_and_dask():
    setup = ScoreSetup(joints=["a", "b"], metrics=["speed"])
    task = ScoreTask("seq1", (("natural", pathlib.Path("n/seq1.bvh")), ("sys", pathlib.Path("s/seq1.bvh"))),
                     None, setup)
    again = pickle.loads(pickle.dumps(task))
    assert again == task and again.entries[1] == ("sys", pathlib.Path("s/seq1.bvh"))
    assert again.describe() == "sequence 'seq1'"
