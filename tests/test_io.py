"""Tests of meshrepair.io: exact round trips, real files, parsers, errors, masks, as_arrays."""

from __future__ import annotations

import logging

import numpy as np
import plyfile
import pytest

from meshrepair.errors import MeshRepairError
from meshrepair.io import MeshData, as_arrays, read_mesh, read_vertex_mask, write_mesh

from .bundled import data_path

FANDISK = data_path("fandisk.ply")


def _mesh():
    """Tetrahedron + a duplicated vertex (5) + an unreferenced vertex (6), awkward values."""
    V = np.array([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [np.pi, -1e-300, 1e300],
        [1.0, 0.0, 0.0],
        [0.1, 0.2, 0.30000000000000004],
    ])
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3], [4, 5, 2]], dtype=np.int64)
    return V, F


def _soup_mesh():
    """A mesh whose vertices appear in face order (STL can keep that order), float32 exact."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5], [0.25, -2, 3]], dtype=np.float64)
    F = np.array([[0, 1, 2], [2, 1, 3], [3, 1, 4]], dtype=np.int64)
    return V, F


# ------------------------------------------------------------------------------------------------
# round trips
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name,binary", [("m.ply", True), ("m.ply", False), ("m.obj", None),
                                         ("m.off", False), ("M.PLY", True)])
def test_round_trip_exact(tmp_path, name, binary):
    V, F = _mesh()
    p = write_mesh(tmp_path / name, V, F, binary=binary)
    m = read_mesh(p)
    assert isinstance(m, MeshData)
    assert m.V.dtype == np.float64 and m.F.dtype == np.int64
    assert m.V.shape == (7, 3) and m.F.shape == (5, 3)
    np.testing.assert_array_equal(m.V, V)  # bitwise equal values, same order, dups kept
    np.testing.assert_array_equal(m.F, F)
    assert m.path == p
    assert m.vertex_attributes == {}


@pytest.mark.parametrize("name", ["m.obj", "m.OFF"])
def test_binary_text_format_refused(tmp_path, name):
    """OBJ and OFF are written as text: ``binary=True`` is refused before a file is made, not
    ignored; a non-boolean ``binary`` is refused for every format."""
    V, F = _mesh()
    with pytest.raises(MeshRepairError, match="text only"):
        write_mesh(tmp_path / name, V, F, binary=True)
    with pytest.raises(MeshRepairError, match="binary must be"):
        write_mesh(tmp_path / "m.ply", V, F, binary="yes")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("binary", [True, False])
def test_stl_round_trip(tmp_path, binary):
    V, F = _soup_mesh()
    m = read_mesh(write_mesh(tmp_path / "m.stl", V, F, binary=binary))
    np.testing.assert_array_equal(m.V, V)
    np.testing.assert_array_equal(m.F, F)


def test_stl_binary_float32_rounding_warns(tmp_path, caplog):
    V, F = _soup_mesh()
    V[0, 0] = 0.1
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(write_mesh(tmp_path / "m.stl", V, F))
    assert "float32" in caplog.text
    assert m.V[0, 0] == np.float64(np.float32(0.1))
    np.testing.assert_array_equal(m.F, F)
    # ascii STL keeps float64 exactly
    m2 = read_mesh(write_mesh(tmp_path / "a.stl", V, F, binary=False))
    np.testing.assert_array_equal(m2.V, V)


@pytest.mark.parametrize("binary", [True, False])
def test_ply_attributes_round_trip(tmp_path, binary):
    V, F = _mesh()
    n = len(V)
    attrs = {
        "mask": np.array([1, 0, 1, 1, 0, 0, 1], dtype=np.uint8),
        "quality": np.linspace(-1, 1, n).astype(np.float32),
        "weight": np.array([np.pi, np.e, 1e-300, -0.0, 5, 6, 7.5]),
        "label": np.array([-5, 0, 2**31 - 1, 3, 4, 5, 6], dtype=np.int32),
        "sel": np.array([True, False, True, False, False, False, True]),
        "id": np.arange(n, dtype=np.int64),
    }
    m = read_mesh(write_mesh(tmp_path / "a.ply", V, F, vertex_attributes=attrs, binary=binary))
    np.testing.assert_array_equal(m.V, V)
    np.testing.assert_array_equal(m.F, F)
    assert list(m.vertex_attributes) == list(attrs)
    expected_dtypes = {"mask": np.uint8, "quality": np.float32, "weight": np.float64,
                       "label": np.int32, "sel": np.uint8, "id": np.int32}
    for k, a in attrs.items():
        got = m.vertex_attributes[k]
        assert got.dtype == expected_dtypes[k], k
        np.testing.assert_array_equal(got, a.astype(expected_dtypes[k]))
    # the file is a standard PLY for other readers too
    with open(tmp_path / "a.ply", "rb") as fh:
        ply = plyfile.PlyData.read(fh)
    assert ply.text is (not binary)
    assert [p.name for p in ply["vertex"].properties][:3] == ["x", "y", "z"]
    assert ply["vertex"].properties[0].val_dtype == "f8"


def test_real_mesh_read_and_rewrite_bit_identical(tmp_path):
    m = read_mesh(FANDISK)
    assert m.V.shape == (6475, 3) and m.F.shape == (12946, 3)
    with open(FANDISK, "rb") as fh:
        ply = plyfile.PlyData.read(fh, mmap=False)
    V0 = np.stack([ply["vertex"][c] for c in "xyz"], axis=1)
    F0 = np.stack(ply["face"]["vertex_indices"]).astype(np.int64)
    assert np.array_equal(m.V.view(np.uint64), V0.view(np.uint64))  # bit-identical
    np.testing.assert_array_equal(m.F, F0)
    out = write_mesh(tmp_path / "fandisk.ply", m.V, m.F)
    m2 = read_mesh(out)
    assert np.array_equal(m2.V.view(np.uint64), m.V.view(np.uint64))
    np.testing.assert_array_equal(m2.F, m.F)
    # same standard layout as the source: the whole file is byte-identical
    assert out.read_bytes() == FANDISK.read_bytes()


def test_read_returns_writable_independent_arrays(tmp_path):
    V, F = _mesh()
    p = write_mesh(tmp_path / "m.ply", V, F)
    m = read_mesh(p)
    m.V[0, 0] = 42.0  # not a read-only memory map of the file
    m.F[0, 0] = 6
    assert read_mesh(p).V[0, 0] == 0.0


# ------------------------------------------------------------------------------------------------
# parsers
# ------------------------------------------------------------------------------------------------

ASCII_PLY = """ply
format ascii 1.0
comment hand written
element vertex 5
property float x
property float y
property float z
property float nx
property uchar mask
element face 2
property list uchar int vertex_indices
end_header
0 0 0 0 1
1 0 0 0 0
1 1 0 0 1
0 1 0 0 1
0.5 0.5 1 1 0
4 0 1 2 3
3 3 2 4
"""


def test_ascii_ply_with_quad_and_attributes(tmp_path, caplog):
    p = tmp_path / "a.ply"
    p.write_text(ASCII_PLY)
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(p)
    assert "fan-triangulated 1 polygon(s) with more than 3 vertices" in caplog.text
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [3, 2, 4]])
    np.testing.assert_array_equal(m.V[4], [0.5, 0.5, 1.0])
    assert set(m.vertex_attributes) == {"nx", "mask"}
    np.testing.assert_array_equal(m.vertex_attributes["mask"], [1, 0, 1, 1, 0])
    assert m.vertex_attributes["mask"].dtype == np.uint8


def test_binary_ply_polygons_and_big_endian(tmp_path, caplog):
    verts = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0)],
                     dtype=[("x", ">f4"), ("y", ">f4"), ("z", ">f4")])
    faces = np.empty(2, dtype=[("vertex_indices", "O")])
    faces["vertex_indices"][0] = np.array([0, 1, 2, 3], dtype=np.int32)
    faces["vertex_indices"][1] = np.array([1, 4, 2], dtype=np.int32)
    ply = plyfile.PlyData([plyfile.PlyElement.describe(verts, "vertex"),
                           plyfile.PlyElement.describe(faces, "face")], byte_order=">")
    p = tmp_path / "big.ply"
    ply.write(str(p))
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(p)
    assert "fan-triangulated 1 polygon(s) with more than 3 vertices" in caplog.text
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [1, 4, 2]])
    np.testing.assert_array_equal(m.V[:, 0], [0, 1, 1, 0, 2])


def test_ply_without_faces_is_point_cloud(tmp_path, caplog):
    p = tmp_path / "pc.ply"
    p.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\n"
                 "property double y\nproperty double z\nend_header\n0 0 0\n1 2 3\n")
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(p)
    assert m.F.shape == (0, 3) and m.V.shape == (2, 3)
    assert "point cloud" in caplog.text


OBJ = """# comment
mtllib x.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0 1.0
vt 0 0
vn 0 0 1
f 1/1/1 2/1/1 3/1/1
v 0 1 0 0.5 0.5 0.5
g grp
usemtl m
f -4//1 -2//1 -1//1
f 2/1 3/1 4/1 1/1
l 1 2
s off
f 1 2 3 # trailing comment
v 5 5 5
"""


def test_obj_slashes_negative_indices_and_quads(tmp_path, caplog):
    p = tmp_path / "a.obj"
    p.write_text(OBJ)
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(p)
    np.testing.assert_array_equal(m.V, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [5, 5, 5]])
    # relative to the 4 vertices defined before that line: -4//1 -> 0, -2 -> 2, -1 -> 3
    # (the last vertex is defined later and stays, unreferenced)
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [1, 2, 3], [1, 3, 0], [0, 1, 2]])
    assert "fan-triangulated 1 polygon(s) with more than 3 vertices" in caplog.text


OFF = """OFF
# a comment
5 3 0
0 0 0
1 0 0
1 1 0
0 1 0   # inline comment
0.5 0.5 1
4 0 1 2 3
3 3 2 4 255 0 0
3 0 4 1
"""


def test_off_with_comments_colours_and_polygon(tmp_path, caplog):
    p = tmp_path / "a.off"
    p.write_text(OFF)
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        m = read_mesh(p)
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [3, 2, 4], [0, 4, 1]])
    np.testing.assert_array_equal(m.V[4], [0.5, 0.5, 1.0])
    assert "fan-triangulated 1 polygon(s) with more than 3 vertices into 2 triangles" in caplog.text


def test_coff_counts_on_header_line(tmp_path):
    p = tmp_path / "c.off"
    p.write_text("COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
                 "3 0 1 2\n")
    m = read_mesh(p)
    np.testing.assert_array_equal(m.V, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(m.F, [[0, 1, 2]])


def _binary_stl(path, tris):
    tris = np.asarray(tris, dtype=np.float32)
    rec = np.zeros(len(tris), dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = tris
    path.write_bytes(b"solid but actually binary".ljust(80) + np.uint32(len(tris)).tobytes()
                     + rec.tobytes())


def test_stl_merges_equal_positions(tmp_path, caplog):
    tris = [[[0, 0, 0], [1, 0, 0], [0, 1, 0]],
            [[0, 1, 0], [1, 0, 0], [1, 1, -0.0]],
            [[1, 1, 0], [1, 0, 0], [2, 0, 0]]]
    p = tmp_path / "s.stl"
    _binary_stl(p, tris)
    with caplog.at_level(logging.INFO, logger="meshrepair.io"):
        m = read_mesh(p)
    assert "merged 9 corners into 5 vertices" in caplog.text
    np.testing.assert_array_equal(m.V, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0]])
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [2, 1, 3], [3, 1, 4]])
    # ascii version of the same soup
    lines = ["solid x"]
    for t in tris:
        lines += ["facet normal 0 0 1", "outer loop"]
        lines += [f"vertex {a!r} {b!r} {c!r}" for a, b, c in t]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid x")
    q = tmp_path / "s_ascii.stl"
    q.write_text("\n".join(lines))
    m2 = read_mesh(q)
    np.testing.assert_array_equal(m2.V, m.V)
    np.testing.assert_array_equal(m2.F, m.F)


# ------------------------------------------------------------------------------------------------
# bad files
# ------------------------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(MeshRepairError, match=r"cannot read '.*nope\.ply': file not found"):
        read_mesh(tmp_path / "nope.ply")


def test_unknown_extension_lists_supported(tmp_path):
    p = tmp_path / "a.xyz"
    p.write_text("1 2 3\n")
    with pytest.raises(MeshRepairError, match=r"a\.xyz.*unsupported.*\.obj, \.off, \.ply, \.stl"):
        read_mesh(p)
    with pytest.raises(MeshRepairError, match="unsupported"):
        write_mesh(tmp_path / "a.xyz", *_mesh())


def test_garbage_ply(tmp_path):
    p = tmp_path / "g.ply"
    p.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    with pytest.raises(MeshRepairError,
                       match=r"cannot read '.*g\.ply': not a PLY file \(bad header"):
        read_mesh(p)
    p.write_text("ply\nformat ascii 1.0\nelement vertex two\nend_header\n")
    with pytest.raises(MeshRepairError, match=r"g\.ply': not a PLY file \(bad header"):
        read_mesh(p)


@pytest.mark.parametrize("binary", [True, False])
def test_truncated_ply(tmp_path, binary):
    V, F = _mesh()
    p = write_mesh(tmp_path / "t.ply", V, F, binary=binary)
    data = p.read_bytes()
    p.write_bytes(data[:-20])
    with pytest.raises(MeshRepairError, match=r"t\.ply': truncated or corrupt"):
        read_mesh(p)


def test_ply_face_index_out_of_range(tmp_path):
    p = tmp_path / "r.ply"
    p.write_text(ASCII_PLY.replace("3 3 2 4", "3 3 2 9"))
    with pytest.raises(MeshRepairError, match=r"r\.ply'.*references vertex.*5 vertices"):
        read_mesh(p)


def test_ply_missing_xyz(tmp_path):
    p = tmp_path / "n.ply"
    p.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n")
    with pytest.raises(MeshRepairError, match=r"lacks properties \['y', 'z'\]"):
        read_mesh(p)


@pytest.mark.parametrize("text,match", [
    ("hello world\n", r"no vertex \('v'\) lines"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", r"references vertex.*3 vertices"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", r"index 0 .*start at 1"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", r"points before the first vertex"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", r"has 2 vertices"),
    ("v 0 0 zero\n", r"malformed vertex at line 1"),
    ("v 0 0 0\nf 1 a 2\n", r"malformed face index 'a' at line 2"),
])
def test_bad_obj(tmp_path, text, match):
    p = tmp_path / "b.obj"
    p.write_text(text)
    with pytest.raises(MeshRepairError, match=r"cannot read '.*b\.obj': .*" + match):
        read_mesh(p)


def test_binary_garbage_obj(tmp_path):
    p = tmp_path / "b.obj"
    p.write_bytes(b"\x00\x01\x02garbage")
    with pytest.raises(MeshRepairError, match=r"b\.obj': binary data"):
        read_mesh(p)


@pytest.mark.parametrize("text,match", [
    ("PFF\n3 1 0\n", r"not an OFF file \(bad header"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n", r"truncated: header declares 3 vertices and 1 faces"),
    ("OFF\n", r"truncated: missing the 'nV nF nE' counts"),
    ("OFF\nthree 1 0\n", r"bad counts line"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", r"references vertex"),
    ("OFF BINARY\n", r"binary OFF is not supported"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", r"fewer indices than its count"),
])
def test_bad_off(tmp_path, text, match):
    p = tmp_path / "b.off"
    p.write_text(text)
    with pytest.raises(MeshRepairError, match=r"cannot read '.*b\.off': .*" + match):
        read_mesh(p)


def test_bad_stl(tmp_path):
    p = tmp_path / "t.stl"
    _binary_stl(p, [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]] * 3)
    data = p.read_bytes()
    p.write_bytes(b"x" * 5 + data[5:-30])  # no 'solid' prefix, truncated
    with pytest.raises(MeshRepairError, match=r"t\.stl': truncated binary STL: header declares 3"):
        read_mesh(p)
    p.write_bytes(b"tiny")
    with pytest.raises(MeshRepairError, match=r"t\.stl': not an STL file"):
        read_mesh(p)
    p.write_text("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n")
    with pytest.raises(MeshRepairError, match=r"t\.stl': truncated or malformed ASCII STL"):
        read_mesh(p)


def test_directory_is_refused(tmp_path):
    d = tmp_path / "dir.ply"
    d.mkdir()
    with pytest.raises(MeshRepairError, match="is a directory"):
        read_mesh(d)


# ------------------------------------------------------------------------------------------------
# write errors
# ------------------------------------------------------------------------------------------------


def test_write_overwrite_false(tmp_path):
    V, F = _mesh()
    p = write_mesh(tmp_path / "m.obj", V, F)
    before = p.read_bytes()
    with pytest.raises(MeshRepairError, match=r"m\.obj': file exists"):
        write_mesh(p, V + 1, F, overwrite=False)
    assert p.read_bytes() == before
    write_mesh(p, V + 1, F)  # default overwrite=True replaces it
    np.testing.assert_array_equal(read_mesh(p).V, V + 1)


@pytest.mark.parametrize("ext", [".ply", ".obj", ".off", ".stl"])
def test_write_refuses_nonfinite(tmp_path, ext):
    V, F = _mesh()
    V[3, 1] = np.nan
    V[5, 0] = np.inf
    p = tmp_path / ("m" + ext)
    with pytest.raises(MeshRepairError, match=r"refusing to write .*2 vertices have non-finite"
                       r".*\[3, 5\]"):
        write_mesh(p, V, F)
    assert not p.exists()
    assert list(tmp_path.iterdir()) == []  # no temporary file left behind


def test_write_bad_inputs(tmp_path):
    V, F = _mesh()
    with pytest.raises(MeshRepairError, match=r"out of range \[0, 6\]"):
        write_mesh(tmp_path / "a.ply", V, F + 3)
    with pytest.raises(MeshRepairError, match=r"F must have shape \(nF, 3\)"):
        write_mesh(tmp_path / "a.ply", V, np.zeros((2, 4), dtype=int))
    with pytest.raises(MeshRepairError, match=r"attribute 'm' has shape \(3,\), expected \(7,\)"):
        write_mesh(tmp_path / "a.ply", V, F, vertex_attributes={"m": np.zeros(3)})
    with pytest.raises(MeshRepairError, match="invalid vertex attribute name"):
        write_mesh(tmp_path / "a.ply", V, F, vertex_attributes={"a b": np.zeros(7)})
    with pytest.raises(MeshRepairError, match="directory .* does not exist"):
        write_mesh(tmp_path / "no" / "a.ply", V, F)


def test_write_attributes_ignored_outside_ply(tmp_path, caplog):
    V, F = _mesh()
    with caplog.at_level(logging.WARNING, logger="meshrepair.io"):
        write_mesh(tmp_path / "a.obj", V, F, vertex_attributes={"mask": np.ones(7)})
    assert "not stored" in caplog.text


# ------------------------------------------------------------------------------------------------
# read_vertex_mask
# ------------------------------------------------------------------------------------------------


def test_mask_from_ply_property(tmp_path):
    p = tmp_path / "m.ply"
    p.write_text(ASCII_PLY)
    # 'nx' is skipped (a normal, not a mask): the first candidate is 'mask'
    np.testing.assert_array_equal(read_vertex_mask(p, 5), [True, False, True, True, False])
    np.testing.assert_array_equal(read_vertex_mask(p, 5, attribute="nx"),
                                  [False, False, False, False, True])
    with pytest.raises(MeshRepairError, match=r"no vertex property 'foo'"):
        read_vertex_mask(p, 5, attribute="foo")
    with pytest.raises(MeshRepairError,
                       match=r"property 'mask' has 5 values but the mesh has 4 vertices"):
        read_vertex_mask(p, 4)


def test_mask_from_ply_non_binary_values(tmp_path):
    V, F = _mesh()
    p = write_mesh(tmp_path / "q.ply", V, F, vertex_attributes={"quality": np.linspace(0, 1, 7)})
    with pytest.raises(MeshRepairError, match="values other than 0 and 1"):
        read_vertex_mask(p, 7)


def test_mask_from_index_text(tmp_path):
    p = tmp_path / "idx.txt"
    p.write_text("# selected\n0 3\n5\n5\n")
    m = read_vertex_mask(p, 7)
    assert m.dtype == bool and m.shape == (7,)
    np.testing.assert_array_equal(np.flatnonzero(m), [0, 3, 5])
    p.write_text("1\n7\n")
    with pytest.raises(MeshRepairError, match=r"out of range \[0, 6\] \(e\.g\. \[7\]\)"):
        read_vertex_mask(p, 7)
    p.write_text("1\n-1\n")
    with pytest.raises(MeshRepairError, match="out of range"):
        read_vertex_mask(p, 7)
    p.write_text("1 two\n")
    with pytest.raises(MeshRepairError, match="expected integer vertex indices, found 'two'"):
        read_vertex_mask(p, 7)


def test_mask_from_npy_and_arrays(tmp_path):
    b = np.array([True, False, False, True])
    np.save(tmp_path / "b.npy", b)
    np.testing.assert_array_equal(read_vertex_mask(tmp_path / "b.npy", 4), b)
    np.save(tmp_path / "i.npy", np.array([2, 1]))
    np.testing.assert_array_equal(read_vertex_mask(tmp_path / "i.npy", 4),
                                  [False, True, True, False])
    np.save(tmp_path / "z.npy", b.astype(np.float64))  # per-vertex 0/1 values
    np.testing.assert_array_equal(read_vertex_mask(tmp_path / "z.npy", 4), b)
    with pytest.raises(MeshRepairError, match=r"boolean mask has 4 values but the mesh has 5"):
        read_vertex_mask(b, 5)
    with pytest.raises(MeshRepairError, match="file not found"):
        read_vertex_mask(tmp_path / "missing.npy", 4)
    out = read_vertex_mask(b, 4)
    out[0] = False
    assert b[0]  # a copy


# ------------------------------------------------------------------------------------------------
# as_arrays
# ------------------------------------------------------------------------------------------------


def test_as_arrays_copies_and_dtypes():
    V, F = _mesh()
    V2, F2 = as_arrays(V, F)
    assert V2.dtype == np.float64 and F2.dtype == np.int64
    assert not np.shares_memory(V2, V) and not np.shares_memory(F2, F)
    V2[0, 0] = 9.0
    F2[0, 0] = 6
    assert V[0, 0] == 0.0 and F[0, 0] == 0
    V3, F3 = as_arrays(V[:4].astype(np.float32).tolist(), F[:4].astype(np.int32))
    assert V3.dtype == np.float64 and F3.dtype == np.int64
    np.testing.assert_array_equal(F3, F[:4])
    np.testing.assert_array_equal(V3, V[:4])
    _, F4 = as_arrays(V, F.astype(np.float64))  # integral floats accepted
    np.testing.assert_array_equal(F4, F)


def test_as_arrays_trimesh_and_meshdata():
    trimesh = pytest.importorskip("trimesh")
    V, F = _mesh()
    tm = trimesh.Trimesh(vertices=V, faces=F, process=False)
    V2, F2 = as_arrays(tm)
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)
    assert type(V2) is np.ndarray and not np.shares_memory(V2, tm.vertices)
    md = MeshData(V=V, F=F)
    V3, F3 = as_arrays(md)
    assert not np.shares_memory(V3, md.V)
    with pytest.raises(MeshRepairError, match="not both"):
        as_arrays(tm, F)


@pytest.mark.parametrize("args,match", [
    (("mesh.ply",), r"expected \(V, F\) arrays, a trimesh.Trimesh or a MeshData, got str"),
    ((None,), "got NoneType"),
    ((np.zeros((3, 3)),), "missing face array F"),
    ((np.zeros((3, 3)), np.array([[0, 1, 1.5]])), "integer vertex indices"),
    ((np.zeros((3, 3)), np.array([["a", "b", "c"]])), "integer array"),
])
def test_as_arrays_errors(args, match):
    with pytest.raises(MeshRepairError, match=match):
        as_arrays(*args)


def test_ply_float_face_indices_must_be_whole(tmp_path):
    """A PLY face list of floats reads when every value is whole and is refused otherwise (it
    was truncated: ``3 0 1.7 2`` read as the face (0, 1, 2)), as OBJ and OFF refuse it."""
    head = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar float vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n")
    ok, bad = tmp_path / "ok.ply", tmp_path / "bad.ply"
    ok.write_text(head + "3 0 1 2\n")
    bad.write_text(head + "3 0 1.7 2\n")
    assert read_mesh(ok).F.tolist() == [[0, 1, 2]]
    with pytest.raises(MeshRepairError, match="non-integer vertex indices"):
        read_mesh(bad)


def test_indices_beyond_int64_are_refused_clearly(tmp_path):
    """An index with more digits than int64 holds is a MeshRepairError naming the file, in the
    OBJ, OFF, vertex-mask and face-selection readers (it was a raw OverflowError)."""
    from meshrepair.io.masks import read_face_selection

    huge = "99999999999999999999"
    obj, off = tmp_path / "h.obj", tmp_path / "h.off"
    obj.write_text(f"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 {huge}\n")
    off.write_text(f"OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 {huge}\n")
    for p in (obj, off):
        with pytest.raises(MeshRepairError, match=p.name):
            read_mesh(p)
    sel = tmp_path / "sel.txt"
    sel.write_text(f"1 {huge}\n")
    with pytest.raises(MeshRepairError, match="larger than any"):
        read_vertex_mask(sel, 10)
    with pytest.raises(MeshRepairError, match="larger than any"):
        read_face_selection(sel, 10)


def test_ply_attribute_names_any_ply_allows(tmp_path):
    """Face properties named like the writer's own record fields (n, i, m, uv) round-trip, and
    a non-ASCII name is refused with a MeshRepairError (a PLY header is ASCII), not a raw
    UnicodeEncodeError."""
    V, F = _mesh()
    p = tmp_path / "a.ply"
    head = read_mesh(write_mesh(p, V, F))
    head.face_attributes = {n: np.arange(len(F), dtype=np.int32) + k
                            for k, n in enumerate(("n", "i", "m", "uv"))}
    q = write_mesh(tmp_path / "b.ply", V, F, like=head)
    back = read_mesh(q)
    for k, n in enumerate(("n", "i", "m", "uv")):
        np.testing.assert_array_equal(back.face_attributes[n], np.arange(len(F)) + k)
    with pytest.raises(MeshRepairError, match="ASCII"):
        write_mesh(tmp_path / "c.ply", V, F, vertex_attributes={"größe": np.ones(len(V))})
