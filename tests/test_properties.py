"""Property-based tests (hypothesis) of the contract every entry point keeps (issue 11):

* any input gets a valid result or a MeshRepairError (never another exception, a hang or a
  NaN result);
* the caller's arrays and files are never modified;
* no command overwrites an input or an existing file without --force, and a refused command
  writes nothing.

Broken meshes are made by mutating small valid ones (NaN/inf/huge coordinates, indices out of
range, repeated or flipped faces, zero-area faces, removed faces, non-manifold fans, wrong
shapes and dtypes); broken files by truncating, corrupting or editing the header of valid ones
in every format. The default profile is small and deterministic (CI: well under two minutes);
``HYPOTHESIS_PROFILE=explore`` runs many more random examples.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meshrepair as mr
from meshrepair.cli import main
from meshrepair.errors import MeshRepairError
from meshrepair.io import read_mesh, read_vertex_mask, write_mesh
from meshrepair.mesh.validate import check_mesh
from meshrepair.metrics import distances
from meshrepair.model.noise import add_noise

settings.register_profile("default", max_examples=60, deadline=None, derandomize=True,
                          database=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.function_scoped_fixture])
settings.register_profile("explore", max_examples=400, deadline=None, database=None,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))


def _bases():
    tet_V = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]])
    tet_F = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    ico = trimesh.creation.icosphere(1)
    n = 5
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float), indexing="ij")
    gV = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(x.ravel() + y.ravel())]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    gF = np.r_[np.c_[a, a + n, a + n + 1], np.c_[a, a + n + 1, a + 1]]
    box = trimesh.creation.box()
    return [(tet_V, tet_F), (np.asarray(ico.vertices), np.asarray(ico.faces)), (gV, gF),
            (np.asarray(box.vertices), np.asarray(box.faces))]


BASES = _bases()
MUTATIONS = ("nan", "inf", "huge", "tiny", "index_high", "index_negative", "repeat_index",
             "duplicate_face", "flip_face", "collapse_vertex", "drop_faces", "fan",
             "float_faces", "fractional_faces", "extra_column", "two_columns", "empty_faces",
             "empty", "noise", "unreferenced", "strings", "object")


@st.composite
def broken_meshes(draw):
    V, F = BASES[draw(st.integers(0, len(BASES) - 1))]
    V, F = V.astype(np.float64).copy(), F.astype(np.int64).copy()
    for m in draw(st.lists(st.sampled_from(MUTATIONS), min_size=0, max_size=3)):
        if not (isinstance(V, np.ndarray) and isinstance(F, np.ndarray)) or V.dtype.kind != "f" \
                or F.dtype.kind not in "iu" or V.ndim != 2 or F.ndim != 2 or len(V) == 0 \
                or len(F) == 0 or F.shape[1] != 3 or V.shape[1] != 3:
            break
        k = draw(st.integers(0, len(V) - 1))
        f = draw(st.integers(0, len(F) - 1))
        if m == "nan":
            V[k, draw(st.integers(0, 2))] = np.nan
        elif m == "inf":
            V[k, draw(st.integers(0, 2))] = -np.inf
        elif m == "huge":
            with np.errstate(over="ignore"):
                V = V * 1e300
        elif m == "tiny":
            V = V * 1e-300
        elif m == "index_high":
            F[f, draw(st.integers(0, 2))] = len(V) + draw(st.integers(0, 5))
        elif m == "index_negative":
            F[f, 0] = -1
        elif m == "repeat_index":
            F[f, 1] = F[f, 0]
        elif m == "duplicate_face":
            F = np.r_[F, F[f:f + 1]]
        elif m == "flip_face":
            F[f] = F[f, ::-1]
        elif m == "collapse_vertex":
            V[F[f, 1]] = V[F[f, 0]]
        elif m == "drop_faces":
            keep = np.ones(len(F), bool)
            keep[draw(st.lists(st.integers(0, len(F) - 1), min_size=1, max_size=4))] = False
            F = F[keep]
        elif m == "fan":  # a third face on an edge: non-manifold
            V = np.r_[V, [[9.0, 9.0, 9.0]]]
            F = np.r_[F, [[F[f, 0], F[f, 1], len(V) - 1]]]
        elif m == "float_faces":
            F = F.astype(np.float64)
        elif m == "fractional_faces":
            F = F.astype(np.float64) + 0.5
        elif m == "extra_column":
            F = np.c_[F, F[:, :1]]
        elif m == "two_columns":
            V = V[:, :2].copy()
        elif m == "empty_faces":
            F = F[:0]
        elif m == "empty":
            V, F = V[:0], F[:0]
        elif m == "noise":
            V = V + draw(st.floats(0.0, 0.5)) * np.random.default_rng(f).normal(size=V.shape)
        elif m == "unreferenced":
            V = np.r_[V, [[0.5, 0.25, 0.125]]]
        elif m == "strings":
            V = V.astype(str)
        elif m == "object":
            F = np.array([list(r) for r in F] + [[0, 1]], dtype=object)
    return V, F


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if a.dtype.kind == "f":
        return bool(np.array_equal(a, b, equal_nan=True))
    return bool(np.array_equal(a, b))


def _call(fn, V, F):
    """Run ``fn(V, F)``; check the inputs are unchanged; return the result or None if refused
    with MeshRepairError (any other exception fails the test)."""
    V0, F0 = np.array(V, copy=True), np.array(F, copy=True)
    try:
        out = fn(V, F)
    except MeshRepairError as exc:
        assert str(exc), "a MeshRepairError must say what is wrong"
        out = None
    assert _same(V, V0) and _same(F, F0), "the input arrays were modified"
    return out


@given(broken_meshes())
def test_check_mesh_contract(mesh):
    V, F = mesh
    rep = _call(lambda a, b: check_mesh(a, b), V, F)
    if rep is not None:
        assert rep.n_vertices == len(V) and rep.n_faces == len(F)


@given(broken_meshes())
def test_denoise_contract(mesh):
    V, F = mesh
    r = _call(lambda a, b: mr.denoise(a, b, robust_iters=3, feature_iters=3), V, F)
    if r is not None:
        assert r.V.shape == np.shape(V) and r.V.dtype == np.float64
        assert np.isfinite(r.V).all(), "denoise returned non-finite vertices"
        assert np.array_equal(r.F, np.asarray(F).astype(np.int64))


@given(broken_meshes(), st.floats(allow_nan=True, allow_infinity=True, width=32))
def test_noise_and_metrics_contract(mesh, gamma):
    V, F = mesh
    Vn = _call(lambda a, b: add_noise(a, b, gamma, seed=1), V, F)
    if Vn is not None:
        assert Vn.shape == np.shape(V)
    d = _call(lambda a, b: distances(a, b, a, b), V, F)
    if d is not None:
        assert all(np.isfinite(v) and v >= 0 for v in d.values())


@given(broken_meshes(), st.sampled_from(["curvature", "none"]), st.sampled_from(["flat",
                                                                                  "smooth"]))
def test_render_contract(mesh, color, shading):
    from meshrepair.render import render_mesh

    V, F = mesh
    with np.errstate(all="ignore"):  # 1e300 coordinates overflow inside the raster
        img = _call(lambda a, b: render_mesh(a, b, width=48, height=48, color_by=color,
                                             shading=shading, colorbar=False), V, F)
    if img is not None:
        assert img.shape == (48, 48, 3) and img.dtype == np.uint8


@given(broken_meshes(), st.sampled_from([".ply", ".obj", ".off", ".stl"]), st.booleans())
def test_write_then_read_contract(tmp_path_factory, mesh, ext, binary):
    """write_mesh accepts or refuses (nothing written); what it writes reads back exactly (STL:
    as a soup merged by position)."""
    V, F = mesh
    d = tmp_path_factory.mktemp("w")
    p = d / f"m{ext}"
    out = _call(lambda a, b: write_mesh(p, a, b, binary=binary), V, F)
    if out is None:
        assert list(d.iterdir()) == [], "a refused write left a file"
        return
    assert [x.name for x in d.iterdir()] == [p.name]
    m = read_mesh(p)
    assert np.isfinite(m.V).all(), "a written file reads back non-finite coordinates"
    if ext != ".stl":  # STL stores a soup (float32 when binary): checked by the readers' tests
        assert np.array_equal(m.F, np.asarray(F).astype(np.int64))
        assert np.array_equal(m.V, np.asarray(V, dtype=np.float64))


# ---------------------------------------------------------------------------------------------
# broken files


def _valid_files():
    V, F = BASES[1]
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for ext in (".ply", ".obj", ".off", ".stl"):
            for binary in ((True, False) if ext in (".ply", ".stl") else (False,)):
                p = write_mesh(Path(d) / f"m{ext}", V, F, binary=binary)
                out[(ext, binary)] = p.read_bytes()
    return out


VALID_FILES = _valid_files()


@st.composite
def broken_files(draw):
    ext, binary = draw(st.sampled_from(sorted(VALID_FILES)))
    data = bytearray(VALID_FILES[(ext, binary)])
    kind = draw(st.sampled_from(["truncate", "flip", "insert", "delete", "header", "garbage",
                                 "append", "empty"]))
    if kind == "truncate":
        data = data[:draw(st.integers(0, len(data) - 1))]
    elif kind == "flip":
        for _ in range(draw(st.integers(1, 8))):
            i = draw(st.integers(0, len(data) - 1))
            data[i] = draw(st.integers(0, 255))
    elif kind == "insert":
        i = draw(st.integers(0, len(data)))
        data[i:i] = draw(st.binary(min_size=1, max_size=20))
    elif kind == "delete":
        i = draw(st.integers(0, len(data) - 1))
        del data[i:i + draw(st.integers(1, 40))]
    elif kind == "header":  # change a count in the header
        text = bytes(data[:300])
        digits = [i for i in range(len(text)) if chr(text[i]).isdigit()]
        if digits:
            data[draw(st.sampled_from(digits))] = ord(str(draw(st.integers(0, 9))))
    elif kind == "garbage":
        data = bytearray(draw(st.binary(min_size=0, max_size=300)))
    elif kind == "append":
        data += draw(st.sampled_from([b"3 0 1 2\n", b"f 1 2 3\n", bytes(50), b"junk",
                                      b"facet normal 0 0 1\n"]))
    else:
        data = bytearray()
    return ext, bytes(data)


@given(broken_files())
def test_readers_contract(tmp_path_factory, case):
    ext, data = case
    p = tmp_path_factory.mktemp("r") / f"x{ext}"
    p.write_bytes(data)
    try:
        m = read_mesh(p)
    except MeshRepairError as exc:
        assert str(p) in str(exc), "a read error must name the file"
    else:
        assert m.V.ndim == 2 and m.V.shape[1] == 3 and m.V.dtype == np.float64
        assert m.F.ndim == 2 and m.F.shape[1] == 3 and m.F.dtype == np.int64
        if m.F.size:
            assert m.F.min() >= 0 and m.F.max() < len(m.V)
    try:
        read_vertex_mask(p, 42)
    except MeshRepairError:
        pass
    assert p.read_bytes() == data, "reading modified the file"


# ---------------------------------------------------------------------------------------------
# commands: nothing of the user's is overwritten


@given(st.sampled_from(["noise", "denoise", "fill", "render", "report"]),
       st.sampled_from(["input", "existing", "new", "other_input"]),
       st.sampled_from([None, "input", "existing_json", "new_json", "new_ply", "existing"]),
       st.booleans())
def test_commands_never_overwrite(tmp_path_factory, cmd, out_kind, log_kind, force):
    d = tmp_path_factory.mktemp("c")
    V, F = BASES[1]
    keep = np.ones(len(F), bool)
    keep[:2] = False  # a small hole for fill
    src = write_mesh(d / "in.ply", V, F[keep])
    other = write_mesh(d / "other.ply", V, F)
    suffix = {"render": ".png", "report": ".html"}.get(cmd, ".ply")
    existing = d / f"old{suffix}"
    existing.write_bytes(b"user data")
    (d / "old.json").write_bytes(b'{"user": "data"}')
    out = {"input": src, "existing": existing, "new": d / f"new{suffix}",
           "other_input": other}[out_kind]
    argv = [cmd, str(src), str(out)]
    if cmd == "report":
        argv += ["--input", str(other), "--image-size", "64"]
    elif cmd == "render":
        argv += ["--size", "64", "64"]
    elif cmd in ("denoise", "fill"):
        argv += ["-q"] + (["--feature-iters", "2", "--robust-iters", "2"] if cmd == "denoise"
                          else ["--no-refine"])
    if log_kind is not None and cmd in ("denoise", "fill"):
        log = {"input": src, "existing_json": d / "old.json", "new_json": d / "run.json",
               "new_ply": d / "run.ply", "existing": existing}[log_kind]
        argv += ["--log", str(log)]
    if force:
        argv.append("--force")
    inputs = {src: src.read_bytes()}
    if cmd == "report":
        inputs[other] = other.read_bytes()
    before = {p.name: p.read_bytes() for p in d.iterdir()}
    rc = main(argv)
    after = {p.name: p.read_bytes() for p in d.iterdir()}
    for p, b in inputs.items():
        assert p.read_bytes() == b, f"{cmd} modified its input {p.name}"
    changed = {n for n in before if after.get(n) != before[n]}
    new = set(after) - set(before)
    assert not any(n.endswith(".tmp") for n in after), "a temporary file was left behind"
    if rc != 0:
        assert rc == 2 and not changed and not new, "a refused command wrote something"
        return
    # success: only the output (and the log) may be new; an existing file only with --force
    allowed = {out.name} | ({Path(argv[argv.index("--log") + 1]).name} if "--log" in argv
                            else set())
    assert new | changed <= allowed
    assert force or not changed, "an existing file was replaced without --force"
    assert out not in inputs, "an input was accepted as the output"
