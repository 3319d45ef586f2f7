"""Readers refuse truncated or inconsistent files, non-regular files and impossible paths with
MeshRepairError (issue 11): nothing is read as part of a mesh."""

from __future__ import annotations

import os
import signal
import struct

import numpy as np
import pytest
import trimesh

from meshrepair.cli import main
from meshrepair.complete.api import load_transform
from meshrepair.errors import MeshRepairError
from meshrepair.io import read_mesh, read_vertex_mask, write_mesh


@pytest.fixture
def mesh():
    m = trimesh.creation.icosphere(1)
    return np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int64)


def _replace_once(data: bytes, old: bytes, new: bytes) -> bytes:
    assert data.count(old) == 1
    return data.replace(old, new)


@pytest.mark.parametrize("binary", [True, False])
def test_ply_header_undercounting_faces_is_refused(tmp_path, mesh, binary):
    V, F = mesh
    p = write_mesh(tmp_path / "m.ply", V, F, binary=binary)
    data = p.read_bytes()
    p.write_bytes(_replace_once(data, f"element face {len(F)}\n".encode(),
                                f"element face {len(F) - 1}\n".encode()))
    with pytest.raises(MeshRepairError, match="header declares .*more .* follow"):
        read_mesh(p)
    # also through the vertex-mask reader, which parses PLY the same way
    with pytest.raises(MeshRepairError, match="undercounts"):
        read_vertex_mask(p, len(V), attribute="x")


@pytest.mark.parametrize("binary", [True, False])
def test_ply_header_undercounting_vertices_is_refused(tmp_path, mesh, binary):
    V, F = mesh
    p = write_mesh(tmp_path / "m.ply", V, F, binary=binary)
    p.write_bytes(_replace_once(p.read_bytes(), f"element vertex {len(V)}\n".encode(),
                                f"element vertex {len(V) - 2}\n".encode()))
    with pytest.raises(MeshRepairError, match=r"m\.ply'"):
        read_mesh(p)


@pytest.mark.parametrize("binary", [True, False])
def test_ply_trailing_newline_is_fine(tmp_path, mesh, binary):
    V, F = mesh
    p = write_mesh(tmp_path / "m.ply", V, F, binary=binary)
    p.write_bytes(p.read_bytes() + b"\n\n")
    m = read_mesh(p)
    assert np.array_equal(m.F, F) and np.array_equal(m.V, V)


def test_ply_polygon_file_with_trailing_record_is_refused(tmp_path):
    # quads take plyfile's generic (non memory-mapped) path
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    head = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n"
            b"property double y\nproperty double z\nelement face 1\n"
            b"property list uchar int vertex_indices\nend_header\n")
    quad = struct.pack("<B4i", 4, 0, 1, 2, 3)
    p = tmp_path / "q.ply"
    p.write_bytes(head + V.astype("<f8").tobytes() + quad)
    assert read_mesh(p).F.shape == (2, 3)
    p.write_bytes(head + V.astype("<f8").tobytes() + quad + quad)
    with pytest.raises(MeshRepairError, match="undercounts"):
        read_mesh(p)


def test_off_header_undercounting_faces_is_refused(tmp_path, mesh):
    V, F = mesh
    p = write_mesh(tmp_path / "m.off", V, F)
    p.write_bytes(_replace_once(p.read_bytes(), f"{len(V)} {len(F)} 0".encode(),
                                f"{len(V)} {len(F) - 3} 0".encode()))
    with pytest.raises(MeshRepairError, match="declares .* 3 more data lines"):
        read_mesh(p)


def test_binary_stl_header_undercounting_is_refused(tmp_path, mesh):
    V, F = mesh
    p = write_mesh(tmp_path / "m.stl", V, F)
    data = bytearray(p.read_bytes())
    data[80:84] = struct.pack("<I", len(F) - 2)
    p.write_bytes(bytes(data))
    with pytest.raises(MeshRepairError, match="2 more triangle records"):
        read_mesh(p)
    # a binary STL whose 80-byte header starts with 'solid' and is inconsistent
    data[:5] = b"solid"
    p.write_bytes(bytes(data))
    with pytest.raises(MeshRepairError, match="binary STL: header declares"):
        read_mesh(p)


def _ascii_stl(tmp_path, mesh):
    V, F = mesh
    return write_mesh(tmp_path / "m.stl", V, F, binary=False)


