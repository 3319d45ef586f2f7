"""Reading and writing what a mesh file holds besides V and F, format by format (the table of
docs/files.md), and the interpolation maths of meshrepair.mesh.attributes."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from meshrepair.io import MeshData, carry_attributes, read_mesh, write_mesh
from meshrepair.mesh.attributes import harmonic_extend, propagate_faces

SQUARE_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)


def _grid(n: int = 9):
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), \
        idx[1:, :-1].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


@pytest.mark.parametrize("method", ["biharmonic", "harmonic"])
def test_linear_field_is_reproduced_on_a_flat_patch(method):
    V, F = _grid()
    x = 0.3 + 2 * V[:, 0] - V[:, 1]
    known = (np.abs(V[:, :2] - 0.5) > 0.3).any(axis=1)  # a square hole of unknowns
    got = harmonic_extend(V, F, np.where(known, x, 0.0), known, method)
    assert (~known).sum() == 25
    np.testing.assert_allclose(got, x, atol=1e-10)


def test_harmonic_stays_in_the_border_range_and_biharmonic_is_clipped():
    V, F = _grid()
    known = (np.abs(V[:, :2] - 0.5) > 0.3).any(axis=1)
    vals = np.where(V[:, 0] > 0.5, 1.0, 0.0)
    for method in ("harmonic", "biharmonic"):
        got = harmonic_extend(V, F, vals, known, method)
        assert got.min() >= 0.0 and got.max() <= 1.0


def test_propagate_faces_takes_a_neighbours_value():
    V, F = _grid(5)
    known = np.ones(len(F), bool)
    known[[5, 6, 21]] = False
    src = propagate_faces(F, known)
    assert (src >= 0).all() and known[src].all()
    assert np.array_equal(src[known], np.flatnonzero(known))


def test_ply_per_corner_texcoords_and_face_colours_round_trip(tmp_path):
    F = np.array([[0, 1, 2], [0, 2, 3]])
    m = MeshData(V=SQUARE_V, F=F, texcoords=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
                 face_texcoords=np.array([[0, 1, 2], [0, 2, 3]]),
                 face_attributes={"red": np.array([255, 0], np.uint8)})
    for binary in (True, False):
        p = write_mesh(tmp_path / f"t{binary}.ply", m.V, m.F, like=m, binary=binary)
        assert "property list uchar float texcoord" in p.read_bytes()[:400].decode("latin-1")
        r = read_mesh(p)
        np.testing.assert_array_equal(r.texcoords[r.face_texcoords], m.texcoords[F])
        np.testing.assert_array_equal(r.face_attributes["red"], [255, 0])


def test_obj_vertex_colours_normals_and_groups(tmp_path, caplog):
    p = tmp_path / "c.obj"
    p.write_text("o thing\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 0.5 0.5 0.5\n"
                 "vn 0 0 1\nf 1//1 2//1 3//1 4//1\n")
    with caplog.at_level(logging.WARNING, logger="meshrepair"):
        m = read_mesh(p)
    assert "'o' lines" in caplog.text or "o lines" in caplog.text
    np.testing.assert_array_equal(m.vertex_attributes["green"], [0, 1, 0, 0.5])
    np.testing.assert_allclose(m.vertex_attributes["nz"], 1.0)
    q = write_mesh(tmp_path / "o.obj", m.V, m.F, like=m)
    r = read_mesh(q)
    np.testing.assert_array_equal(r.vertex_attributes["red"], m.vertex_attributes["red"])
    assert "vn " in q.read_text() and "f 1//1 2//2 3//3" in q.read_text()


def test_coff_colours_round_trip(tmp_path):
    p = tmp_path / "c.off"
    p.write_text("COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 128\n"
                 "0 1 0 9 9 9 255\n3 0 1 2\n3 0 2 3\n")
    m = read_mesh(p)
    assert m.vertex_attributes["alpha"].dtype == np.uint8
    r = read_mesh(write_mesh(tmp_path / "o.off", m.V, m.F, like=m))
    for n in ("red", "green", "blue", "alpha"):
        np.testing.assert_array_equal(r.vertex_attributes[n], m.vertex_attributes[n])


def test_float32_output_only_without_loss(tmp_path):
    V, F = _grid()
    m = MeshData(V=V.astype(np.float32).astype(float), F=F)
    from meshrepair.io import FileFormat

    m.file_format = FileFormat(binary=True, precision="float32")
    p = write_mesh(tmp_path / "a.ply", m.V + 1e-9, m.F, like=m)  # below 1e-3 edge: float32
    assert b"property float x" in p.read_bytes()[:200]
    far = m.V + 1e6 + 0.01  # float32 would move vertices by up to 0.03, 0.25 edge lengths
    p = write_mesh(tmp_path / "b.ply", far, m.F, like=m)
    assert b"property double x" in p.read_bytes()[:200]
    p = write_mesh(tmp_path / "c.ply", m.V, m.F, like=m, precision="float64")
    assert b"property double x" in p.read_bytes()[:200]


def test_carry_refuses_a_result_of_another_mesh():
    V, F = _grid()
    m = MeshData(V=V, F=F, vertex_attributes={"q": np.zeros(len(V))})

    from types import SimpleNamespace

    from meshrepair.errors import MeshRepairError

    with pytest.raises(MeshRepairError, match="fewer than the source"):
        carry_attributes(m, SimpleNamespace(V=V[:10], F=F[:2]))


def test_stl_keeps_binary_or_ascii(tmp_path):
    V, F = _grid(3)
    a = write_mesh(tmp_path / "a.stl", V, F, binary=False)
    m = read_mesh(a)
    assert m.file_format is not None and not m.file_format.binary
    out = write_mesh(tmp_path / "b.stl", m.V, m.F, like=m)
    assert out.read_bytes().startswith(b"solid")
