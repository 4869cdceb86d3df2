"""How a sweep's samples are cut into Dask tasks (spacecraft/sweep/execute.py: batch_size,
batch_bounds): every sample once, in order, and the last round of tasks in smaller batches."""

import math

import pytest

from spacecraft.sweep.execute import batch_bounds, batch_size


@pytest.mark.parametrize("n_todo", [0, 1, 7, 100, 1001, 10_000])
@pytest.mark.parametrize("size", [1, 3, 87, 250])
@pytest.mark.parametrize("n_workers", [1, 2, 5])
@pytest.mark.parametrize("tail", [True, False])
def test_the_batches_cover_every_sample_once_in_order(n_todo, size, n_workers, tail):
    bounds = batch_bounds(n_todo, size, n_workers, tail=tail)
    assert bounds[0] == 0 and bounds[-1] == n_todo
    lengths = [b - a for a, b in zip(bounds[:-1], bounds[1:])]
    assert all(0 < k <= size for k in lengths)
    if not tail or n_workers == 1:
        # fixed batches: all of ``size`` but the last
        assert all(k == size for k in lengths[:-1])
    elif size > 1:
        # the last n_workers x size samples in batches of at most a quarter of a batch
        start = max(0, n_todo - n_workers * size)
        for a, b in zip(bounds[:-1], bounds[1:]):
            assert b - a <= (math.ceil(size / 4) if a >= start else size)


def test_a_ten_thousand_sample_sweep_ends_in_quarter_batches():
    bounds = batch_bounds(10_000, 80, 2)
    lengths = [b - a for a, b in zip(bounds[:-1], bounds[1:])]
    assert lengths[:123] == [80] * 123          # 9840 samples in whole batches
    assert lengths[123:] == [20] * 8            # the last 2 x 80 in quarters
    assert sum(lengths) == 10_000


def test_batch_size_keeps_a_task_near_its_target_and_the_load_balanced():
    assert batch_size(0.02, 10_000, 2) == 100          # 2 s of 20 ms samples
    assert batch_size(0.02, 200, 2) == 25               # a quarter of a worker's share
    assert batch_size(10.0, 5, 2) == 1                  # at least one sample
