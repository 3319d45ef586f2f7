"""One spelling of a face and of a list of rows (:func:`meshrepair.mesh.topology.least_first`,
:func:`meshrepair.mesh.topology.row_order`): what makes Triangle's input and Liepa's triangles
independent of the order the caller listed them in."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from meshrepair.mesh.topology import least_first, row_order

faces = st.integers(1, 30).flatmap(
    lambda t: st.lists(st.permutations(range(50)).map(lambda p: p[:3]), min_size=t, max_size=t))


@given(faces, st.integers(0, 2))
def test_least_first_is_one_spelling_of_each_oriented_face(F, shift):
    T = np.asarray(F, dtype=np.int64)
    L = least_first(T)
    assert (L[:, 0] == T.min(axis=1)).all()
    # a cyclic shift of the input rows gives the same spelling; the orientation is kept
    assert np.array_equal(least_first(np.roll(T, shift, axis=1)), L)
    flipped = least_first(T[:, ::-1])
    assert not (flipped == L).all(axis=1).any()
    assert np.array_equal(least_first(L), L)


@given(arrays(np.int64, st.tuples(st.integers(0, 40), st.integers(1, 4)),
              elements=st.integers(-5, 5)))
def test_row_order_sorts_rows_lexicographically(A):
    o = row_order(A)
    assert sorted(o.tolist()) == list(range(len(A)))
    rows = [tuple(r) for r in A[o].tolist()]
    assert rows == sorted(rows)


def test_row_order_of_no_rows():
    assert row_order(np.empty((0, 3), np.int64)).size == 0
