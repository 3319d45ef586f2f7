"""inpaint never closes what the user did not mark (issue 27, item 3): a region reaching an open
border is refused by default, or filled with the border kept (``keep_border=True``)."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.fill import inpaint
from meshrepair.mesh.geometry import mean_edge_length
from meshrepair.mesh.topology import boundary_loops, edge_topology

from .conftest import grid, shared_mesh


def _border_vertices(F, nV):
    t = edge_topology(F, nV)
    out = np.zeros(nV, bool)
    out[t.edges[t.boundary].ravel()] = True
    return out


def _check(V, F, centre, radius):
    on0 = _border_vertices(F, len(V))
    region = ("sphere", centre, radius)
    safe = inpaint(V, F, region)
    # default: the merged loop is refused, nothing is closed: the output's boundary holds every
    # kept input border vertex, and no new face touches the border
    assert safe.n_filled == 0 and safe.n_skipped >= 1
    assert any("open border" in h.reason and "keep_border" in h.reason for h in safe.holes)
    assert "refused" in safe.params["border"]
    kept = safe.vertex_map[on0]
    on1 = _border_vertices(safe.F, len(safe.V))
    assert on1[kept[kept >= 0]].all()
    # keep_border: the region is filled, the border stays open and keeps all its vertices
    res = inpaint(V, F, region, keep_border=True)
    assert res.n_filled >= 1 and res.n_skipped == 0, res.summary()
    assert "kept" in res.params["border"]
    assert all("border left open" in h.note for h in res.holes if h.status == "filled")
    m = res.vertex_map[on0]
    assert (m >= 0).all()  # no border vertex removed
    on2 = _border_vertices(res.F, len(res.V))
    assert on2[m].all()
    assert len(boundary_loops(res.F, len(res.V))) == len(boundary_loops(F, len(V)))
    assert not np.isin(res.new_vertices, np.flatnonzero(on2)).any()
    return res


def test_inpaint_next_to_the_border_of_a_small_open_mesh():
    V, F = grid(24, z=lambda x, y: 0.05 * (x - 12) ** 2)
    _check(V, F, (0.0, 11.0, float(V[0, 2])), 3.5)


def test_inpaint_away_from_the_border_fills_and_says_so():
    V, F = grid(24)
    res = inpaint(V, F, ("sphere", (12.0, 12.0, 0.0), 3.0))
    assert res.n_filled == 1 and "does not reach" in res.params["border"]
    assert len(boundary_loops(res.F, len(res.V))) == 1


def test_keep_border_option_checked():
    from meshrepair.errors import MeshRepairError

    V, F = grid(8)
    with pytest.raises(MeshRepairError, match="keep_border"):
        inpaint(V, F, [27], keep_border="yes")


@pytest.mark.shared
@pytest.mark.parametrize("name", ["nicolo.ply", "kinect_pyramid.ply"])
def test_inpaint_near_the_open_border_of_a_real_scan(name):
    V, F = shared_mesh(name)
    loop = max(boundary_loops(F, len(V)), key=len)
    _check(V, F, tuple(V[loop[len(loop) // 3]]), 6.0 * mean_edge_length(V, F))


def test_cli_inpaint_keep_border(tmp_path, capsys):
    from meshrepair.cli import main
    from meshrepair.io import read_mesh, write_mesh

    V, F = grid(24, z=lambda x, y: 0.05 * (x - 12) ** 2)
    src = tmp_path / "in.ply"
    write_mesh(src, V, F)
    sphere = f"0,11,{V[0, 2]},3.5"
    assert main(["inpaint", str(src), str(tmp_path / "a.ply"), "--sphere", sphere, "-q"]) == 0
    out = capsys.readouterr().out
    assert "open border" in out and "--keep-border" in out and "0 filled" in out
    assert main(["inpaint", str(src), str(tmp_path / "b.ply"), "--sphere", sphere, "-q",
                 "--keep-border"]) == 0
    out = capsys.readouterr().out
    assert "1 filled" in out and "border left open" in out
    m = read_mesh(tmp_path / "b.ply")
    assert len(boundary_loops(m.F, len(m.V))) == 1
