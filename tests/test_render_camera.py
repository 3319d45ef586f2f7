"""The default camera shows the object's front with its up vertical; a given view direction keeps
the object's up; both deterministic and independent of the vertex order."""

import numpy as np
import pytest
import trimesh

from meshrepair.render import render_mesh
from meshrepair.render.autocam import default_view, object_up
from meshrepair.render.camera import _aim

WHITE = 250


def _bust(up_axis: str, facing: np.ndarray):
    """An open scan of a standing half-cylinder (radius 0.5, height 3): its outside faces look
    along ``facing`` (the scanner side); long axis along world ``up_axis``."""
    c = trimesh.creation.cylinder(radius=0.5, height=3.0, sections=48)
    c = c.subdivide().subdivide()
    V, F = np.asarray(c.vertices), np.asarray(c.faces)
    n = c.face_normals
    keep = (n @ np.array([0.0, -1.0, 0.0]) > 0.05) & (np.abs(n[:, 2]) < 0.5)  # front half, z-up
    sub = trimesh.Trimesh(V, F[keep], process=False)
    sub.remove_unreferenced_vertices()
    V, F = np.asarray(sub.vertices), np.asarray(sub.faces, np.int64)
    # rotate: z -> up_axis, -y -> facing
    up = {"y": np.array([0.0, 1.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}[up_axis]
    front = np.asarray(facing, float)
    R = np.stack([np.cross(-front, up), -front, up], axis=1)  # a rotation: columns x, y, z
    return V @ R.T, F


def _toward_viewer(V, F, **kw):
    axes, _, _ = _aim(kw.get("azimuth"), kw.get("elevation"), kw.get("view_dir"), None, None,
                      True, V, F)
    return axes


@pytest.mark.parametrize(("up_axis", "facing"), [("y", [0, 0, -1]), ("y", [0, 0, 1]),
                                                 ("z", [0, -1, 0]), ("z", [1, 0, 0])])
def test_default_camera_sees_the_front_of_a_scan_upright(up_axis, facing):
    V, F = _bust(up_axis, np.array(facing, float))
    n = trimesh.Trimesh(V, F, process=False).face_normals
    assert (n @ np.array(facing, float)).mean() > 0.5  # the scan looks along `facing`
    axes = _toward_viewer(V, F)
    assert axes[2] @ np.array(facing, float) > 0.99  # the camera sits on the scan's front
    up = {"y": [0, 1, 0], "z": [0, 0, 1]}[up_axis]
    assert axes[1] @ np.array(up, float) > 0.99  # and the scan stands upright in the picture
    # in the picture: the top third of the scan is drawn in the upper part of the image
    top = (V @ np.array(up, float)) > 0.5
    img = render_mesh(V, F, region_mask=top, color_by="none", width=120, height=120,
                      colorbar=False).astype(int)
    blue = (img[..., 2] - img[..., 0]) > 60
    assert blue.sum() > 100 and blue[:60].sum() > 0.95 * blue.sum()


def test_old_default_saw_a_y_up_scan_facing_minus_z_from_behind():
    # the case of the issue: azimuth 0 looks along -z, at the back of this scan
    V, F = _bust("y", np.array([0.0, 0.0, -1.0]))
    assert _toward_viewer(V, F, azimuth=0.0)[2] @ np.array([0, 0, -1.0]) < -0.99
    assert _toward_viewer(V, F)[2] @ np.array([0, 0, -1.0]) > 0.99


@pytest.mark.parametrize("view_dir", [[0, -1, 0], [0, 1, 0], [1, 0, 0], [-1, 0.2, 0]])
def test_given_view_dir_keeps_a_z_up_object_upright(view_dir):
    V, F = _bust("z", np.array([0.0, -1.0, 0.0]))
    assert object_up(V, F) @ np.array([0, 0, 1.0]) > 0.99
    axes = _toward_viewer(V, F, view_dir=view_dir)
    assert axes[1][2] > 0.95  # +z is up in the picture, never down


def test_closed_objects_keep_the_world_default_when_round():
    s = trimesh.creation.icosphere(3)
    d, up = default_view(s.vertices, s.faces)
    assert np.allclose(d, [0, 0, -1]) and np.allclose(up, [0, 1, 0])
    box = trimesh.creation.box([4.0, 2.0, 1.0])  # flat along z: seen from +z, its largest side
    d, up = default_view(box.vertices, box.faces)
    assert np.allclose(d, [0, 0, -1]) and np.allclose(up, [0, 1, 0])


def test_default_camera_is_deterministic_and_independent_of_the_order():
    V, F = _bust("z", np.array([0.6, -0.8, 0.0]))
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(V))
    inv = np.argsort(perm)
    V2, F2 = V[perm], inv[F][rng.permutation(len(F))]
    F2 = np.roll(F2, 1, axis=1)  # corners rotated: same faces, same orientation
    kw = dict(color_by="none", width=100, height=100, colorbar=False)
    a, b = _toward_viewer(V, F), _toward_viewer(V2, F2)
    assert np.allclose(a, b, atol=1e-9)
    img1 = render_mesh(V, F, **kw)
    assert np.array_equal(img1, render_mesh(V, F, **kw))
    assert np.count_nonzero(np.any(img1 != render_mesh(V2, F2, **kw), axis=2)) <= 20
