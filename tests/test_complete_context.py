"""Completion that trusts only the intact surface, and completion from the mesh's own symmetry.

Self-completion: a region of a mesh is damaged (dented, spiked, noisy or flattened) and completed
with its own original surface moved far away by a rigid motion, given as a bare patch or as a
piece of a moved copy of the mesh (then its context rings are matched too). The default
alignment must not look at the damaged faces: the result is the original surface.

Symmetric completion: ``template="mirror"`` on meshes that are exactly symmetric (the bundled
fandisk made symmetric by mirroring one half; spot, which is; trim_star, symmetric in shape but
not in tessellation) and refused on one that is not (fandisk as it is).

Fast tests use the bundled fandisk (CAD) and an ellipsoid (smooth); tests marked ``shared`` use
spot, fandisk and trim_star from ../shared/meshes.
"""

import argparse
import logging
from pathlib import Path

import numpy as np
import pytest
import trimesh

from meshrepair.complete.api import complete, extract_patch
from meshrepair.complete.correspondence import apply_transform
from meshrepair.complete.rigid import reflection
from meshrepair.complete.symmetry import detect_symmetry
from meshrepair.errors import MeshRepairError
from meshrepair.io import read_mesh
from meshrepair.mesh.geometry import mean_edge_length
from meshrepair.mesh.validate import check_mesh
from meshrepair.metrics import point_to_surface
from meshrepair.synthetic import DAMAGES, damage_region, geodesic_disc, random_rigid, symmetrize

from .conftest import shared_mesh

DATA = Path(__file__).resolve().parents[1] / "src" / "meshrepair" / "data"


def geodesic(V, F, center, radius):
    return geodesic_disc(V, F, center, radius, return_distances=True)


def damage(V, F, faces, d, radius, kind, seed=0):
    """The mesh with the region's interior vertices damaged (its boundary is left intact)."""
    Vd = damage_region(V, F, faces, d, radius, kind, seed=seed)
    assert np.abs(Vd - V).max() > 0.2 * mean_edge_length(V, F)
    return Vd


def self_completion_errors(V, F, center, radius_l=6.0, kinds=DAMAGES):
    """Max distance to the truth / diag for each damage, bare patch and moved-piece templates."""
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    faces, d = geodesic(V, F, center, radius_l * l)
    T = random_rigid(3, 2 * diag)
    VP, FP = extract_patch(V, F, faces)
    out = {}
    for kind in kinds:
        Vd = damage(V, F, faces, d, radius_l * l, kind)
        for name, tmpl in (("patch", (apply_transform(T, VP), FP)),
                           ("piece", (apply_transform(T, V), F, faces))):
            res = complete(Vd, F, faces, tmpl)
            assert check_mesh(res.V, res.F).is_closed
            out[kind, name] = (point_to_surface(res.V, V, F).max() / diag, res)
    return out


@pytest.fixture(scope="module")
def fandisk():
    m = read_mesh(DATA / "fandisk.ply")
    return m.V, m.F


@pytest.fixture(scope="module")
def ellipsoid():
    m = trimesh.creation.icosphere(subdivisions=4)
    V = np.asarray(m.vertices, float) * [1.0, 0.7, 0.5]
    return V, np.asarray(m.faces, np.int64)


# ----------------------------------------------------------------------------------------------
# alignment from the intact context only


@pytest.mark.parametrize("mesh", ["ellipsoid", "fandisk"])
def test_self_completion_of_damaged_region_is_exact(mesh, request):
    V, F = request.getfixturevalue(mesh)
    center = 100 if mesh == "ellipsoid" else 2000
    errs = self_completion_errors(V, F, center)
    for (kind, name), (err, res) in errs.items():
        assert err < 1e-3, (kind, name, err)  # measured <= 6.1e-5 (ellipsoid), 2.2e-4 (fandisk)
        a = res.alignment
        assert a["boundary_rms"] < 1e-9 and not a["warning"]
        if name == "piece":  # the template's own context rings were matched to the mesh's
            assert res.correspondence["icp"]["target"] == "context"
            assert a["context_rms"] < 1e-9 and a["context_points"] > 0
        else:
            assert a["context_rms"] is None


