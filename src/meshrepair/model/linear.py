"""Solvers for the N-subproblem (25): ``(DᵀD + c I) N = B`` with three right-hand sides.

* ``"cg"``: block Jacobi-preconditioned conjugate gradients, warm-started from the previous N.
  The matrix is a weighted face-graph Laplacian plus ``c I`` with ``c = β2/β1 ≥ 1``; with Jacobi
  its condition number is small (≲ 10 on unit-edge meshes), so a handful of iterations suffice and
  the cost is linear in the mesh size.
* ``"direct"``: sparse Cholesky (cholespy when installed, else SuperLU from scipy),
  refactorised each call since the edge lengths in D change with V.
* ``"auto"``: ``"cg"`` at every size: warm-started, the system needs 3-6 PCG iterations per ADMM
  iteration, far cheaper than any refactorisation we measured (docs/performance.md).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from meshrepair import _kernels as _k

N_SOLVERS = ("auto", "cg", "direct")


class NormalSystem:
    """The matrix ``DᵀD + c I`` of (25) with a fixed sparsity pattern and cheap value updates.

    Only the interior edges couple faces: ``fa[e], fb[e]`` are the two faces of interior edge e.
    :meth:`matrix` refreshes the values in place from the squared edge lengths.
    """

    def __init__(self, fa: np.ndarray, fb: np.ndarray, n_faces: int, table=None):
        self.fa, self.fb, self.nF = fa, fb, n_faces
        self.M = None  # the sparse matrix, built on first use (direct solves only)
        # per-face neighbour table for the gather-form matrix-vector product (``table``: the
        # ``face_neighbour_table(fa, fb, n_faces)`` already built)
        self.nb, self.fe = (_k.face_neighbour_table(fa, fb, n_faces) if table is None
                            else table)

    def _build(self) -> None:
        fa, fb, nF = self.fa, self.fb, self.nF
        ar = np.arange(nF)
        self.rows = np.r_[fa, fb, ar]
        self.cols = np.r_[fb, fa, ar]
        M = sp.csr_matrix((np.arange(1, len(self.rows) + 1, dtype=np.float64),
                           (self.rows, self.cols)), shape=(nF, nF))
        M.sum_duplicates()
        self.perm = (M.data - 1).astype(np.int64) if M.nnz == len(self.rows) else None
        self.M = M

    def solve_cg(self, w: np.ndarray, c: float, B: np.ndarray, X0: np.ndarray, *,
                 rtol: float = 1e-5, maxiter: int = 200) -> tuple[np.ndarray, int]:
        """Jacobi-PCG on ``(DᵀD + c I) X = B`` from ``X0``; fused kernel when numba is present."""
        if not _k.HAVE_NUMBA:
            return block_pcg(self.matrix(w, c), B, X0, rtol=rtol, maxiter=maxiter)
        X = np.array(X0, dtype=np.float64, copy=True, order="C")
        it = _k._nb_pcg(self.nb, self.fe, np.ascontiguousarray(w, dtype=np.float64), float(c),
                        np.ascontiguousarray(B), X, rtol, maxiter)
        return X, int(it)

    def matrix(self, w: np.ndarray, c: float) -> sp.csr_matrix:
        """``DᵀD + c I`` for interior-edge weights ``w = l²``; returns the (reused) matrix."""
        if self.M is None:
            self._build()
        nF = self.nF
        diag = np.bincount(self.fa, w, nF) + np.bincount(self.fb, w, nF) + c
        vals = np.r_[-w, -w, diag]
        if self.perm is None:
            return sp.csr_matrix((vals, (self.rows, self.cols)), shape=(nF, nF))
        self.M.data[:] = vals[self.perm]
        return self.M


def block_pcg(A: sp.spmatrix, B: np.ndarray, X0: np.ndarray | None = None, *, rtol: float = 1e-6,
              maxiter: int = 200) -> tuple[np.ndarray, int]:
    """Jacobi-preconditioned CG for ``A X = B`` with all columns at once.

    CG runs on the Kronecker system ``(A ⊗ I) vec(X) = vec(B)``: step lengths come from
    Frobenius inner products, so rotating the columns of ``B`` rotates the iterates exactly (the
    solver is rotation-equivariant, not only its converged answer). Stops when
    ``||B - A X||_F <= rtol ||B||_F``.

    Parameters
    ----------
    A : (n, n) SPD sparse
    B : (n, k)
    X0 : (n, k), optional warm start

    Returns
    -------
    X : (n, k)
    iterations : int
    """
    A = sp.csr_matrix(A)
    dinv = 1.0 / A.diagonal()
    X = np.zeros_like(B) if X0 is None else np.array(X0, dtype=np.float64, copy=True)
    R = B - A @ X
    tol2 = rtol**2 * max(float(np.einsum("ij,ij->", B, B)), 1e-300)
    Z = dinv[:, None] * R
    P = Z.copy()
    rz = float(np.einsum("ij,ij->", R, Z))
    rn = float(np.einsum("ij,ij->", R, R))
    it = 0
    while it < maxiter and rn > tol2:
        AP = A @ P
        pap = float(np.einsum("ij,ij->", P, AP))
        if pap <= 0:
            break
        alpha = rz / pap
        X += alpha * P
        R -= alpha * AP
        Z = dinv[:, None] * R
        rz_new = float(np.einsum("ij,ij->", R, Z))
        rn = float(np.einsum("ij,ij->", R, R))
        P = Z + (rz_new / rz if rz > 0 else 0.0) * P
        rz = rz_new
        it += 1
    return X, it


def direct_solve(A: sp.spmatrix, B: np.ndarray) -> np.ndarray:
    """Factorise the SPD ``A`` once and solve for all columns of ``B``.

    Uses cholespy's sparse Cholesky (CHOLMOD-based, wheels on PyPI: ``pip install cholespy``)
    when installed, else scipy's SuperLU. On a 29k-face system: cholespy 0.34 s,
    SuperLU 8.7 s, warm-started PCG 3-5 iterations ≈ 0.01 s (docs/performance.md).
    """
    A = sp.csc_matrix(A)
    B = np.ascontiguousarray(B, dtype=np.float64)
    try:
        from cholespy import CholeskySolverD, MatrixType  # type: ignore[import-not-found]
    except ImportError:
        from scipy.sparse.linalg import splu

        return splu(A, permc_spec="MMD_AT_PLUS_A").solve(B)
    solver = CholeskySolverD(A.shape[0], A.indptr.astype(np.int32), A.indices.astype(np.int32),
                             A.data.astype(np.float64), MatrixType.CSC)
    X = np.zeros_like(B)
    solver.solve(B, X)
    return X


def solve_normals(A: sp.spmatrix, B: np.ndarray, X0: np.ndarray | None, *, method: str = "auto",
                  rtol: float = 1e-6) -> tuple[np.ndarray, int]:
    """Solve (25) by ``method`` (one of :data:`N_SOLVERS`); returns ``(N, iterations)``."""
    if method in ("auto", "cg"):
        return block_pcg(A, B, X0, rtol=rtol)
    if method == "direct":
        return direct_solve(A, B), 1
    raise ValueError(f"unknown N solver {method!r}; choose one of {N_SOLVERS}")
