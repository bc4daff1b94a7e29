"""FOTA, the Fractional Optimal-Transport Assignment of SAGA-Track (Nguyen et al., arXiv 2022, §3.2, Eq. 6–15).

N tracks carry mass ``p`` and M detections mass ``q``; a plan π moves exactly ``s`` of it at least cost
(Eq. 6–7). One extra row and column turn that into a balanced problem (Eq. 8)::

    C̄ = [[C, E·1], [E·1ᵀ, 2E + max C]],   p̄ = [p, ‖q‖₁ − s],   q̄ = [q, ‖p‖₁ − s]

which entropic Sinkhorn–Knopp iterations solve (Eq. 9–15). A detection column is then decoded to the row
holding most of its mass: a real track (if the pair's cost passes the gate) or the extra row (unmatched).
A track may receive several detections; a detection never goes to two tracks.

Choices where the paper is silent (documented in the README):

* masses: a detection carries 1, a track carries ``track_mass`` (default 2: an object is seen by at most
  two neighbouring cameras of a ring whose neighbours overlap; with 1 a track seen twice would get ½ + ½
  and tie with the extra row);
* transported fraction: ``s = min(n_gated, ‖p‖₁) − 0.01`` where ``n_gated`` counts detections with at
  least one track within the gate. Every detection that can be matched is pushed to match; the 0.01 keeps
  both extra masses positive (a zero mass has no logarithm);
* bound: ``E`` is the gate, and costs above the gate are capped to ``E`` before solving, so an
  out-of-gate pair costs the same as leaving the detection unmatched (and exp(−C̄/γ) stays representable).

The physical constraint (``cameras`` given): one track takes at most one detection per camera per frame —
one camera sees one vehicle once. It is enforced in the decoding, not in the transport problem (whose
marginals cannot express a per-(track, camera) cap): the candidate (track, detection) pairs are those the
unconstrained decoding would accept — allowed by the gate, holding more of the column's mass than the extra
row, and not in a column whose argmax is an out-of-gate track — taken greedily by plan mass (ties: lower
cost, then lower indices), skipping a pair whose detection is taken or whose track already took a detection
of that camera. A detection that loses its first track this way goes to the next track holding more of its
mass than the extra row, if any, else stays unmatched. Without conflicts this is the unconstrained decoding.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .assignment import UNMATCHED

GAMMA = 0.1
"""γ, the entropic regularisation of Eq. 9 (the paper's value)."""
ITERATIONS = 50
"""T, Sinkhorn–Knopp iterations (the paper's value)."""
SLACK = 0.01
"""How far below its maximum the transported mass s is set, in detection masses."""
_SCALING_RANGE = 600.0  # largest (max C − min C)/γ solved in the scaling form; exp(−600) ≈ 3e−261


def augmented_problem(
    cost: np.ndarray, p: np.ndarray, q: np.ndarray, s: float, bound: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq. 8: the (N+1, M+1) cost C̄ and masses p̄, q̄ for transporting exactly ``s`` of ``cost`` (N, M).

    >>> C, a, b = augmented_problem(np.array([[1.0, 3.0]]), np.array([2.0]), np.ones(2), s=1.5, bound=4.0)
    >>> C.tolist(), a.tolist(), b.tolist()
    ([[1.0, 3.0, 4.0], [4.0, 4.0, 11.0]], [2.0, 0.5], [1.0, 1.0, 0.5])
    """
    n, m = cost.shape
    if not 0 <= s <= min(p.sum(), q.sum()):
        raise ValueError(f"transported mass s={s} must lie in [0, min(‖p‖₁, ‖q‖₁)]")
    top = cost.max() if cost.size else 0.0
    out = np.empty((n + 1, m + 1))
    out[:n, :m] = cost
    out[:n, m] = bound
    out[n, :m] = bound
    out[n, m] = 2 * bound + top
    return out, np.append(p, q.sum() - s), np.append(q, p.sum() - s)


def sinkhorn(a: np.ndarray, b: np.ndarray, cost: np.ndarray, gamma: float, iterations: int) -> np.ndarray:
    """Entropic OT plan after ``iterations`` Sinkhorn–Knopp iterations (Eq. 14–15), (len a, len b).

    Computes the log-domain iterates, in the order of POT's ``ot.sinkhorn(..., method='sinkhorn_log')``:
    from log u = 0, each iteration sets log v = log b − lse_i(−C/γ + log u), then
    log u = log a − lse_j(−C/γ + log v); the plan is exp(−C/γ + log u + log v). When exp(−C/γ) is
    representable (cost range/γ ≤ 600 after shifting C by its minimum, which leaves the plan unchanged) the
    same iterates are computed as scalings u, v with matrix–vector products, ~10× faster; a non-finite
    scaling falls back to the log domain.
    """
    if cost.size == 0:
        return np.zeros_like(cost)
    shifted = cost - cost.min()
    if shifted.max() / gamma <= _SCALING_RANGE:
        plan = _sinkhorn_scaling(a, b, np.exp(-shifted / gamma), iterations)
        if plan is not None:
            return plan
    return _sinkhorn_log(a, b, -shifted / gamma, iterations)


def _sinkhorn_scaling(a: np.ndarray, b: np.ndarray, kernel: np.ndarray, iterations: int) -> np.ndarray | None:
    u = np.ones(len(a))
    v = np.ones(len(b))
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        for _ in range(iterations):
            v = b / (u @ kernel)
            u = a / (kernel @ v)
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(v))):
            return None
        return u[:, None] * kernel * v[None, :]


def _logsumexp(x: np.ndarray, axis: int) -> np.ndarray:
    top = np.max(x, axis=axis, keepdims=True)
    return (np.log(np.sum(np.exp(x - top), axis=axis, keepdims=True)) + top).squeeze(axis)


def _sinkhorn_log(a: np.ndarray, b: np.ndarray, log_kernel: np.ndarray, iterations: int) -> np.ndarray:
    log_a, log_b = np.log(a), np.log(b)
    log_u = np.zeros(len(a))
    log_v = np.zeros(len(b))
    for _ in range(iterations):
        log_v = log_b - _logsumexp(log_kernel + log_u[:, None], 0)
        log_u = log_a - _logsumexp(log_kernel + log_v[None, :], 1)
    return np.exp(log_kernel + log_u[:, None] + log_v[None, :])


@dataclass(frozen=True, eq=False)
class FotaResult:
    """owner: (M,) track index per detection or −1; plan: the (N+1, M+1) Sinkhorn plan (empty when
    nothing could match); transported: the mass s that was moved."""

    owner: np.ndarray
    plan: np.ndarray
    transported: float


def fota(
    cost: np.ndarray,
    gate: float,
    *,
    gamma: float = GAMMA,
    iterations: int = ITERATIONS,
    track_mass: float = 2.0,
    cameras: np.ndarray | None = None,
) -> FotaResult:
    """One-to-many assignment of M detections to N tracks (columns to rows of ``cost`` (N, M)).

    A pair is allowed when its cost is finite and ``≤ gate``. See the module docstring for the masses,
    the transported mass s and the bound E (= ``gate``). ``cameras`` (M,): the camera of each detection;
    when given, no track receives two detections of one camera.
    """
    n, m = cost.shape
    owner = np.full(m, UNMATCHED, dtype=np.int64)
    if gamma <= 0 or iterations < 1 or track_mass <= 0 or not np.isfinite(gate):
        raise ValueError(f"fota: need gamma > 0, iterations ≥ 1, track_mass > 0 and a finite gate; "
                         f"got gamma={gamma}, iterations={iterations}, track_mass={track_mass}, gate={gate}")
    allowed = np.isfinite(cost) & (cost <= gate)
    gated = int(allowed.any(axis=0).sum()) if n else 0
    if gated == 0:
        return FotaResult(owner, np.zeros((n + 1, m + 1)), 0.0)
    p, q = np.full(n, float(track_mass)), np.ones(m)
    s = min(float(gated), p.sum()) - SLACK
    capped = np.where(allowed, cost, gate)
    augmented, a, b = augmented_problem(capped, p, q, s, bound=gate)
    plan = sinkhorn(a, b, augmented, gamma, iterations)
    best = np.argmax(plan[:, :m], axis=0)
    matched = best < n
    columns = np.nonzero(matched)[0]
    keep = allowed[best[columns], columns]
    owner[columns[keep]] = best[columns[keep]]
    if cameras is not None and _conflicts(owner, np.asarray(cameras)):
        owner = _decode_one_per_camera(plan, allowed, best, np.asarray(cameras), capped)
    return FotaResult(owner, plan, s)


def _conflicts(owner: np.ndarray, cameras: np.ndarray) -> bool:
    """Whether some track got two detections of one camera."""
    taken = owner != UNMATCHED
    pairs = owner[taken] * (int(cameras.max(initial=0)) + 1) + cameras[taken]
    return len(np.unique(pairs)) < len(pairs)


def _decode_one_per_camera(plan: np.ndarray, allowed: np.ndarray, best: np.ndarray, cameras: np.ndarray,
                           cost: np.ndarray) -> np.ndarray:
    """Greedy decoding by plan mass under the one-detection-per-camera-per-track constraint (module
    docstring)."""
    n, m = allowed.shape
    owner = np.full(m, UNMATCHED, dtype=np.int64)
    real = plan[:n, :m]
    blocked = (best < n) & ~allowed[np.minimum(best, n - 1), np.arange(m)]  # argmax is an out-of-gate track
    candidate = allowed & (real > plan[n, :m][None, :]) & ~blocked[None, :]
    rows, cols = np.nonzero(candidate)
    if len(rows) == 0:
        return owner
    order = np.lexsort((cols, rows, cost[rows, cols], -real[rows, cols]))
    taken: set[tuple[int, int]] = set()
    for i, j in zip(rows[order].tolist(), cols[order].tolist(), strict=True):
        key = (i, int(cameras[j]))
        if owner[j] != UNMATCHED or key in taken:
            continue
        owner[j] = i
        taken.add(key)
    return owner
