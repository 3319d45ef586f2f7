"""The model profiles of meshrepair.denoise.scale walk one chain W^n Z; they equal the definition
``c_k(m) = MAD-std((W^m Z - W^k W^m Z)[ok])``, ``σ_m = rms(W^m Z [ok])`` bit for bit."""

import numpy as np
import trimesh

from meshrepair.denoise import scale as S
from meshrepair.mesh.topology import edge_topology


def _reference(W, ks, ok, Z):
    C = np.zeros((len(S.CANDIDATE_STEPS), len(ks)))
    sig = np.zeros(len(S.CANDIDATE_STEPS))
    for i, m in enumerate(S.CANDIDATE_STEPS):
        Zm = Z
        for _ in range(m):
            Zm = W @ Zm
        sig[i] = np.sqrt(np.mean(Zm[ok] ** 2))
        for j, k in enumerate(ks):
            Zk = Zm
            for _ in range(k):
                Zk = W @ Zk
            x = (Zm - Zk)[ok].ravel()
            C[i, j] = 1.4826 * np.median(np.abs(x - np.median(x)))
    return C, sig


def test_model_profiles_equal_their_definition():
    m = trimesh.creation.icosphere(3)
    topo = edge_topology(np.asarray(m.faces, np.int64), len(m.vertices))
    W = S._umbrella_operator(topo)
    ok = np.ones(len(m.vertices), bool)
    ok[::7] = False
    V = np.asarray(m.vertices, np.float64)
    Z = S.model_probe(V, ok, S.canonical_order(V))
    assert Z.shape == (len(V), min(8, int(np.ceil(20_000 / ok.sum()))))
    for ks in (S.SCALES, (1, 3)):
        C, sig = S._model_profiles(W, ks, ok, Z)
        C0, sig0 = _reference(W, ks, ok, Z)
        assert np.array_equal(C, C0) and np.array_equal(sig, sig0)
