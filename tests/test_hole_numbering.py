"""One hole numbering (issue 27, item 4): ``fill --list``, ``fill --holes``, ``complete
--hole``, ``--frame-hole`` and the reports all number the simple loops of
:func:`meshrepair.holes.find_holes` (pinched loops split, longest first)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from meshrepair.complete.api import complete
from meshrepair.errors import MeshRepairError
from meshrepair.fill import fill_holes
from meshrepair.holes import find_holes
from meshrepair.mesh.topology import boundary_loops
from meshrepair.render.framing import frame_hole

from .conftest import grid, shared_mesh


def pinched_sheet():
    """A 14 x 14 sheet with two square holes touching at one vertex (one pinched boundary
    loop: two holes) and a third hole apart: 3 boundary loops, 4 holes."""
    V, F = grid(14)
    c = V[F].mean(axis=1)

    def box(x0, x1, y0, y1):
        return (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)

    drop = box(3, 6, 3, 6) | box(6, 8, 6, 8) | box(9, 11, 2, 5)
    F = F[~drop]
    used = np.unique(F)
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    return V[used], m[F]


def _listed(text):
    return {int(k): bool(p) for k, p in re.findall(r"hole (\d+): .*?(, pinched)?$", text, re.M)}


def _agree(V, F, tmp_path, capsys):
    from meshrepair.cli import main
    from meshrepair.io import write_mesh

    holes = find_holes(V, F)
    src = tmp_path / "in.ply"
    write_mesh(src, V, F)
    assert main(["fill", str(src), "--list"]) == 0
    listed = _listed(capsys.readouterr().out)
    assert listed == {h.index: h.pinched for h in holes}
    for h in holes:
        # --frame-hole
        fr = frame_hole(V, F, h.index)
        assert fr.name == f"hole {h.index}"
        assert np.allclose(fr.center, frame_hole(V, F, h.index).center)
        # complete --hole: a pinched hole is refused as pinched, the others get past the hole
        # (and stop at the template, which is invalid on purpose)
        with pytest.raises(MeshRepairError) as exc:
            complete(V, F, template="not-a-template", hole=h.index)
        assert ("pinched" in str(exc.value)) == h.pinched, str(exc.value)
        if h.pinched:
            assert f"hole {h.index} is pinched" in str(exc.value)
    with pytest.raises(MeshRepairError, match=f"{len(holes)} holes"):
        complete(V, F, template="not-a-template", hole=len(holes))
    # fill --holes k: the report of hole k is the loop find_holes numbers k
    k = len(holes) - 1
    res = fill_holes(V, F, holes=[k])
    rep = {r.index: r for r in res.holes}
    assert rep[k].status == "filled"
    assert sorted(rep[k].loop.tolist()) == sorted(holes[k].vertices.tolist())
    assert all(r.status == "skipped" for i, r in rep.items() if i != k)
    return holes


def test_one_numbering_on_a_sheet_with_pinched_loops(tmp_path, capsys):
    V, F = pinched_sheet()
    assert len(boundary_loops(F, len(V))) == 3
    holes = _agree(V, F, tmp_path, capsys)
    assert len(holes) == 4 and sum(h.pinched for h in holes) == 2


@pytest.mark.shared
def test_one_numbering_on_a_real_scan_with_pinched_loops(tmp_path, capsys):
    V, F = shared_mesh("kinect_pyramid.ply")
    holes = _agree(V, F, tmp_path, capsys)
    assert len(holes) > len(boundary_loops(F, len(V))) and any(h.pinched for h in holes)
