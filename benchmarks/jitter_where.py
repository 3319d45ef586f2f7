"""Where the main solve parts two runs whose inputs differ by a 1e-10 · diagonal jitter.

Runs ``denoise`` on a case's noisy input and on its jittered copy (the jittered plan reads the
first plan's probe, as ``jitter.py --share-probe``), records every V-subproblem call of the main
solve, and prints per ADMM iteration: the largest difference of the two runs' V before and after
the V-step (mean edge lengths), its median, the largest difference of ``z = ρ2 - β2 N``, the
faces folded against their target normal before / after the V-step, how many of the 20 vertices
that differ most touch such a face, and the Armijo step of the two runs; then, for iterations 1-3,
the four vertices that differ most with the area ``|c|`` and ``cos(N, n)`` of their faces before
and after the step.

    python benchmarks/jitter_where.py noisy/fandisk__gauss0.7
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402
import jitter as J  # noqa: E402


def _solves(rec):
    out, cur = [], None
    for r in rec:
        if cur is None or r[0] != cur:
            out.append([])
            cur = r[0]
        out[-1].append(r)
    return out


def _faces(V, z, F):
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    q = np.linalg.norm(c, axis=1)
    Nt = -z / np.maximum(np.linalg.norm(z, axis=1), 1e-300)[:, None]
    return q, np.einsum("ij,ij->i", Nt, c) / np.maximum(q, 1e-300)


def main(argv=None) -> None:
    import meshrepair.model.solver.admm as A
    from meshrepair import denoise, plan_denoise

    args = sys.argv[1:] if argv is None else argv
    case = args[0] if args else "noisy/fandisk__gauss0.7"
    noisy = case + "__noisy" if case.startswith("published/") else case
    Vn, F, _ = C.read(noisy)
    C.limit_threads(1)
    rec = []
    run_inner = A.run_inner

    def recording(name, prob, V, iters, state):
        out = run_inner(name, prob, V, iters, state)
        rec.append((id(prob), V.copy(), out.copy(), prob.z.copy(), state.step))
        return out

    A.run_inner = recording
    try:
        p0 = plan_denoise(Vn, F)
        rec.clear()
        denoise(Vn, F, plan=p0)
        s0 = _solves(rec)
        p1 = J._jittered_plan(J.jitter(Vn, 1e-10, 0), F, p0, {}, True)
        rec.clear()
        denoise(J.jitter(Vn, 1e-10, 0), F, plan=p1)
        s1 = _solves(rec)
    finally:
        A.run_inner = run_inner
    a, b = s0[-1], s1[-1]
    print(f"{case}: main solve {len(a)} / {len(b)} V-steps")
    for k, (ra, rb) in enumerate(zip(a[:30], b[:30], strict=False)):
        d = np.linalg.norm(ra[2] - rb[2], axis=1)
        din = np.linalg.norm(ra[1] - rb[1], axis=1)
        _, ci = _faces(ra[1], ra[3], F)
        _, co = _faces(ra[2], ra[3], F)
        touch = np.zeros(len(Vn), bool)
        touch[F[ci < 0].ravel()] = True
        dz = np.linalg.norm(ra[3] - rb[3], axis=1).max()
        print(f"it {k:3d} max|dV| in {din.max():.2e} out {d.max():.2e} median {np.median(d):.1e}"
              f" max|dz| {dz:.2e} folded in/out {int(np.sum(ci < 0))}/{int(np.sum(co < 0))}"
              f" top20 touching folded {int(touch[np.argsort(-d)[:20]].sum())}"
              f" step {ra[4]:.3g}/{rb[4]:.3g}")
    vf = [[] for _ in range(len(Vn))]
    for m, f in enumerate(F):
        for v in f:
            vf[v].append(m)
    for k in (1, 2, 3):
        ra, rb = a[k], b[k]
        d = np.linalg.norm(ra[2] - rb[2], axis=1)
        qi, ci = _faces(ra[1], ra[3], F)
        qo, co = _faces(ra[2], ra[3], F)
        for v in np.argsort(-d)[:4]:
            faces = " ".join(f"[|c| {qi[m]:.2f}->{qo[m]:.3f} cos {ci[m]:+.2f}->{co[m]:+.2f}]"
                             for m in vf[v])
            print(f"it {k} vertex {v}: |dV| {d[v]:.1e}, moved "
                  f"{np.linalg.norm(ra[2][v] - ra[1][v]):.2f}; faces {faces}")


if __name__ == "__main__":
    main()
