"""Fused per-element kernels of the hot loop, compiled with numba when it is installed.

Each kernel has a pure-numpy twin with identical results (checked in ``tests/test_kernels.py``);
the numpy path is used when numba is missing or ``MESHREPAIR_NO_NUMBA=1`` is set. Profiling showed
the V-subproblem energy/gradient (gather, cross, normalise, dot, scatter over faces) and the
edge gathers dominating an ADMM iteration; fusing them removes the temporaries (see
docs/performance.md).
"""

from __future__ import annotations

# split by concept: _jit (numba detection, njit, FASTMATH), faces (per-face geometry), venergy
# (the V-subproblem), edges (per-edge gathers), admm (PCG, t update, multipliers, regulariser),
# connectivity, patterns, tables (setup kernels: grouping and union-find, sparse patterns,
# per-element tables); every name is re-exported here. tstep (the t-update from N in one pass),
# fidelity (the tangential anchor) and priors (the flat-TV / per-edge-weight t-update) are
# imported from their modules.
from meshrepair._kernels._jit import CACHE_DISABLED, FASTMATH, HAVE_NUMBA, njit  # noqa: F401
from meshrepair._kernels.admm import (  # noqa: F401
    _np_normalize_z,
    _np_reg_energy,
    _np_rhs,
    _np_sqdist,
    _np_update_rho1,
    _np_update_rho2,
    normalize_z,
    reg_energy,
    rhs,
    sqdist,
    update_rho1,
    update_rho2,
)
from meshrepair._kernels.connectivity import (  # noqa: F401
    _np_edges_from_groups,
    _np_face_neighbour_table,
    _np_group_halfedges,
    _np_morton,
    _np_pair_order,
    _np_union_find,
    creased,
    edges_from_groups,
    face_neighbour_table,
    group_halfedges,
    morton,
    pair_order,
    union_find,
)
from meshrepair._kernels.edges import (  # noqa: F401
    _np_edge_lengths,
    _np_edge_lengths_exact,
    _np_grad_edges,
    _np_grad_edges_T,
    _np_umbrella,
    edge_lengths,
    edge_lengths_exact,
    grad_edges,
    grad_edges_T,
    neighbor_sum,
    umbrella,
)
from meshrepair._kernels.faces import (  # noqa: F401
    _np_face_area2_lmax2,
    _np_face_centroids,
    _np_face_normals,
    _np_folded,
    _np_min_corner_cos,
    _np_vertex_normals,
    face_area2_lmax2,
    face_centroids,
    face_normals,
    folded,
    min_corner_cos,
    vertex_normals,
)
from meshrepair._kernels.patterns import (  # noqa: F401
    _np_face_neighbours,
    _np_face_side_csr,
    _np_product_pattern,
    _np_sym_csr,
    _np_umbrella_entries,
    edge_csr,
    face_neighbours,
    face_side_csr,
    product_pattern,
    sym_csr,
    umbrella_entries,
)
from meshrepair._kernels.tables import (  # noqa: F401
    _np_creased_edges,
    _np_duplicate_rows,
    _np_edge_tables,
    _np_fan_counts,
    _np_grow,
    _np_interior_edges,
    _np_permuted_edges,
    _np_renumbered_faces,
    creased_edges,
    duplicate_rows,
    edge_tables,
    fan_counts,
    grow,
    interior_edges,
    permuted_edges,
    renumbered_faces,
)
from meshrepair._kernels.venergy import (  # noqa: F401
    _np_venergy,
    _np_venergy_grad,
    _np_vhess_diag,
    venergy,
    venergy_grad,
    vhess_diag,
)

if HAVE_NUMBA:
    from meshrepair._kernels.admm import (  # noqa: F401
        _nb_lap_matvec_dot,
        _nb_normalize_z,
        _nb_pcg,
        _nb_reg_energy,
        _nb_rhs,
        _nb_sqdist,
        _nb_t_update,
        _nb_update_rho1,
        _nb_update_rho2,
    )
    from meshrepair._kernels.connectivity import (  # noqa: F401
        _nb_creased,
        _nb_edges_from_groups,
        _nb_face_neighbour_table,
        _nb_group_halfedges,
        _nb_morton,
        _nb_pair_order,
        _nb_union_find,
    )
    from meshrepair._kernels.edges import (  # noqa: F401
        _nb_edge_lengths,
        _nb_edge_lengths_exact,
        _nb_grad_edges,
        _nb_grad_edges_T,
        _nb_neighbor_sum,
        _nb_umbrella,
    )
    from meshrepair._kernels.faces import (  # noqa: F401
        _nb_face_area2_lmax2,
        _nb_face_centroids,
        _nb_face_normals,
        _nb_folded,
        _nb_min_corner_cos,
        _nb_vertex_normals,
        _tri,
    )
    from meshrepair._kernels.patterns import (  # noqa: F401
        _nb_face_neighbours,
        _nb_face_side_csr,
        _nb_product_pattern,
        _nb_sorted_edge_csr,
        _nb_sym_csr,
        _nb_umbrella_entries,
    )
    from meshrepair._kernels.tables import (  # noqa: F401
        _nb_creased_edges,
        _nb_duplicate_rows,
        _nb_edge_tables,
        _nb_fan_counts,
        _nb_grow,
        _nb_interior_edges,
        _nb_permuted_edges,
        _nb_renumbered_faces,
    )
    from meshrepair._kernels.venergy import _nb_venergy, _nb_venergy_grad, _nb_vhess_diag  # noqa: F401
