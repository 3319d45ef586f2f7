"""Kinked crease pairs (``holes.creases._kinked_pairs``): two leftover crease ends of one crease
that bends where it meets the loop are joined by a straight route; never through the
surround, never two ends of one chain."""

from __future__ import annotations

import numpy as np

from meshrepair.holes.creases import (
    KINKED_PAIR_TURN,
    PAIR_MAX_TURN,
    CreaseEnd,
    _kinked_pairs,
    route_creases,
)


def _circle(k=16):
    t = 2 * np.pi * np.arange(k) / k
    return np.c_[np.cos(t), np.sin(t), np.zeros(k)]


def _end(pos, direction, chain_id=-1, convex=True, angle=70.0):
    d = np.asarray(direction, float)
    return CreaseEnd(pos=pos, vertex=pos, direction=d / np.linalg.norm(d), angle=angle,
                     convex=convex, chain_id=chain_id)


def _dir_at(angle_deg, towards):
    """Unit vector at ``angle_deg`` from ``towards`` (in the xy-plane, turned towards +y)."""
    a = np.arctan2(towards[1], towards[0]) + np.radians(angle_deg)
    return np.array([np.cos(a), np.sin(a), 0.0])


def test_kinked_pair_routed_straight():
    """Ends at opposite loop vertices, each 50° off the chord (beyond PAIR_MAX_TURN, within
    KINKED_PAIR_TURN), turned to opposite sides (their lines do not meet): one straight route
    between them."""
    assert PAIR_MAX_TURN < 50.0 < KINKED_PAIR_TURN
    V = _circle()
    ends = [_end(0, _dir_at(50.0, (-1.0, 0.0))), _end(8, _dir_at(50.0, (1.0, 0.0)))]
    r = route_creases(V, np.arange(16), ends)
    assert r is not None and r.kinds == ["kinked"]
    assert sorted(r.segments[0].tolist()) == [0, 8]
    mid = r.evaluate(0, np.array([0.5]))[0]
    assert np.allclose(mid, 0.0, atol=1e-12)  # straight: the chord's midpoint


def test_kinked_pair_refused_beyond_turn_or_convexity():
    V = _circle()
    too_far = [_end(0, _dir_at(70.0, (-1.0, 0.0))), _end(8, _dir_at(70.0, (1.0, 0.0)))]
    assert route_creases(V, np.arange(16), too_far) is None
    mixed = [_end(0, _dir_at(50.0, (-1.0, 0.0))),
             _end(8, _dir_at(50.0, (1.0, 0.0)), convex=False)]
    assert route_creases(V, np.arange(16), mixed) is None
    gap = [_end(0, _dir_at(50.0, (-1.0, 0.0)), angle=40.0),
           _end(8, _dir_at(50.0, (1.0, 0.0)), angle=80.0)]
    assert route_creases(V, np.arange(16), gap) is None


def test_kinked_pair_refused_when_the_lines_meet_ahead():
    """Both ends turned 50° to the same side: their lines meet in front of both, two creases of
    a corner whose third crease was not found (fandisk creases r=16), not one kinked crease."""
    from meshrepair.holes.creases import _lines_meet_ahead

    V = _circle()
    a, b = _dir_at(50.0, (-1.0, 0.0)), _dir_at(-50.0, (1.0, 0.0))
    assert _lines_meet_ahead(V[0], a, V[8], b)
    assert not _lines_meet_ahead(V[0], a, V[8], _dir_at(50.0, (1.0, 0.0)))
    assert route_creases(V, np.arange(16), [_end(0, a), _end(8, b)]) is None


def test_kinked_pair_one_end_per_chain():
    """The loop cuts one crease at two neighbouring vertices (same chain): one of them is paired
    with the third end (both would be valid partners), the other is then left alone, and the
    two are never paired with each other."""
    V = _circle()
    ends = [_end(0, _dir_at(50.0, (-1.0, 0.0))),
            _end(8, _dir_at(45.0, (1.0, 0.0)), chain_id=7),
            _end(9, _dir_at(50.0, V[0] - V[9]), chain_id=7)]
    pairs = _kinked_pairs(V, ends)
    assert len(pairs) == 1 and pairs[0][0] == 0 and pairs[0][1] in (1, 2)
    for j in (1, 2):  # each alone would be paired with end 0
        assert _kinked_pairs(V, [ends[0], ends[j]]) == [(0, 1)]
    twins = [_end(8, _dir_at(0.0, V[9] - V[8]), chain_id=7),
             _end(9, _dir_at(0.0, V[8] - V[9]), chain_id=7)]
    assert _kinked_pairs(V, twins) == []


def test_kinked_pair_not_through_the_surround():
    """A C-shaped loop: the chord between the two tips of the C passes outside the loop (over
    the surround), so the ends are not joined."""
    t = np.linspace(0.25 * np.pi, 1.75 * np.pi, 13)
    outer = np.c_[np.cos(t), np.sin(t)]
    inner = 0.5 * np.c_[np.cos(t[::-1]), np.sin(t[::-1])]
    P = np.r_[outer, inner]
    V = np.c_[P, np.zeros(len(P))]
    k = len(P)
    a, b = 0, 12  # the two outer tips of the C, the chord crossing its mouth
    s = V[b] - V[a]
    ends = [_end(a, _dir_at(40.0, s[:2])), _end(b, _dir_at(40.0, -s[:2]))]
    assert route_creases(V, np.arange(k), ends) is None
