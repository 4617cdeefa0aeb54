"""The exponential moving average of weights that the re-implementations may validate and keep (``ema``)."""
from __future__ import annotations

import pytest
import torch  # required by the test suite (.ci/run installs it), not skipped

from evalsuite.generators.weight_averaging import WeightAverage


def _net() -> torch.nn.Module:
    torch.manual_seed(0)
    return torch.nn.Sequential(torch.nn.Linear(3, 4), torch.nn.BatchNorm1d(4))


def test_decay_zero_is_the_network_itself():
    net = _net()
    avg = WeightAverage(net, 0.0)
    assert avg.module is net
    avg.update(net)  # a no-op
    assert avg.module is net


def test_the_average_follows_the_formula_for_weights_and_batch_norm_statistics():
    net = _net()
    avg = WeightAverage(net, 0.9)
    assert avg.module is not net
    w0 = net[0].weight.detach().clone()
    avg.update(net)  # the first update copies
    with torch.no_grad():
        net[0].weight.add_(1.0)
        net[1].running_mean.fill_(2.0)
    avg.update(net)
    torch.testing.assert_close(avg.module[0].weight, 0.9 * w0 + 0.1 * (w0 + 1.0))
    torch.testing.assert_close(avg.module[1].running_mean, torch.full((4,), 0.2))


@pytest.mark.parametrize("decay", [-0.1, 1.0])
def test_a_decay_outside_the_unit_interval_is_refused(decay):
    with pytest.raises(ValueError, match="decay"):
        WeightAverage(_net(), decay)