def test_surface_icp_is_an_opt_in_that_trusts_the_damaged_faces(fandisk):
    """The old default (fit the template to the region's own faces) sits in the dent."""
    V, F = fandisk
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    faces, d = geodesic(V, F, 3000, 6 * l)
    Vd = damage(V, F, faces, d, 6 * l, "dent")
    VP, FP = extract_patch(V, F, faces)
    tmpl = (apply_transform(random_rigid(3, 2 * diag), VP), FP)
    res = complete(Vd, F, faces, tmpl, icp="surface")
    assert res.correspondence["icp"]["target"] == "surface"
    assert point_to_surface(res.V, V, F).max() / diag > 1e-3  # measured 8.4e-3
    assert res.alignment["boundary_rms"] > 0.1
    assert complete(Vd, F, faces, tmpl).params["icp"] == "context"


def test_alignment_report_warns_on_a_template_that_does_not_fit(fandisk, caplog):
    V, F = fandisk
    l = mean_edge_length(V, F)
    faces, _ = geodesic(V, F, 3000, 6 * l)
    VP, FP = extract_patch(V, F, faces)
    c = VP.mean(axis=0)
    with caplog.at_level(logging.WARNING, logger="meshrepair.complete.alignment"):
        res = complete(V, F, faces, ((VP - c) * 1.3 + c, FP), iterations=5)
    a = res.alignment
    assert a["warning"] and a["boundary_rms"] > 0.5
    assert "alignment residual" in caplog.text
    assert a["unit"] == pytest.approx(l)


def test_strip_fidelity_follows_the_seam_gap(fandisk):
    V, F = fandisk
    l = mean_edge_length(V, F)
    faces, _ = geodesic(V, F, 3000, 6 * l)
    VP, FP = extract_patch(V, F, faces)
    res = complete(V, F, faces, (VP, FP), iterations=5)
    assert res.M_V[res.strip_vertices] == pytest.approx(16)  # exact template: kept
    res = complete(V, F, faces, (VP, FP), iterations=5, strip_fidelity=0)
    assert (res.M_V[res.strip_vertices] == 0).all()  # the paper's free strip
    with pytest.raises(MeshRepairError, match="strip_fidelity"):
        complete(V, F, faces, (VP, FP), strip_fidelity=-1)
    with pytest.raises(MeshRepairError, match="strip_fidelity"):
        complete(V, F, faces, (VP, FP), strip_fidelity="x")


# ----------------------------------------------------------------------------------------------
# symmetry


def test_reflection_is_an_involution():
    M = reflection([1.0, 2.0, -0.5], [0.3, 0.1, 2.0])
    np.testing.assert_allclose(M @ M, np.eye(4), atol=1e-12)
    assert np.linalg.det(M[:3, :3]) == pytest.approx(-1)
    with pytest.raises(MeshRepairError, match="zero"):
        reflection([0, 0, 0], [0, 0, 0])


def test_detect_symmetry_recovers_a_plane_after_a_rigid_motion(fandisk):
    V, F = symmetrize(*fandisk, axis=0)
    T = random_rigid(5, 1.0)
    s = detect_symmetry(apply_transform(T, V), F)
    n_true = T[:3, :3] @ np.array([1.0, 0, 0])
    assert abs(abs(s["normal"] @ n_true) - 1) < 1e-9
    assert s["residual"] < 1e-6
    assert detect_symmetry(*fandisk)["residual"] > 1.0  # measured 1.66
    with pytest.raises(MeshRepairError, match="samples"):
        detect_symmetry(V, F, samples=2)
    with pytest.raises(MeshRepairError, match="exclude_faces"):
        detect_symmetry(V, F, [len(F)])
    mask = np.zeros(len(F), bool)
    mask[:10] = True
    assert detect_symmetry(V, F, mask)["residual"] < 1e-6  # a boolean face mask


def _far_centers(V, F, k=2, seed=0):
    s = detect_symmetry(V, F)
    l = mean_edge_length(V, F)
    far = np.flatnonzero(np.abs((V - s["point"]) @ s["normal"]) > 6 * l)
    return np.random.default_rng(seed).choice(far, k, replace=False)


def mirror_errors(V, F, centers, radius_l=5.0):
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    out = []
    for c in centers:
        faces, d = geodesic(V, F, int(c), radius_l * l)
        Vd = damage(V, F, faces, d, radius_l * l, "dent")
        res = complete(Vd, F, faces, "mirror")
        assert check_mesh(res.V, res.F).is_closed
        out.append((point_to_surface(res.V, V, F).max() / diag, res))
    return out


def test_mirror_completion_on_a_symmetric_cad_mesh(fandisk):
    V, F = symmetrize(*fandisk, axis=0)
    for err, res in mirror_errors(V, F, _far_centers(V, F)):
        assert err < 1e-3  # measured <= 6e-5
        s = res.symmetry
        assert abs(abs(s["normal"][0]) - 1) < 1e-9 and s["residual"] < 1e-6
        assert res.params["template"] == "mirror"


