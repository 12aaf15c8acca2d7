"""animlod.sorted_keys: np.unique and np.isin by sorting, as the sequence readers use them."""

from __future__ import annotations

import numpy as np

from animlod.sorted_keys import among, distinct


def test_they_agree_with_numpy_on_random_keys():
    rng = np.random.default_rng(0)
    values, keys = rng.integers(0, 50, 200), rng.integers(0, 50, 70)
    np.testing.assert_array_equal(among(values, keys), np.isin(values, keys))
    np.testing.assert_array_equal(distinct(keys), np.unique(keys))


def test_no_keys_hold_no_value():
    assert among(np.array([1, 2]), np.array([], dtype=np.int64)).tolist() == [False, False]
    assert distinct(np.array([], dtype=np.int64)).size == 0
