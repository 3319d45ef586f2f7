"""A local surface fitted to the surround of a hole, and the fairing of a patch relative to it.

**Fit** (:func:`fit_surround`). The loop's best-fit plane (centroid ``o``, principal directions
``e1, e2``, normal ``n`` oriented with the surround's vertex normals) carries a height field
``h = q(u, v)``, ``q`` a polynomial of total degree ``d`` in the scaled coordinates
``(u / R, v / R)`` (``R`` the loop's RMS radius in the plane), fitted by least squares to the
original vertices within ``k`` rings of the loop. Vertices whose normal makes more than
:data:`FOLD_ANGLE` with ``n`` are left out: there the surround folds over the plane and is no
height field over it (the other side of a fold must not pull the patch across it).

The degree ``d ∈`` :data:`FIT_DEGREES` and the scale ``k = max(2, round(s R / l̄))``,
``s ∈`` :data:`FIT_SCALES` (``l̄`` the loop's mean edge length), are chosen together by
cross-validation on the ring (a candidate must lower the error of the best simpler one by
:data:`FIT_GAIN`): the data are split into :data:`FIT_SECTORS` angular sectors round
``o``; each sector is predicted by the fit to the others, and the score is the RMS error of the
predictions at the held-out vertices within 2 rings of the loop. A held-out sector is a gap of
the surround as wide as a part of the hole, so the score measures what the fit is used for:
carrying the surround across a gap. Degree 1 (the plane) is one of the candidates; where it
wins, the fit adds nothing to the fairing and is not used.

Everything is expressed in the loop's frame and in units of ``R`` and ``l̄``: the fit is
invariant under rotations, translations and uniform scaling of the mesh, and it reproduces
exactly a surround that is a polynomial height field of degree ``≤ 3`` over the loop's plane.

**Fairing relative to the fit** (:func:`fair_on_fit`). The map
``T(x) = x - q(u(x), v(x)) n`` (a shear along ``n``, inverted exactly by adding ``q`` back)
takes the fitted surface to the plane. The patch and its surround are mapped by ``T``, the
patch is faired there by the model's curvature-continuous thin plate
(:func:`meshrepair.holes.fair_vertices`) with the surround as Dirichlet data, and mapped back.
The fairing then only interpolates the residual of the surround against the fit (zero for a
surround the fit reproduces), so the patch follows the fitted surface inside the hole and meets
the surround with continuous position and tangent plane at the loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FIT_DEGREES = (1, 2, 3)
"""Polynomial degrees of the height field tried by the cross-validation (1: the plane)."""

FIT_SCALES = (0.5, 1.0, 2.0)
"""Data radii tried, in loop radii ``R``: the rings ``k = max(2, round(s R / l̄))``."""

FIT_SECTORS = 8
"""Angular sectors of the cross-validation."""

FOLD_ANGLE = 75.0
"""Vertices whose normal is more than this many degrees from the plane's normal are not data."""

PROBE_BAND = 0.5
"""Width of the probe band, in loop radii: ``j = max(2, round(PROBE_BAND R / l̄))`` rings."""
PROBE_BAND_MAX = 64

FIT_GAIN = 0.9
"""A candidate replaces the best so far only when its cross-validation error is below this
fraction of it (candidates in order of scale, then degree)."""

_MIN_PER_TERM = 3  # data points per polynomial coefficient in every training set


@dataclass
class LocalFit:
    """A polynomial height field over a plane: ``x = o + u e1 + v e2 + q(u, v) n``."""

    origin: np.ndarray  # (3,)
    frame: np.ndarray  # (3, 3): rows e1, e2, n
    radius: float  # R: coordinates are scaled by 1/R in the polynomial
    degree: int
    coef: np.ndarray  # polynomial coefficients (see _monomials), heights in units of R
    rings: int  # rings of data used
    cv: float  # cross-validation RMS error (in units of R)
    cv_plane: float  # the plane's cross-validation error (same units)

    def local(self, X: np.ndarray) -> np.ndarray:
        """(n, 3) coordinates ``(u, v, h)`` / R in the frame."""
        return (np.asarray(X, float) - self.origin) @ self.frame.T / self.radius

    def height(self, X: np.ndarray) -> np.ndarray:
        """Fitted height ``q(u, v)`` (in the mesh's units) at the projections of ``X``."""
        L = self.local(X)
        return _monomials(L[:, 0], L[:, 1], self.degree) @ self.coef * self.radius

    def flatten(self, X: np.ndarray) -> np.ndarray:
        """``T(X) = X - q(u, v) n``: the fitted surface mapped to the plane."""
        return np.asarray(X, float) - self.height(X)[:, None] * self.frame[2]

    def unflatten(self, Y: np.ndarray) -> np.ndarray:
        """The inverse of :meth:`flatten` (``u, v`` are unchanged by the shear)."""
        return np.asarray(Y, float) + self.height(Y)[:, None] * self.frame[2]


