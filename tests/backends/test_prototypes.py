"""The prototype store's host-side helpers."""

from __future__ import annotations

import numpy as np
import pytest

from ndpack.backends.prototypes import top_order


@pytest.mark.parametrize("k", [0, 1, 7, 100, 499, 500, 999, 1000])
def test_top_order_takes_the_largest_first_and_ties_by_lower_id(k):
    """The partial sort (a few of many) gives the whole sort's first ``k``, ties included."""
    rng = np.random.default_rng(k)
    ids = rng.permutation(5000)[:1000]  # any order, as a store may answer
    clearance = rng.choice([0.1, 0.2, 0.3, -np.inf], 1000) + np.where(rng.random(1000) < 0.5, 0.0, rng.random(1000))
    order = top_order(ids, clearance, k)
    np.testing.assert_array_equal(order, np.lexsort((ids, -clearance))[:k])
    assert len(order) == k


def test_largest_keeps_the_most_largest_and_their_ties():
    from ndpack.backends.prototypes import largest

    values = np.array([0.5, 0.1, 0.9, 0.5, 0.7, 0.5])
    assert largest(values, None).tolist() == [0, 1, 2, 3, 4, 5]
    assert largest(values, 6).tolist() == [0, 1, 2, 3, 4, 5]
    assert largest(values, 2).tolist() == [2, 4]
    assert largest(values, 3).tolist() == [0, 2, 3, 4, 5]  # the third largest's ties come along
    assert largest(values, 0).tolist() == []
