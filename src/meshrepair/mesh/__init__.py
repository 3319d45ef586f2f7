"""The triangle mesh and its discrete operators: topology (edges, edge-face incidence, boundary
loops, components), geometry (normals, areas, dihedral angles, the sharp-edge mask M_E of (5)),
the operators D̄ and D = L·D̄ of (4) and the edge-Willmore energy (8), input validation and the
``(V, F)`` array contract, the Morton reordering of large meshes, and the
interpolation of per-vertex values onto new vertices (``attributes``: colours and texture
coordinates on filled patches).

May import: ``meshrepair.errors``, ``meshrepair.options``, ``meshrepair._kernels``. Imported by
every task and by ``meshrepair.model``; it imports no task.
"""
