"""The body's coefficient tables: ``_table_coefficients`` searches the shared incidence column once and
interpolates the drag, lift and moment tables with ``table_lookup``'s arithmetic — so it must return exactly
what three separate ``table_lookup`` calls return (bit for bit, in one process), including the end values held
outside the table and the fore–aft fold for reverse flow (|θ| > 90° beyond a table that stops at ±90°)."""
from __future__ import annotations

import numpy as np
import pytest

from towenv.core import kernels as K


def _three_lookups(theta, inc, cd, cl, cm, n):
    """The previous form: one search per table, the lift's sign flipped on the fold."""
    if abs(theta) > 90.0 and (theta > inc[n - 1] or theta < inc[0]) and inc[n - 1] <= 90.0 and inc[0] >= -90.0:
        tf = 180.0 - abs(theta)
        if theta < 0.0:
            tf = -tf
        return (K.table_lookup(tf, inc, cd, n), -K.table_lookup(tf, inc, cl, n), K.table_lookup(tf, inc, cm, n))
    return K.table_lookup(theta, inc, cd, n), K.table_lookup(theta, inc, cl, n), K.table_lookup(theta, inc, cm, n)


def _tables(rng, lo, hi, n, pad):
    inc = np.sort(rng.uniform(lo, hi, n))
    inc[0], inc[-1] = lo, hi
    cols = [rng.normal(size=n) for _ in range(3)]
    # tables are stored padded to a common length (btab rows): entries past n must not be read
    return [np.concatenate([c, np.full(pad, np.nan)]) for c in (inc, *cols)]


@pytest.mark.parametrize("lo, hi", [(-90.0, 90.0), (-30.0, 45.0), (-180.0, 180.0), (0.0, 90.0)])
def test_one_search_equals_three_lookups_bit_for_bit(lo, hi):
    rng = np.random.default_rng(int(hi - lo))
    n = 9
    inc, cd, cl, cm = _tables(rng, lo, hi, n, pad=4)
    thetas = np.concatenate([rng.uniform(-200.0, 200.0, 400), inc[:n], [-180.0, -90.0, -0.0, 0.0, 90.0, 180.0,
                                                                        lo - 1e-9, hi + 1e-9, 95.0, -135.0]])
    folded = 0
    for th in thetas:
        got = K._table_coefficients(float(th), inc, cd, cl, cm, n)
        want = _three_lookups(float(th), inc, cd, cl, cm, n)
        assert np.array_equal(np.array(got), np.array(want)), (th, got, want)
        assert all(np.isfinite(got))
        folded += abs(th) > 90.0 and (th > inc[n - 1] or th < inc[0]) and hi <= 90.0 and lo >= -90.0
    if hi <= 90.0 and lo >= -90.0:
        assert folded > 50            # the fold is exercised