def _monomials(u: np.ndarray, v: np.ndarray, degree: int) -> np.ndarray:
    """(n, (d+1)(d+2)/2) monomials ``u^a v^b``, ``a + b <= degree``."""
    cols = [u ** (t - b) * v ** b for t in range(degree + 1) for b in range(t + 1)]
    return np.stack(cols, axis=1)


def _lstsq(A: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(A, y, rcond=None)[0]


def fit_surround(X: np.ndarray, ring: np.ndarray, normals: np.ndarray, loop_xyz: np.ndarray,
                 edge_length: float) -> LocalFit | None:
    """Fit the height field of the module docstring.

    Parameters
    ----------
    X : (m, 3) float
        Original vertices near the loop (the loop itself included).
    ring : (m,) int
        Their ring distance from the loop (0 on the loop).
    normals : (m, 3) float
        Their unit normals (orientation of the surface).
    loop_xyz : (k, 3) float
        The loop's vertices.
    edge_length : float
        The loop's mean edge length ``l̄``.

    Returns
    -------
    LocalFit, or None when the data cannot support any fit (too few points).
    """
    X = np.asarray(X, float)
    ring = np.asarray(ring, np.int64)
    P = np.asarray(loop_xyz, float)
    if len(P) < 3 or len(X) < 10:
        return None
    o = P.mean(axis=0)
    _, s, vt = np.linalg.svd(P - o, full_matrices=False)
    frame = vt.copy()
    nsum = np.asarray(normals, float)[ring <= 2].sum(axis=0)  # the surround next to the loop
    if nsum @ frame[2] < 0:
        frame[2] = -frame[2]
        frame[1] = -frame[1]  # keep the frame right-handed
    R = float(np.sqrt((((P - o) @ frame[:2].T) ** 2).sum(axis=1).mean()))
    if not R > 0 or not edge_length > 0:
        return None
    ok = np.asarray(normals, float) @ frame[2] >= np.cos(np.radians(FOLD_ANGLE))
    L = (X - o) @ frame.T / R
    u, v, h = L[:, 0], L[:, 1], L[:, 2]
    sector = np.floor((np.arctan2(v, u) + np.pi) / (2 * np.pi) * FIT_SECTORS).astype(np.int64)
    sector = np.clip(sector, 0, FIT_SECTORS - 1)
    best = None
    cv_plane = np.inf
    for scale in FIT_SCALES:
        k = max(2, int(round(scale * R / edge_length)))
        use = ok & (ring <= k)
        for d in FIT_DEGREES:
            nt = (d + 1) * (d + 2) // 2
            A = _monomials(u, v, d)
            err, cnt, valid = 0.0, 0, True
            for sct in range(FIT_SECTORS):
                tr = use & (sector != sct)
                te = use & (sector == sct) & (ring <= 2)
                if not te.any():
                    continue
                if tr.sum() < _MIN_PER_TERM * nt:
                    valid = False
                    break
                c = _lstsq(A[tr], h[tr])
                err += float(((A[te] @ c - h[te]) ** 2).sum())
                cnt += int(te.sum())
            if not valid or cnt == 0:
                continue
            cv = float(np.sqrt(err / cnt))
            if d == 1:
                cv_plane = min(cv_plane, cv)
            # a more complex model must predict clearly better (ties, as on exact data, go to
            # the lower degree and the smaller scale)
            if best is None or cv < FIT_GAIN * best[0] - 1e-12:
                best = (cv, d, k)
    if best is None:
        return None
    cv, d, k = best
    use = ok & (ring <= k)
    c = _lstsq(_monomials(u[use], v[use], d), h[use])
    return LocalFit(origin=o, frame=frame, radius=R, degree=d, coef=c, rings=k, cv=cv,
                    cv_plane=float(cv_plane))


def _rings_from(F: np.ndarray, seed: np.ndarray, nV: int, k: int) -> np.ndarray:
    """Ring distance (0..k) of every vertex from the ``seed`` vertices over ``F``; ``k + 1``
    beyond."""
    d = np.full(nV, k + 1, np.int64)
    cur = np.zeros(nV, bool)
    cur[seed] = True
    d[cur] = 0
    for r in range(1, k + 1):
        nxt = np.zeros(nV, bool)
        nxt[F[cur[F].any(axis=1)].ravel()] = True
        nxt &= d > r
        if not nxt.any():
            break
        d[nxt] = r
        cur |= nxt
    return d


def hole_rings(F_orig: np.ndarray, loop: np.ndarray, nV_orig: int, V: np.ndarray
               ) -> tuple[np.ndarray, float, float]:
    """``(d, l̄, R)``: ring distance of the original vertices from ``loop`` (up to the largest
    data scale, ``kmax + 1`` beyond), the loop's mean edge length and RMS radius."""
    loop = np.asarray(loop, np.int64)
    le = float(np.linalg.norm(V[loop] - V[np.roll(loop, -1)], axis=1).mean())
    P = V[loop]
    R = float(np.sqrt(((P - P.mean(axis=0)) ** 2).sum(axis=1).mean()))
    kmax = max(2, int(round(max(FIT_SCALES) * R / max(le, 1e-300)))) + PROBE_BAND_MAX
    return _rings_from(F_orig, loop, nV_orig, kmax), le, R


def fit_hole(V: np.ndarray, F_orig: np.ndarray, d: np.ndarray, le: float, nV_orig: int,
             band: int = 0, exclude: np.ndarray | None = None) -> LocalFit | None:
    """:func:`fit_surround` on the original surface round a loop (``d`` its ring distances from
    :func:`hole_rings`, ``F_orig`` the original faces, vertices below ``nV_orig`` original),
    using only the vertices at ring ``>= band`` (the vertices at ring ``band`` play the loop);
    ``exclude`` (bool over the original vertices): vertices that are no data (on sharp edges).
    None when the fit is not better than the plane."""
    from meshrepair.holes.fairing import _vertex_normals

    kmax = int(d.max()) - 1
    near = np.flatnonzero((d <= kmax) & (d >= band))
    if exclude is not None:
        near = near[~np.asarray(exclude, bool)[near]]
    fm = (d[F_orig] <= kmax).all(axis=1)
    N = _vertex_normals(V[:nV_orig], F_orig[fm], nV_orig)[near]
    P = V[near[d[near] == band]]
    fit = fit_surround(V[near], d[near] - band, N, P, le)
    if fit is None or fit.degree == 1 or not fit.cv < fit.cv_plane:
        return None
    return fit


def fair_on_fit(V: np.ndarray, F: np.ndarray, free: np.ndarray, fit: LocalFit | None, *,
                rings: int = 5, fair=None, **fair_options) -> np.ndarray:
    """Fair the ``free`` vertices relative to ``fit`` (module docstring): map the faces within
    ``rings`` of them by ``T`` (``fit=None``: the identity), run ``fair(V, F, free,
    **fair_options)`` (default :func:`meshrepair.holes.fair_vertices`) on that submesh, map
    back.
    Returns a new ``V`` (only ``free`` rows differ). ``fair_options`` index arrays
    (``exclude_rows``, ``curvature_exclude``) are global vertex indices."""
    from meshrepair.holes import fair_vertices

    fair = fair_vertices if fair is None else fair
    free = np.asarray(free, np.int64)
    d = _rings_from(F, free, len(V), rings)
    fsub = (d[F] <= rings).all(axis=1)
    Fs = F[fsub]
    vs = np.unique(Fs)
    loc = -np.ones(len(V), np.int64)
    loc[vs] = np.arange(len(vs))
    opts = {}
    for key, val in fair_options.items():
        if key in ("exclude_rows", "curvature_exclude") and val is not None:
            m = np.zeros(len(V), bool)
            m[np.asarray(val)] = True
            val = np.flatnonzero(m[vs])
        opts[key] = val
    Y = fit.flatten(V[vs]) if fit is not None else np.array(V[vs], float)
    Y = fair(Y, loc[Fs], loc[free], **opts)
    out = np.array(V, float, copy=True)
    out[free] = fit.unflatten(Y[loc[free]]) if fit is not None else Y[loc[free]]
    return out