def test_mirror_completion_of_an_existing_hole(fandisk):
    V, F = symmetrize(*fandisk, axis=0)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    c = int(_far_centers(V, F, k=1)[0])
    faces, _ = geodesic(V, F, c, 5 * mean_edge_length(V, F))
    Vh, Fh = extract_patch(V, F, np.setdiff1d(np.arange(len(F)), faces))
    res = complete(Vh, Fh, None, "mirror", hole=0)
    assert check_mesh(res.V, res.F).is_closed
    assert point_to_surface(res.V, V, F).max() / diag < 1e-3  # measured 9.4e-6
    # the mirrored rim of the hole's counterpart is left out of the residual
    assert res.symmetry["residual_max"] < 1e-6


def test_mirror_completion_picks_a_plane_the_region_does_not_straddle():
    """A triangular prism has 4 mirror planes; a region across its mid-height plane (the best
    one) is completed from a vertical mirror plane instead."""
    m = trimesh.creation.cylinder(radius=1.0, height=1.2, sections=3)
    for _ in range(4):
        m = m.subdivide()
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    target = np.r_[0.7 * np.array([1.0, 0.0]) + 0.3 * np.array([-0.5, np.sqrt(3) / 2]), 0.0]
    faces, d = geodesic(V, F, int(np.argmin(np.linalg.norm(V - target, axis=1))), 3 * l)
    z = V[np.unique(F[faces]), 2]
    assert z.min() < 0 < z.max()  # the region straddles z = 0
    res = complete(damage(V, F, faces, d, 3 * l, "spike"), F, faces, "mirror")
    assert abs(res.symmetry["normal"][2]) < 1e-6  # a vertical plane
    assert point_to_surface(res.V, V, F).max() / diag < 1e-3  # measured 7.1e-6


def test_mirror_completion_is_refused_on_a_non_symmetric_mesh(fandisk):
    V, F = fandisk
    l = mean_edge_length(V, F)
    faces, _ = geodesic(V, F, 3000, 5 * l)
    with pytest.raises(MeshRepairError, match=r"symmetry residual of 1\.\d+ mean edge lengths"):
        complete(V, F, faces, "mirror")
    with pytest.raises(MeshRepairError, match="max_symmetry_residual"):
        complete(V, F, faces, "mirror", max_symmetry_residual=0)
    with pytest.raises(MeshRepairError, match="max_symmetry_residual"):
        complete(V, F, faces, "mirror", max_symmetry_residual="x")
    with pytest.raises(MeshRepairError, match="'mirror'"):
        complete(V, F, faces, "mirrored")


def test_cli_mirror(tmp_path, fandisk, capsys):
    from meshrepair.commands import complete as cmd
    from meshrepair.io import write_mesh

    V, F = symmetrize(*fandisk, axis=0)
    c = int(_far_centers(V, F, k=1)[0])
    faces, _ = geodesic(V, F, c, 5 * mean_edge_length(V, F))
    inp = write_mesh(tmp_path / "sym.ply", V, F)
    reg = tmp_path / "region.txt"
    reg.write_text("\n".join(map(str, faces)))
    p = argparse.ArgumentParser()
    cmd.register(p.add_subparsers())
    out = tmp_path / "out.ply"
    args = p.parse_args(["complete", str(inp), str(out), "--region", str(reg), "--mirror",
                         "--iterations", "10"])
    assert args.func(args) == 0
    text = capsys.readouterr().out
    assert "symmetry plane" in text and "alignment residual" in text
    m = read_mesh(out)
    assert check_mesh(m.V, m.F).is_closed
    args = p.parse_args(["complete", str(inp), str(out), "--region", str(reg), "--mirror"])
    with pytest.raises(MeshRepairError, match="--force"):
        args.func(args)
    args = p.parse_args(["complete", str(inp), str(tmp_path / "o2.ply"), "--region", str(reg)])
    with pytest.raises(MeshRepairError, match="IN TEMPLATE OUT"):
        args.func(args)
    nonsym = write_mesh(tmp_path / "fan.ply", *fandisk)
    faces2, _ = geodesic(*fandisk, 2000, 5 * mean_edge_length(*fandisk))
    reg2 = tmp_path / "region2.txt"
    reg2.write_text(" ".join(map(str, faces2)))
    args = p.parse_args(["complete", str(nonsym), str(tmp_path / "o3.ply"), "--region",
                         str(reg2), "--mirror"])
    with pytest.raises(MeshRepairError, match="residual"):
        args.func(args)


