"""Solvers for the N-subproblem (25): ``(DᵀD + c I) N = B`` with three right-hand sides.

* ``"cg"``: block Jacobi-preconditioned conjugate gradients, warm-started from the previous N.
  The matrix is a weighted face-graph Laplacian plus ``c I`` with ``c = β2/β1 ≥ 1``; with Jacobi
  its condition number is small (≲ 10 on unit-edge meshes), so a handful of iterations suffice and
  the cost is linear in the mesh size.
* ``"direct"``: sparse Cholesky (CHOLMOD via scikit-sparse when installed, else SuperLU from
  scipy), refactorised each call since the edge lengths in D change with V.
* ``"auto"``: ``"cg"`` (measured faster per ADMM iteration than refactorising at every size we
  tried; see docs/performance.md).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

N_SOLVERS = ("auto", "cg", "direct")


def block_pcg(A: sp.spmatrix, B: np.ndarray, X0: np.ndarray | None = None, *, rtol: float = 1e-6,
              maxiter: int = 200) -> tuple[np.ndarray, int]:
    """Jacobi-preconditioned CG on all columns of ``B`` at once (one sparse product per step).

    Stops when every column satisfies ``||B - A X|| <= rtol ||B||``.

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
    X = np.zeros_like(B) if X0 is None else X0.copy()
    R = B - A @ X
    bn = np.maximum(np.sqrt(np.einsum("ij,ij->j", B, B)), 1e-300)
    Z = dinv[:, None] * R
    P = Z.copy()
    rz = np.einsum("ij,ij->j", R, Z)
    for it in range(maxiter):
        rn = np.sqrt(np.einsum("ij,ij->j", R, R))
        if np.all(rn <= rtol * bn):
            return X, it
        AP = A @ P
        pap = np.einsum("ij,ij->j", P, AP)
        alpha = np.where(pap > 0, rz / np.where(pap > 0, pap, 1.0), 0.0)
        X += alpha * P
        R -= alpha * AP
        Z = dinv[:, None] * R
        rz_new = np.einsum("ij,ij->j", R, Z)
        beta = np.where(rz > 0, rz_new / np.where(rz > 0, rz, 1.0), 0.0)
        P = Z + beta * P
        rz = rz_new
    return X, maxiter


def direct_solve(A: sp.spmatrix, B: np.ndarray) -> np.ndarray:
    """Factorise ``A`` once and solve for all columns of ``B``."""
    try:  # optional, fastest when available
        from sksparse.cholmod import cholesky  # type: ignore[import-not-found]

        return cholesky(sp.csc_matrix(A))(B)
    except ImportError:
        from scipy.sparse.linalg import splu

        lu = splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A")
        return lu.solve(np.asarray(B))


def solve_normals(A: sp.spmatrix, B: np.ndarray, X0: np.ndarray | None, *, method: str = "auto",
                  rtol: float = 1e-6) -> tuple[np.ndarray, int]:
    """Solve (25) by ``method`` (one of :data:`N_SOLVERS`); returns ``(N, iterations)``."""
    if method in ("auto", "cg"):
        return block_pcg(A, B, X0, rtol=rtol)
    if method == "direct":
        return direct_solve(A, B), 1
    raise ValueError(f"unknown N solver {method!r}; choose one of {N_SOLVERS}")
