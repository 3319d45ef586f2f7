"""Interactive 3-D viewer: one self-contained HTML file with side-by-side, camera-linked panes.

``meshrepair view A.ply B.ply -o view.html`` and every ``--report`` use it. See
:mod:`meshrepair.viewer.page` for the page layout, :mod:`meshrepair.viewer.decimate` for the
display copies of big meshes and ``vendor/README.md`` for how three.js is vendored.
"""

from meshrepair.viewer.decimate import Decimation, cluster_decimate
from meshrepair.viewer.page import (
    DEFAULT_FACE_BUDGET,
    ViewerMesh,
    viewer_page,
    viewer_section,
    write_viewer,
)

__all__ = [
    "DEFAULT_FACE_BUDGET",
    "Decimation",
    "ViewerMesh",
    "cluster_decimate",
    "viewer_page",
    "viewer_section",
    "write_viewer",
]