# ----------------------------------------------------------------------------------------------
# shared meshes: spot (smooth), fandisk (CAD), trim_star


@pytest.mark.shared
@pytest.mark.parametrize("name,centers", [("spot.ply", (100, 1500, 2500)),
                                          ("fandisk.ply", (2000, 4000, 6000))])
def test_shared_self_completion_of_damaged_regions(name, centers):
    V, F = shared_mesh(name)
    for c in centers:
        for (kind, tname), (err, _) in self_completion_errors(V, F, c).items():
            assert err < 1e-3, (name, c, kind, tname, err)  # measured <= 3.3e-4


@pytest.mark.shared
def test_shared_mirror_completion_exactly_symmetric():
    """spot is mirror-symmetric as it is; fandisk made so by mirroring one half."""
    spot = shared_mesh("spot.ply")
    assert detect_symmetry(*spot)["residual"] < 1e-9
    fan = symmetrize(*shared_mesh("fandisk.ply"), axis=0)
    for V, F in (spot, fan):
        for err, _ in mirror_errors(V, F, _far_centers(V, F, k=3)):
            assert err < 1e-3  # measured <= 9.0e-4 (spot), 5.6e-5 (fandisk)


@pytest.mark.shared
def test_shared_mirror_completion_trim_star_and_refusal():
    """trim_star: symmetric on average (residual 0.005 l) but not everywhere (mirrored vertices
    up to 0.2 l from the surface = 3e-3 diag) and its halves are tessellated differently;
    measured 0.9e-3..1.5e-3 diag (the 1e-3 target is missed here, see docs/completion.md)."""
    V, F = shared_mesh("trim_star.ply")
    assert detect_symmetry(V, F, samples=10**6)["residual_max"] > 0.15  # measured 0.22
    for err, res in mirror_errors(V, F, _far_centers(V, F, k=3)):
        assert err < 2e-3
        assert res.symmetry["residual"] < 0.01
    V, F = shared_mesh("fandisk.ply")
    faces, _ = geodesic(V, F, 3000, 5 * mean_edge_length(V, F))
    with pytest.raises(MeshRepairError, match=r"residual of 1\.\d+ mean edge lengths"):
        complete(V, F, faces, "mirror")


def test_cli_template_region_uses_the_template_context(tmp_path, fandisk):
    """``--template-region`` makes the template a piece of its mesh: its context rings align it,
    and the summary reports the residual on them."""
    import json

    from meshrepair.commands import complete as cmd
    from meshrepair.io import write_mesh

    V, F = fandisk
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    faces, d = geodesic(V, F, 2000, 6 * l)
    inp = write_mesh(tmp_path / "dent.ply", damage(V, F, faces, d, 6 * l, "dent"), F)
    tpl = write_mesh(tmp_path / "moved.ply", apply_transform(random_rigid(3, 2 * diag), V), F)
    reg = tmp_path / "region.txt"
    reg.write_text("\n".join(map(str, faces)))
    p = argparse.ArgumentParser()
    cmd.register(p.add_subparsers())
    out, log = tmp_path / "out.ply", tmp_path / "run.json"
    args = p.parse_args(["complete", str(inp), str(tpl), str(out), "--region", str(reg),
                         "--template-region", str(reg), "--log", str(log), "-q"])
    assert args.func(args) == 0
    run = json.loads(log.read_text())
    assert run["correspondence"]["icp"]["target"] == "context"
    assert run["alignment"]["context_rms"] < 1e-9
    m = read_mesh(out)
    assert point_to_surface(m.V, V, F).max() / diag < 1e-3


def test_mirror_completion_commutes_with_a_rigid_motion(fandisk):
    """Moving the damaged mesh moves the result the same way (plane detection, cut, alignment
    and blending are all equivariant)."""
    V, F = symmetrize(*fandisk, axis=0)
    l = mean_edge_length(V, F)
    c = int(_far_centers(V, F, k=1)[0])
    faces, d = geodesic(V, F, c, 5 * l)
    Vd = damage(V, F, faces, d, 5 * l, "noise")
    T = random_rigid(11, 3.0)
    r0 = complete(Vd, F, faces, "mirror", iterations=20)
    r1 = complete(apply_transform(T, Vd), F, faces, "mirror", iterations=20)
    assert np.array_equal(r0.F, r1.F)
    np.testing.assert_allclose(r1.V, apply_transform(T, r0.V), atol=1e-6 * l)
    n0 = T[:3, :3] @ r0.symmetry["normal"]
    assert abs(abs(n0 @ r1.symmetry["normal"]) - 1) < 1e-9
