"""The N-ball kernel's clusters: stacks of N balls with linear contacts, solved exactly phase by
phase (docs/model.md, "Stacks
of N balls").

The two-ball solver of :mod:`twoball.kernels.phases`, generalised. In a phase a set of contacts is
active; it splits the stack into *clusters*, runs of balls joined by active ball contacts. A
cluster resting on the floor through an active floor contact is *grounded*.

- A cluster's shape is given by the overlaps eta_c of its active contacts. They obey
  eta'' = -W (eta - eta_rest + 2 Z eta') with W = D M^-1 D^T (D maps heights to overlaps, M is
  diagonal in the masses, Z in the damping ratios): the state z = (eta - eta_rest, eta') of a
  cluster with k active contacts satisfies z' = B z, B = [[0, I], [-W, -W 2Z]]. eta_rest is the
  static compression under the weight above each contact (grounded) or zero (free clusters).
- A free cluster's centre of mass is a parabola; a ball on its own is one.
- z' = B z is solved in closed form through a real block-diagonal form
  B = X diag(B_1..B_k) X^-1 with 2x2 blocks, each advanced exactly on every damping branch
  (:func:`twoball.kernels.phases._block_flow`).
  One contact: X = I. Two contacts: the refined mode split of the two-ball solver
  (:func:`twoball.kernels.closed_forms._split_modes`). More: eigenvectors, each pair refined
  by Newton's method (:mod:`twoball.kernels.modes`), complex pairs as rotations and real
  eigenvalues paired in order; a near-defective pair then costs accuracy in proportion to the
  condition of X, which the tolerance carries.

Why no contact can be missed: the certified steps of :mod:`twoball.kernels.phases`. Every switching
function is linear in the heights and velocities of at most two balls; its second derivative is
a constant (from gravity, for balls of free clusters) plus a linear form in each involved
cluster's w = z' (which obeys the same equation as z). In the block coordinates X^-1 w that form
is a sum over the blocks, and each block's share is bounded for the rest of the phase by sizes
of its state that never grow (a rotation's norm, a diagonal's entries, a strongly overdamped
block's two exponentials, else its oscillator energy): :func:`_block_weights`. So each step
keeps F + F' h - bound h^2/2 above -tol, and a root can be approached but not stepped over.
Bounding mode by mode, as the two-ball solver does, steps each contact at the pace of the modes
that move it: the cluster's total energy weighs a light top ball's contact by 1/sqrt(its mass)
times the whole stack's motion.

A stack is at rest when every contact is active and the same per-mode bounds, on z, leave every
contact force above zero for ever, beyond the rounding of the phase's start
(:func:`_rest_rounding`): docs/stacks.md, "Why every damped stack ends", has the argument.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from twoball.jit import njit
from twoball.kernels.closed_forms import (
    OVERDAMPED_SAFETY,
    _companion,
    _companion_row,
    _overdamped_rates,
)
from twoball.kernels.codes import ROUNDING
from twoball.kernels.modes import _real_blocks
from twoball.kernels.phases import _block_change, contact_switch

# How a block's future is bounded (:func:`_block_kind`).
BLOCK_ROTATION, BLOCK_DIAGONAL, BLOCK_EXPONENTIALS, BLOCK_ENERGY = 0, 1, 2, 3


class Clusters(NamedTuple):
    """Every cluster's closed form, built on first use (cluster id from :func:`_cluster_id`)."""

    ready: np.ndarray  # (ids,) bool
    contacts: np.ndarray  # (ids,) active contacts k
    x: np.ndarray  # (ids, 2N, 2N) X of the block form (first 2k rows and columns)
    x_inv: np.ndarray
    blocks: np.ndarray  # (ids, N, 2, 2)
    kind: np.ndarray  # (ids, N) how each block's future is bounded (BLOCK_ROTATION, ...)
    companion: np.ndarray  # (ids, N, 2, 2) (u, u') = R y of a block (BLOCK_ENERGY, _EXPONENTIALS)
    rates: np.ndarray  # (ids, N, 2) slow and fast decay rates (BLOCK_EXPONENTIALS)
    eta_rest: np.ndarray  # (ids, N) by local contact
    shape: np.ndarray  # (ids, N, N) ball (local) height from z_1 (contact local)
    offset: np.ndarray  # (ids, N) ball height at z = 0 (grounded), 0 for free clusters
    # weights (ids, N, N, 2) of each functional on each block's sizes (:func:`_block_weights`):
    # per ball, x'' and the g'' of its lower and upper contact, on w = z'; per active contact,
    # eta'' and g'' on w and g - g_rest on z
    w_x2: np.ndarray
    w_g_low: np.ndarray
    w_g_up: np.ndarray
    w_eta: np.ndarray
    w_g: np.ndarray
    w_rest: np.ndarray
    noise: np.ndarray  # (ids,) condition of X