def test_ascii_stl_cut_in_half_is_refused(tmp_path, mesh, capsys):
    p = _ascii_stl(tmp_path, mesh)
    text = p.read_bytes()
    n = text.count(b"endfacet")
    # cut exactly after a complete facet: used to be read as half the triangles
    cut = text.index(b"endfacet", len(text) // 2) + len(b"endfacet\n")
    half = tmp_path / "half.stl"
    half.write_bytes(text[:cut])
    with pytest.raises(MeshRepairError, match="no 'endsolid'"):
        read_mesh(half)
    # and the CLI writes nothing
    out = tmp_path / "out.ply"
    assert main(["noise", str(half), str(out)]) == 2
    assert "truncated" in capsys.readouterr().err and not out.exists()
    # cut anywhere else: refused too
    for k in (len(text) // 3, len(text) - 25, len(text) - 40, 30):
        half.write_bytes(text[:k])
        with pytest.raises(MeshRepairError, match="ASCII STL|not an STL"):
            read_mesh(half)
    assert read_mesh(p).n_faces == n


def test_ascii_stl_broken_facet_is_refused(tmp_path, mesh):
    p = _ascii_stl(tmp_path, mesh)
    text = p.read_bytes()
    i = text.index(b"vertex", len(text) // 2)
    j = text.index(b"\n", i) + 1
    p.write_bytes(text[:i] + text[j:])  # a facet with two vertices
    with pytest.raises(MeshRepairError, match="facet .* is not"):
        read_mesh(p)


def test_ascii_stl_several_solids_and_empty_solid(tmp_path, mesh):
    p = _ascii_stl(tmp_path, mesh)
    text = p.read_bytes()
    p.write_bytes(text + text.replace(b"solid meshrepair", b"solid second"))
    assert read_mesh(p).n_faces == 2 * len(mesh[1])
    p.write_bytes(b"solid empty\nendsolid empty\n")
    assert read_mesh(p).n_faces == 0


class _Timeout(Exception):
    pass


def _alarm(*_):
    raise _Timeout


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs POSIX FIFOs")
def test_fifo_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "x.ply"
    os.mkfifo(fifo)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(10)  # a blocking open would hang: turn that into a failure
    try:
        with pytest.raises(MeshRepairError, match="not a regular file"):
            read_mesh(fifo)
        with pytest.raises(MeshRepairError, match="not a regular file"):
            read_vertex_mask(fifo, 3)
        txt = tmp_path / "T.txt"
        os.mkfifo(txt)
        with pytest.raises(MeshRepairError, match="not a regular file"):
            load_transform(txt)
        assert main(["denoise", str(fifo), str(tmp_path / "o.ply"), "-q"]) == 2
        assert "not a regular file" in capsys.readouterr().err
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_impossible_paths_are_mesh_repair_errors(tmp_path, capsys):
    long = tmp_path / ("a" * 300 + ".ply")
    with pytest.raises(MeshRepairError, match="too long"):
        read_mesh(long)
    deep = tmp_path / "/".join(["d" * 200] * 30) / "m.ply"  # longer than PATH_MAX
    with pytest.raises(MeshRepairError, match="too long"):
        read_mesh(deep)
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(MeshRepairError, match="Not a directory"):
        read_mesh(f / "m.ply")
    assert main(["denoise", str(long), str(tmp_path / "o.ply"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "too long" in err and "Traceback" not in err
    with pytest.raises(MeshRepairError, match="too long"):
        read_vertex_mask(str(long), 3)


@pytest.mark.parametrize("binary", [True, False])
def test_ply_absurd_header_counts_refused_before_allocating(tmp_path, mesh, binary):
    V, F = mesh
    p = write_mesh(tmp_path / "m.ply", V, F, binary=binary)
    p.write_bytes(_replace_once(p.read_bytes(), f"element face {len(F)}\n".encode(),
                                b"element face 900000000000\n"))
    with pytest.raises(MeshRepairError, match=r"900,000,000,000 face records, which need at "
                                              r"least [\d,]+ bytes"):
        read_mesh(p)


def test_binary_stl_refuses_coordinates_beyond_float32(tmp_path, mesh):
    V, F = mesh
    p = tmp_path / "big.stl"
    with pytest.raises(MeshRepairError, match="float32 of binary STL"):
        write_mesh(p, V * 1e300, F)  # used to write inf coordinates silently
    assert not p.exists() and list(tmp_path.iterdir()) == []
    write_mesh(p, V * 1e300, F, binary=False)  # ASCII STL keeps float64
    m = read_mesh(p)
    assert np.isfinite(m.V).all() and np.abs(m.V).max() > 1e299
