"""The modes of a closed cluster of linear contacts (docs/model.md, "Stacks of N balls"): its
matrix's eigenpairs, each refined to an ulp by Newton's method, paired into real 2x2 blocks for
:mod:`twoball.kernels.clusters`.
"""

from __future__ import annotations

import numpy as np

from twoball.jit import njit
from twoball.kernels.closed_forms import _split_modes


@njit
def _refine_eigenpair(b, lam, v, sweeps=2):
    """lam refined, and v in place, by Newton's method on B v = lam v (v's largest component
    held). The QR algorithm's eigenvalues are accurate to eps ||B||: 5 to 16 ulps for the slow
    modes of three or four balls under a light top ball, whose stiff contact makes ||B|| large
    where the slow modes barely move it. A residual formed in double precision is accurate to
    eps |B| |v|, componentwise, so Newton's steps reach that (docs/accuracy.md, "The linear
    stack")."""
    d = b.shape[0]
    big = np.argmax(np.abs(v))
    matrix = np.zeros((d + 1, d + 1), dtype=np.complex128)
    rhs = np.zeros(d + 1, dtype=np.complex128)
    for _ in range(sweeps):
        for i in range(d):
            total = -lam * v[i]
            for j in range(d):
                total += b[i, j] * v[j]
                matrix[i, j] = b[i, j]
            matrix[i, i] -= lam
            matrix[i, d] = -v[i]
            rhs[i] = -total
        matrix[d, :] = 0.0
        matrix[d, big] = 1.0
        rhs[d] = 0.0
        step = np.linalg.solve(matrix, rhs)
        for i in range(d):
            v[i] += step[i]
        lam += step[d]
    return lam


@njit
def _real_blocks(b, k):
    """X, X^-1 and k 2x2 blocks with B = X diag(blocks) X^-1 (see the module docstring)."""
    d = 2 * k
    x = np.zeros((d, d))
    blocks = np.zeros((k, 2, 2))
    if k == 1:
        x[0, 0] = x[1, 1] = 1.0
        blocks[0] = b
        return x, x.copy(), blocks
    if k == 2:
        x4, x4_inv, blocks2 = _split_modes(b)
        return x4, x4_inv, blocks2
    lam, vec = np.linalg.eig(b.astype(np.complex128))
    for i in range(d):
        lam[i] = _refine_eigenpair(b, lam[i], vec[:, i])
    scale = np.abs(lam).max()
    used = np.zeros(d, dtype=np.bool_)
    count = 0
    for i in range(d):
        if used[i] or abs(lam[i].imag) <= 1e-12 * scale:
            continue
        partner, gap = -1, np.inf
        for j in range(d):
            if j != i and not used[j] and abs(lam[j] - np.conj(lam[i])) < gap:
                partner, gap = j, abs(lam[j] - np.conj(lam[i]))
        used[i] = used[partner] = True
        top = i if lam[i].imag > 0.0 else partner
        x[:, 2 * count] = vec[:, top].real
        x[:, 2 * count + 1] = vec[:, top].imag
        re, im = lam[top].real, lam[top].imag
        blocks[count, 0, 0], blocks[count, 0, 1] = re, im
        blocks[count, 1, 0], blocks[count, 1, 1] = -im, re
        count += 1
    real_index = np.array([i for i in range(d) if not used[i]], dtype=np.int64)
    order = real_index[np.argsort(lam[real_index].real)]
    for p in range(0, order.size, 2):
        for q in range(2):
            v = vec[:, order[p + q]]
            big = np.argmax(np.abs(v))
            phase = np.conj(v[big]) / abs(v[big])  # a real eigenvector times a phase
            x[:, 2 * count + q] = (v * phase).real
        blocks[count, 0, 0] = lam[order[p]].real
        blocks[count, 1, 1] = lam[order[p + 1]].real
        count += 1
    return x, np.linalg.inv(x), blocks