@njit
def _cluster_id(lo, hi, grounded, n):
    """Index of the cluster of balls lo..hi (grounded ones have lo = 0)."""
    return n * n + hi if grounded else lo * n + hi


@njit
def new_clusters(n):
    """Empty storage for every cluster of an n-ball stack."""
    ids = n * n + n
    d = 2 * n
    return Clusters(
        np.zeros(ids, dtype=np.bool_),
        np.zeros(ids, dtype=np.int64),
        np.zeros((ids, d, d)),
        np.zeros((ids, d, d)),
        np.zeros((ids, n, 2, 2)),
        np.zeros((ids, n), dtype=np.int64),
        np.zeros((ids, n, 2, 2)),
        np.zeros((ids, n, 2)),
        np.zeros((ids, n)),
        np.zeros((ids, n, n)),
        np.zeros((ids, n)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros(ids),
    )


@njit
def _block_kind(block):
    """How a 2x2 block's future is bounded (docs/stacks.md, "Why every damped stack ends"):
    a scaled rotation (a complex pair of the eigenvector form), a diagonal (two real
    eigenvalues), a strongly overdamped block (two exponentials) or, otherwise, the energy of
    its oscillator."""
    if block[0, 1] == 0.0 and block[1, 0] == 0.0:
        return BLOCK_DIAGONAL
    if block[0, 0] == block[1, 1] and block[0, 1] == -block[1, 0]:
        return BLOCK_ROTATION
    if _overdamped_rates(block)[1] > 0.0:
        return BLOCK_EXPONENTIALS
    return BLOCK_ENERGY


@njit
def _block_weights(kind, block, companion, rates, r0, r1):
    """(p, q) with |r . y(s)| <= p a + q b for every later time s of the phase, where
    (a, b) = :func:`_sizes` of the block's state y now (docs/stacks.md, "Why every damped stack
    ends"). A rotation keeps |y| or shrinks it, a diagonal each |y_i|; a strongly overdamped block
    is two decaying exponentials (:func:`twoball.kernels.closed_forms._overdamped_bound`); otherwise
    Cauchy-Schwarz on the oscillator energy of (u, u') = R y, which never rises."""
    if kind == BLOCK_ROTATION:
        return math.hypot(r0, r1), 0.0
    if kind == BLOCK_DIAGONAL:
        return abs(r0), abs(r1)
    row = np.empty(2)
    row[0], row[1] = r0, r1
    alpha_beta = _companion_row(row, companion)
    alpha, beta = alpha_beta[0], alpha_beta[1]
    if kind == BLOCK_EXPONENTIALS:
        slow, fast = rates[0], rates[1]
        return (
            abs(alpha - beta * slow) * OVERDAMPED_SAFETY,
            abs(alpha - beta * fast) * OVERDAMPED_SAFETY,
        )
    omega = math.sqrt(block[0, 0] * block[1, 1] - block[0, 1] * block[1, 0])
    return math.hypot(alpha / omega, beta), 0.0


@njit
def _store_weights(target, store, cid, index, row, k):
    """target[cid, index] = the weights of the functional ``row`` (on z or w, length 2k) on
    each block of the cluster: row X restricted to the block, through :func:`_block_weights`."""
    x = store.x[cid]
    for blk in range(k):
        r0 = r1 = 0.0
        for m in range(2 * k):
            r0 += row[m] * x[m, 2 * blk]
            r1 += row[m] * x[m, 2 * blk + 1]
        p, q = _block_weights(
            store.kind[cid, blk],
            store.blocks[cid, blk],
            store.companion[cid, blk],
            store.rates[cid, blk],
            r0,
            r1,
        )
        target[cid, index, blk, 0] = p
        target[cid, index, blk, 1] = q


@njit
def _build_cluster(store, cid, lo, hi, grounded, masses, zeta):
    """Fill ``store`` at ``cid`` for the cluster of balls lo..hi (docs/model.md, "Stacks of N
    balls")."""
    n = masses.size
    first = 0 if grounded else lo + 1  # its first active contact
    k = hi - first + 1
    balls = hi - lo + 1
    store.contacts[cid] = k
    if k == 0:
        store.ready[cid] = True
        store.noise[cid] = 1.0
        return
    # W = D M^-1 D^T on the active contacts (contact c joins balls c-1 and c)
    w = np.zeros((k, k))
    for i in range(k):
        c = first + i
        w[i, i] = 1.0 / masses[c] + (1.0 / masses[c - 1] if c >= 1 else 0.0)
        if i + 1 < k:
            w[i, i + 1] = w[i + 1, i] = -1.0 / masses[c]
    b = np.zeros((2 * k, 2 * k))
    for i in range(k):
        b[i, k + i] = 1.0
        for j in range(k):
            b[k + i, j] = -w[i, j]
            b[k + i, k + j] = -w[i, j] * 2.0 * zeta[first + j]
    x, x_inv, blocks = _real_blocks(b, k)
    store.x[cid, : 2 * k, : 2 * k] = x
    store.x_inv[cid, : 2 * k, : 2 * k] = x_inv
    store.blocks[cid, :k] = blocks
    store.noise[cid] = np.abs(x).sum(axis=0).max() * np.abs(x_inv).sum(axis=0).max()
    for blk in range(k):
        kind = _block_kind(blocks[blk])
        store.kind[cid, blk] = kind
        if kind in (BLOCK_ENERGY, BLOCK_EXPONENTIALS):
            store.companion[cid, blk] = _companion(np.ascontiguousarray(blocks[blk]))
        if kind == BLOCK_EXPONENTIALS:
            store.rates[cid, blk] = _overdamped_rates(blocks[blk])
    # heights from the shape: x_j = offset_j + shape[j] . z_1 (+ centre of mass if free)
    total = masses[lo : hi + 1].sum()
    for jl in range(balls):
        j = lo + jl
        for i in range(k):
            c = first + i
            if grounded:
                store.shape[cid, jl, i] = 1.0 if c <= j else 0.0
            else:
                above = masses[c : hi + 1].sum()
                store.shape[cid, jl, i] = (1.0 if c <= j else 0.0) - above / total
    if grounded:
        for i in range(k):
            store.eta_rest[cid, i] = -masses[i : hi + 1].sum()  # the weight above contact i
        for jl in range(balls):
            store.offset[cid, jl] = store.eta_rest[cid, : jl + 1].sum()
    b2 = b @ b
    for jl in range(balls):
        j = lo + jl
        row = np.zeros(2 * k)
        row[:k] = store.shape[cid, jl, :k]
        r1 = row @ b  # x'' = r1 . w
        r2 = row @ b2  # x''' = r2 . w
        _store_weights(store.w_x2, store, cid, jl, r1, k)
        _store_weights(store.w_g_low, store, cid, jl, r1 + 2.0 * zeta[j] * r2, k)
        above = zeta[j + 1] if j + 1 < n else 0.0
        _store_weights(store.w_g_up, store, cid, jl, r1 + 2.0 * above * r2, k)
    for i in range(k):
        c = first + i
        row = np.zeros(2 * k)
        row[i] = 1.0
        _store_weights(store.w_eta, store, cid, i, row @ b, k)
        row[k + i] = 2.0 * zeta[c]
        _store_weights(store.w_g, store, cid, i, row @ b, k)
        _store_weights(store.w_rest, store, cid, i, row, k)  # g - g_rest on z
    store.ready[cid] = True


@njit(borrow=True)
def _clusters_ready(active, ready):
    """Whether the store (its ``ready``) holds every cluster of this set of active contacts."""
    n = active.size
    j = 0
    while j < n:
        start = j
        while j + 1 < n and active[j + 1]:
            j += 1
        if not ready[_cluster_id(start, j, start == 0 and active[0], n)]:
            return False
        j += 1
    return True


@njit
def _ensure_clusters(active, store, masses, zeta):
    """Build the closed forms of this set of active contacts' clusters that ``store`` lacks
    (:func:`_build_cluster`): before :func:`_phase`, which allocates nothing. Called only when
    :func:`_clusters_ready` says so: handing it the store counts its arrays' references."""
    n = masses.size
    j = 0
    while j < n:
        start = j
        while j + 1 < n and active[j + 1]:
            j += 1
        grounded = start == 0 and active[0]
        cid = _cluster_id(start, j, grounded, n)
        if not store.ready[cid]:
            _build_cluster(store, cid, start, j, grounded, masses, zeta)
        j += 1


@njit(borrow=True)
def _phase(
    active,
    e,
    de,
    store,
    masses,
    zeta,
    lo,
    hi,
    cid,
    grounded,
    modes,
    centre,
    size,
    speed,
    of_ball,
    z,
):
    """Split the stack into clusters for this set of active contacts (their closed forms built:
    :func:`_ensure_clusters`); their modes at the start. Returns the number of clusters; per
    cluster, into the arrays passed: its balls lo..hi, its id cid, whether it is grounded, its
    modes X^-1 z at the start, its centre of mass height and velocity (free clusters), the
    rounding scales of its heights (size) and velocities (speed); of_ball the cluster of each
    ball; z is a work array (2N). Allocates nothing, so a phase counts no references.

    The state is relative (docs/stacks.md, "How the state is carried"): e[0] the floor's overlap
    (ball 0's height), e[c] = x_c - x_(c-1) the overlap of contact c, de their rates. A cluster's
    z is read from them as it stands; only the centres of mass of free clusters, and the scales
    of rounding, take the heights, summed from the overlaps below."""
    n = masses.size
    eta_rest, x_inv = store.eta_rest, store.x_inv
    height = rate = 0.0
    count = 0
    j = 0
    while j < n:
        start = j
        while j + 1 < n and active[j + 1]:
            j += 1
        lo[count], hi[count] = start, j
        grounded[count] = start == 0 and active[0]
        cid[count] = _cluster_id(start, j, grounded[count], n)
        here = cid[count]
        k = store.contacts[here]
        first = 0 if grounded[count] else start + 1
        total = mass_x = mass_v = 0.0
        size[count] = 1.0
        speed[count] = 0.0
        for ball in range(start, j + 1):  # loops, not slices or temporaries (see _evaluate_arrays)
            height += e[ball]
            rate += de[ball]
            total += masses[ball]
            mass_x += masses[ball] * height
            mass_v += masses[ball] * rate
            of_ball[ball] = count
            size[count] += abs(height)
            speed[count] += abs(rate)
        centre[count, 0] = mass_x / total
        centre[count, 1] = mass_v / total
        for i in range(k):
            c = first + i
            z[i] = e[c] - eta_rest[here, i]
            z[k + i] = de[c]
            size[count] += abs(eta_rest[here, i])
        for row in range(2 * k):  # modes = X^-1 z
            total = 0.0
            for col in range(2 * k):
                total += x_inv[here, row, col] * z[col]
            modes[count, row] = total
        count += 1
        j += 1
    return count


@njit(borrow=True, inline=True)
def _evaluate_arrays(
    tau,
    count,
    every_ball,
    cids,
    lows,
    highs,
    grounded,
    centre,
    modes,
    store,
    e0,
    de0,
    x,
    v,
    a,
    shape_z,
    shape_w,
    mode_z,
    mode_w,
    e,
    de,
    change_z,
    size_change,
    size_value,
    shift_x,
    shift_v,
):
    """Heights, velocities, accelerations of the balls of the phase's count clusters at tau into
    the phase (into x, v, a; with every_ball False only the accelerations of the balls at
    either end of a cluster, all that the step loop reads), each cluster's z and the rates of
    w = z', eta'' (into shape_z and the second half of shape_w) and the block (mode)
    coordinates X^-1 z and X^-1 w (into mode_z, mode_w), from the phase's (:func:`_phase`) and
    the store's arrays, passed one by one: the step loop reads them once per phase. Written
    without array slices or tuples of arrays: each would count references, which took most of
    the time of a step.

    Also the relative state at tau (into e, de) from the phase's start e0, de0 (docs/stacks.md,
    "How the state is carried"): each overlap and rate moved by its change, formed to its own
    rounding, as :func:`twoball.kernels.phases.state_at` moves the two-ball state. An active
    contact's change is X (exp(B tau) - I) X^-1 z (or, once that sums larger terms than the value
    itself, as after the modes have decayed, eta_rest + z(tau)); an inactive contact's is the
    difference of the changes of the two balls' heights, tau eta' plus each ball's share of its
    cluster's change beyond its start velocity (into shift_x, shift_v), gravity cancelling
    between two free clusters. change_z, size_change and size_value are work arrays."""
    contacts, blocks, big_x = store.contacts, store.blocks, store.x
    shape, offset, eta_rest = store.shape, store.offset, store.eta_rest
    # At a phase's start in the step loop the state is the start's (e = e0, de = de0, as the
    # zero change below gives to the bit) and only the rates w are formed: a third of the
    # sums of a step (docs/stacks.md, "What a step costs")
    start = tau == 0.0 and not every_ball
    gravity_below = 0.0  # -tau^2/2 (or 0) in the height of the ball below, and its rate
    gravity_rate_below = 0.0
    for p in range(count):
        cid = cids[p]
        k = contacts[cid]
        d = 2 * k
        for row in range(d):
            shape_z[p, row] = 0.0
            shape_w[p, row] = 0.0
            change_z[p, row] = 0.0
            size_change[p, row] = 0.0
            size_value[p, row] = 0.0
        for blk in range(k):
            block = (
                (blocks[cid, blk, 0, 0], blocks[cid, blk, 0, 1]),
                (blocks[cid, blk, 1, 0], blocks[cid, blk, 1, 1]),
            )
            if tau == 0.0:  # a phase's start: the values _block_change gives there, at no cost
                n0, n1, d0, d1 = modes[p, 2 * blk], modes[p, 2 * blk + 1], 0.0, 0.0
                r0 = block[0][0] * n0 + block[0][1] * n1
                r1 = block[1][0] * n0 + block[1][1] * n1
            else:
                n0, n1, d0, d1, r0, r1 = _block_change(
                    block, modes[p, 2 * blk], modes[p, 2 * blk + 1], tau
                )
            mode_z[p, 2 * blk], mode_z[p, 2 * blk + 1] = n0, n1
            mode_w[p, 2 * blk], mode_w[p, 2 * blk + 1] = r0, r1
            for row in range(k, d):  # w = X rate: its rates only (eta'', read as a[] and g'')
                left, right = big_x[cid, row, 2 * blk], big_x[cid, row, 2 * blk + 1]
                shape_w[p, row] += left * r0 + right * r1
            if start:
                continue  # z is the start's, its change zero, as zeroed above
            for row in range(d):  # z = X flow, and its change, without allocating
                left, right = big_x[cid, row, 2 * blk], big_x[cid, row, 2 * blk + 1]
                shape_z[p, row] += left * n0 + right * n1
                change_z[p, row] += left * d0 + right * d1
                size_change[p, row] += abs(left * d0) + abs(right * d1)
                size_value[p, row] += abs(left * n0) + abs(right * n1)
        if grounded[p]:
            base_x = base_v = base_a = 0.0
            gravity, gravity_rate = 0.0, 0.0
        else:
            base_x = centre[p, 0] + tau * (centre[p, 1] - 0.5 * tau)
            base_v = centre[p, 1] - tau
            base_a = -1.0
            gravity, gravity_rate = -0.5 * tau * tau, -tau
        first = 0 if grounded[p] else lows[p] + 1
        for ball in range(lows[p], highs[p] + 1):
            if not (every_ball or ball == lows[p] or ball == highs[p]):
                continue
            jl = ball - lows[p]
            acc, moved, moved_rate = _ball_sums(
                shape[cid, jl], shape_w[p], change_z[p], de0, first, k, tau
            )
            a[ball] = base_a + acc
            shift_x[ball], shift_v[ball] = moved, moved_rate
            if every_ball:
                xs = vs = 0.0
                for i in range(k):
                    xs += shape[cid, jl, i] * shape_z[p, i]
                    vs += shape[cid, jl, i] * shape_z[p, k + i]
                x[ball] = base_x + offset[cid, jl] + xs
                v[ball] = base_v + vs
        for i in range(k):  # the active contacts: start plus change, or rest plus value
            c = first + i
            if size_change[p, i] <= abs(eta_rest[cid, i]) + size_value[p, i]:
                e[c] = e0[c] + change_z[p, i]
            else:
                e[c] = eta_rest[cid, i] + shape_z[p, i]
            if size_change[p, k + i] <= size_value[p, k + i]:
                de[c] = de0[c] + change_z[p, k + i]
            else:
                de[c] = shape_z[p, k + i]
        if not grounded[p]:  # the inactive contact below the cluster
            c = lows[p]
            below_x = shift_x[c - 1] if c >= 1 else 0.0
            below_v = shift_v[c - 1] if c >= 1 else 0.0
            e[c] = e0[c] + (tau * de0[c] + (shift_x[c] - below_x) + (gravity - gravity_below))
            de[c] = de0[c] + ((shift_v[c] - below_v) + (gravity_rate - gravity_rate_below))
        gravity_below, gravity_rate_below = gravity, gravity_rate


@njit(borrow=True, inline=True)
def _ball_sums(shape_row, shape_w, change_z, de0, first, k, tau):
    """A ball's acceleration from its cluster's modes, and its height's and speed's change
    over ``tau`` (``shape_row``: the ball's row of the cluster's shape; docs/stacks.md, "How
    each force is solved")."""
    acc = moved = moved_rate = 0.0
    for i in range(k):
        coefficient = shape_row[i]
        acc += coefficient * shape_w[k + i]
        moved += coefficient * (change_z[i] - tau * de0[first + i])
        moved_rate += coefficient * change_z[k + i]
    return acc, moved, moved_rate


@njit(borrow=True, inline=True)
def _mode_step(blocks, cid, blk, modes, mode_w, cluster, tau):
    """Mode pair ``blk`` of cluster ``cluster`` (of kind ``cid``) over ``tau``:
    :func:`_block_change` of its 2x2 block, its rates kept in ``mode_w``
    (docs/stacks.md, "How each force is solved")."""
    block = (
        (blocks[cid, blk, 0, 0], blocks[cid, blk, 0, 1]),
        (blocks[cid, blk, 1, 0], blocks[cid, blk, 1, 1]),
    )
    changes = _block_change(block, modes[cluster, 2 * blk], modes[cluster, 2 * blk + 1], tau)
    mode_w[cluster, 2 * blk], mode_w[cluster, 2 * blk + 1] = changes[4], changes[5]
    return changes


@njit(borrow=True, inline=True)
def _evaluate_contact(
    tau,
    c,
    is_active,
    cids,
    lows,
    grounded,
    modes,
    of_ball,
    store,
    e0,
    de0,
    a,
    shape_w,
    mode_w,
    e,
    de,
    change_z,
):
    """What :func:`_check_contact` reads of contact c at tau, and nothing else: the rows of
    :func:`_evaluate_arrays` that c's overlap, rate and curvature are formed from, summed in the
    same order (so to the same bits), and the rates of its clusters' modes (mode_w, for their
    sizes). Active, the two rows of c in its cluster; inactive, the shifts and accelerations of
    the two balls it joins. A step that approaches one contact's root (most do: docs/stacks.md,
    "What grows with N") then costs O(k) per cluster of k contacts for an active contact, not
    the O(k^2) of the cluster's every row and ball."""
    contacts, blocks, big_x = store.contacts, store.blocks, store.x
    shape, eta_rest = store.shape, store.eta_rest
    upper = of_ball[c]
    if is_active:
        cid = cids[upper]
        k = contacts[cid]
        i = c - (0 if grounded[upper] else lows[upper] + 1)
        z0 = z1 = w1 = change0 = change1 = size0 = size1 = value0 = value1 = 0.0
        for blk in range(k):
            n0, n1, d0, d1, r0, r1 = _mode_step(blocks, cid, blk, modes, mode_w, upper, tau)
            left, right = big_x[cid, i, 2 * blk], big_x[cid, i, 2 * blk + 1]
            z0 += left * n0 + right * n1
            change0 += left * d0 + right * d1
            size0 += abs(left * d0) + abs(right * d1)
            value0 += abs(left * n0) + abs(right * n1)
            left, right = big_x[cid, k + i, 2 * blk], big_x[cid, k + i, 2 * blk + 1]
            z1 += left * n0 + right * n1
            w1 += left * r0 + right * r1
            change1 += left * d0 + right * d1
            size1 += abs(left * d0) + abs(right * d1)
            value1 += abs(left * n0) + abs(right * n1)
        shape_w[upper, k + i] = w1
        if size0 <= abs(eta_rest[cid, i]) + value0:
            e[c] = e0[c] + change0
        else:
            e[c] = eta_rest[cid, i] + z0
        de[c] = de0[c] + change1 if size1 <= value1 else z1
        return
    below_x = below_v = gravity_below = gravity_rate_below = 0.0
    for p in range(of_ball[c - 1] if c >= 1 else upper, upper + 1):
        ball = c if p == upper else c - 1
        cid = cids[p]
        k = contacts[cid]
        for row in range(2 * k):
            change_z[p, row] = 0.0
        for row in range(k, 2 * k):
            shape_w[p, row] = 0.0
        for blk in range(k):
            n0, n1, d0, d1, r0, r1 = _mode_step(blocks, cid, blk, modes, mode_w, p, tau)
            for row in range(2 * k):
                left, right = big_x[cid, row, 2 * blk], big_x[cid, row, 2 * blk + 1]
                change_z[p, row] += left * d0 + right * d1
                if row >= k:
                    shape_w[p, row] += left * r0 + right * r1
        first = 0 if grounded[p] else lows[p] + 1
        acc, moved, moved_rate = _ball_sums(
            shape[cid, ball - lows[p]], shape_w[p], change_z[p], de0, first, k, tau
        )
        a[ball] = (0.0 if grounded[p] else -1.0) + acc
        if p != upper:
            below_x, below_v = moved, moved_rate
            if not grounded[p]:
                gravity_below, gravity_rate_below = -0.5 * tau * tau, -tau
        else:
            e[c] = e0[c] + (tau * de0[c] + (moved - below_x) + (-0.5 * tau * tau - gravity_below))
            de[c] = de0[c] + ((moved_rate - below_v) + (-tau - gravity_rate_below))


@njit(borrow=True, inline=True)
def _check_contact(
    c,
    tau,
    clock,
    is_active,
    zeta_c,
    carried,
    e,
    de,
    a,
    shape_w,
    of_ball,
    cids,
    lows,
    grounded,
    store,
    sizes,
    speeds,
    mode_w,
    sizes_w,
    sized,
    stamp,
):
    """Contact c's switching function at tau from the evaluated phase (:func:`_evaluate_arrays`
    of its clusters): (F, F', tol, tol of the rate, certified step, the error of one Newton step
    to the root or inf if F does not fall), by :func:`twoball.kernels.phases.contact_switch`.
    Its curvature bounds are formed from its clusters' block sizes of w (:func:`_sizes`, each
    cluster's once per ``stamp``: ``sized`` holds the stamp they were formed at)."""
    contacts, noise, kinds, blocks = store.contacts, store.noise, store.kind, store.blocks
    companions, rates, w_x2, w_g_low = store.companion, store.rates, store.w_x2, store.w_g_low
    w_g_up, w_eta, w_g = store.w_g_up, store.w_eta, store.w_g
    upper = of_ball[c]
    cid_u = cids[upper]
    k_u = contacts[cid_u]
    if sized[upper] != stamp:
        _sizes(kinds, blocks, companions, rates, cid_u, k_u, mode_w, upper, sizes_w)
        sized[upper] = stamp
    noise_u = noise[cid_u]
    tol_state = noise_u * (sizes[upper] + speeds[upper] * (1.0 + tau) + tau * tau)
    tol_rate = noise_u * (speeds[upper] + 1.0 + tau)
    if is_active:
        i = c - (0 if grounded[upper] else lows[upper] + 1)
        eta, deta, ddeta = e[c], de[c], shape_w[upper, k_u + i]
        bound_eta = _bound(w_eta, cid_u, i, sizes_w, upper, k_u)
        bound_g = _bound(w_g, cid_u, i, sizes_w, upper, k_u)
    else:
        rigid_u = 0.0 if grounded[upper] else -1.0
        jl = c - lows[upper]
        bound_eta = _bound(w_x2, cid_u, jl, sizes_w, upper, k_u)
        bound_g = _bound(w_g_low, cid_u, jl, sizes_w, upper, k_u)
        eta, deta = e[c], de[c]
        if c == 0:
            ddeta = a[0]
            rigid = -rigid_u
        else:
            lower = of_ball[c - 1]
            cid_l = cids[lower]
            ddeta = a[c] - a[c - 1]
            rigid_l = 0.0 if grounded[lower] else -1.0
            rigid = abs(rigid_u - rigid_l)
            k_l = contacts[cid_l]
            if sized[lower] != stamp:
                _sizes(kinds, blocks, companions, rates, cid_l, k_l, mode_w, lower, sizes_w)
                sized[lower] = stamp
            jl = c - 1 - lows[lower]
            bound_eta += _bound(w_x2, cid_l, jl, sizes_w, lower, k_l)
            bound_g += _bound(w_g_up, cid_l, jl, sizes_w, lower, k_l)
            tol_state += noise[cid_l] * (sizes[lower] + speeds[lower] * (1.0 + tau) + tau * tau)
            tol_rate += noise[cid_l] * (speeds[lower] + 1.0 + tau)
        bound_eta += rigid
        bound_g += rigid
    tol_state = ROUNDING * tol_state + carried
    value, rate, tol, h = contact_switch(
        is_active, eta, deta, ddeta, zeta_c, bound_eta, bound_g, tol_state, clock
    )
    # a rate within the rounding of the velocities has no sign: balls moving together
    # (touching, unloaded) would otherwise switch on and off with the rounding
    tol_rate = ROUNDING * tol_rate * (1.0 + 2.0 * zeta_c)
    error = np.inf
    if rate < 0.0:
        g_part = is_active or eta < eta + 2.0 * zeta_c * deta
        s = value / -rate
        error = 0.5 * (bound_g if g_part else bound_eta) * s * s
    return value, rate, tol, tol_rate, h, error


@njit(borrow=True, inline=True)
def _hypot(x, y):
    """math.hypot(x, y) inline, to the same bits here: glibc's algorithm (2.35 on, as built
    without FMA: sysdeps/ieee754/dbl-64/e_hypot.c) where its operands need no scaling, the
    library call elsewhere (scaled, one operand negligible, zero or not finite). The rotation
    blocks' sizes (:func:`_sizes`) take about 13 a phase of the eight-ball drop; the call cost
    three times the arithmetic (docs/performance.md, "Stacks of N balls")."""
    ax, ay = abs(x), abs(y)
    if ax < ay:
        ax, ay = ay, ax
    if not (ax <= 2.0**511 and ay >= 2.0**-459 and ay > ax * 2.0**-54):
        return math.hypot(x, y)
    h = math.sqrt(ax * ax + ay * ay)
    if h <= 2.0 * ay:
        delta = h - ay
        t1 = ax * (2.0 * delta - ax)
        t2 = (delta - 2.0 * (ax - ay)) * delta
    else:
        delta = h - ax
        t1 = 2.0 * delta * (ax - 2.0 * ay)
        t2 = (4.0 * delta - ay) * ay + delta * delta
    return h - (t1 + t2) / (2.0 * h)


@njit(borrow=True, inline=True)
def _sizes(kinds, blocks, companions, rates, cid, k, modes, p, out):
    """The two sizes of each block's state y = modes[p] (cluster cid, k blocks) that
    :func:`_block_weights` weighs, into out[p]: |y| (rotation), |y_0| and |y_1| (diagonal), the
    amplitudes of the slow and the fast exponential (strongly overdamped), sqrt(2 E) =
    sqrt(u'^2 + det(B) u^2) (otherwise). None of them can grow. Whole arrays and indices, not
    slices (see :func:`_evaluate_arrays`)."""
    for blk in range(k):
        kind = kinds[cid, blk]
        y0, y1 = modes[p, 2 * blk], modes[p, 2 * blk + 1]
        if kind == BLOCK_ROTATION:
            out[p, blk, 0], out[p, blk, 1] = _hypot(y0, y1), 0.0
        elif kind == BLOCK_DIAGONAL:
            out[p, blk, 0], out[p, blk, 1] = abs(y0), abs(y1)
        else:
            u = companions[cid, blk, 0, 0] * y0 + companions[cid, blk, 0, 1] * y1
            du = companions[cid, blk, 1, 0] * y0 + companions[cid, blk, 1, 1] * y1
            if kind == BLOCK_EXPONENTIALS:
                slow, fast = rates[cid, blk, 0], rates[cid, blk, 1]
                gap = fast - slow
                out[p, blk, 0] = abs((du + fast * u) / gap)
                out[p, blk, 1] = abs((du + slow * u) / gap)
            else:
                det = (
                    blocks[cid, blk, 0, 0] * blocks[cid, blk, 1, 1]
                    - blocks[cid, blk, 0, 1] * blocks[cid, blk, 1, 0]
                )
                out[p, blk, 0], out[p, blk, 1] = math.sqrt(du * du + det * u * u), 0.0


@njit(borrow=True, inline=True)
def _bound(weights, cid, index, sizes, p, k):
    """sum over the k blocks of p a + q b, (p, q) = weights[cid, index, block] and (a, b) =
    sizes[p, block]: a bound on a functional for the rest of the phase (:func:`_block_weights`)."""
    total = 0.0
    for blk in range(k):
        total += weights[cid, index, blk, 0] * sizes[p, blk, 0]
        total += weights[cid, index, blk, 1] * sizes[p, blk, 1]
    return total


@njit
def _rest_rounding(store, cid, x, v, carried):
    """Per contact, a bound (in units of ROUNDING) on how far the rounding of this phase's
    start moves g - g_rest at any later time (docs/stacks.md, "Why every damped stack ends").

    The start z = (eta - eta_rest, eta') is formed from the heights, each overlap rounded to
    ~|x_c| + |x_(c-1)| + |eta_rest| (and what earlier closed forms ``carried``), each rate to
    ~|v_c| + |v_(c-1)|; its modes X^-1 z then carry at most |X^-1| times that, and a mode's
    error is a state of the same block, bounded for all later times as the mode is
    (:func:`_block_weights`). Only for the eigenvector form (rotations and diagonals), that
    is clusters of three or more contacts. Far tighter than the condition of X times the
    heights: a light top ball's weight (1e-9 of ball 0) is below that, not below this."""
    n = store.contacts[cid]
    scale = np.zeros(2 * n)
    for c in range(n):
        scale[c] = abs(x[c]) + abs(store.eta_rest[cid, c]) + 2.0 * carried / ROUNDING
        scale[n + c] = abs(v[c])
        if c >= 1:
            scale[c] += abs(x[c - 1])
            scale[n + c] += abs(v[c - 1])
    spread = np.zeros((1, 2 * n))
    spread[0] = np.abs(store.x_inv[cid, : 2 * n, : 2 * n]) @ scale
    sizes = np.zeros((1, n, 2))
    _sizes(store.kind, store.blocks, store.companion, store.rates, cid, n, spread, 0, sizes)
    out = np.empty(n)
    for c in range(n):
        out[c] = _bound(store.w_rest, cid, c, sizes, 0, n)
    return out
