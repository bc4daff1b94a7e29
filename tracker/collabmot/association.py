"""CollabMOT's inter-camera tracklet association (Ninh and Kim, IEEE Access 2024, §III-D): Algorithm 1
(Hungarian on S with restarts), Algorithm 2 (association verification, run both ways: mutual verification) and
Eq. 6 (which global id the pair gets).

Temporary ids t𝒢 and costs tminS are collected while verifying and written to the tracklets only when the
round ends without a reset, as Alg. 1 lines 17-18. Choice where the paper is silent: minS of a pair that was
already linked keeps the smaller of its old and new cost (the "global minimum"); a new link starts at S.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from ..assignment import UNMATCHED, hungarian
from .tracklets import NO_ID, Tracklet


@dataclass
class Verification:
    """Algorithm 2's outputs for one side: ``global_id`` g (−1: none), ``valid`` V, the tracklets whose links
    it revokes (t𝒢 ← −1) and the lost tracklets it reconnects to the pair's tracklet (line 16)."""

    global_id: int = NO_ID
    valid: bool = True
    revoked: list[Tracklet] = field(default_factory=list)
    reconnected: list[Tracklet] = field(default_factory=list)


def verify(own: Tracklet, partner: Tracklet, partner_side: Iterable[Tracklet], cost: float) -> Verification:
    """Algorithm 2 for the candidate pair (``own``, ``partner``) with affinity ``cost``, against every
    tracklet T_k of the partner's camera that shares ``own``'s global id:

    * T_k is ``partner``: the pair is already linked, g = 𝒢_k;
    * T_k coexisted with ``partner`` (two objects): if minS_k < cost the old link is better and the pair is
      invalid; otherwise the old link is revoked (t𝒢 of ``own`` and T_k ← −1);
    * T_k is a lost tracklet that never coexisted with ``partner``: g = 𝒢_k and T_k is reconnected to
      ``partner`` (the same object under a new local id).
    """
    out = Verification()
    if own.global_id <= 0:
        return out
    for other in partner_side:
        if other.global_id <= 0 or other.global_id != own.global_id:
            continue
        if other is partner:
            out.global_id = other.global_id
        elif other.overlaps_in_time(partner):
            if other.min_cost < cost:
                out.valid = False
            else:
                out.revoked.extend((own, other))
        else:
            out.global_id = other.global_id
            out.reconnected.append(other)
    return out


NEW = 0
"""What :func:`combine_ids` returns when the pair needs a new global id."""


def combine_ids(g_ego: int, g_remote: int) -> int:
    """Eq. 6: the pair's global id from the two verifications' g: the one that is set if only one is; either
    if equal; −1 if both are set and differ; :data:`NEW` if neither is.

    >>> [combine_ids(*g) for g in ((4, -1), (-1, 7), (5, 5), (4, 7), (-1, -1))]
    [4, 7, 5, -1, 0]
    """
    if g_ego > 0 and g_remote > 0:
        return g_ego if g_ego == g_remote else NO_ID
    if g_ego > 0:
        return g_ego
    if g_remote > 0:
        return g_remote
    return NEW


@dataclass
class Round:
    """What one association round decided: ``links`` (ego, remote, cost) written to the tracklets,
    ``reconnections`` (lost tracklet, tracklet it continues) per camera, ``revoked`` tracklets, and how many
    times Alg. 1 restarted."""

    links: list[tuple[Tracklet, Tracklet, float]] = field(default_factory=list)
    reconnections: list[tuple[Tracklet, Tracklet]] = field(default_factory=list)
    revoked: list[Tracklet] = field(default_factory=list)
    restarts: int = 0


def associate(ego: list[Tracklet], remote: list[Tracklet], cost: np.ndarray, *, ego_all: list[Tracklet],
              remote_all: list[Tracklet], limit: float, new_id: Callable[[], int]) -> Round:
    """Algorithm 1 on the candidates ``ego`` × ``remote`` with affinity ``cost`` (N, M); ``ego_all`` and
    ``remote_all`` are every tracklet of each camera (lost ones included), ``limit`` is λ_appearance and
    ``new_id()`` hands out fresh global ids. Writes 𝒢 and minS to the tracklets and returns the round.

    When Eq. 6 asks for a new global id, the pair gets a fresh one from ``new_id()``, as the paper says — even
    if the ego tracklet had an id before (its link was just revoked)."""
    cost = np.array(cost, dtype=float, copy=True)
    result = Round()
    while True:
        owner = hungarian(np.where(cost < limit, cost, np.inf), limit)
        ids: dict[int, int] = {}  # id(tracklet) -> t𝒢
        costs: dict[int, float] = {}
        links, reconnections, revoked = [], [], []
        restart = False
        for j in np.nonzero(owner != UNMATCHED)[0]:
            i = int(owner[j])
            a, b, s = ego[i], remote[j], float(cost[i, j])
            forward = verify(a, b, remote_all, s)
            backward = verify(b, a, ego_all, s)
            if not (forward.valid and backward.valid):
                cost[i, j] = np.inf
                result.restarts += 1
                restart = True
                break
            for tracklet in forward.revoked + backward.revoked:
                ids[id(tracklet)] = NO_ID
                revoked.append(tracklet)
            g = combine_ids(forward.global_id, backward.global_id)
            if g == NEW:
                g = new_id()
            ids[id(a)] = ids[id(b)] = g
            costs[id(a)] = costs[id(b)] = s
            links.append((a, b, s))
            reconnections += [(k, b) for k in forward.reconnected] + [(k, a) for k in backward.reconnected]
        if not restart:
            break
    everything = {id(t): t for t in ego_all + remote_all}
    previous = {id(t): t.partner for a, b, _ in links for t in (a, b)}
    for key, g in ids.items():
        everything[key].global_id = g
    for a, b, s in links:
        for t, other in ((a, b), (b, a)):
            if t.global_id <= 0:
                t.partner, t.min_cost = None, np.inf
                continue
            t.min_cost = min(t.min_cost, s) if previous[id(t)] is other else costs[id(t)]
            t.partner = other
    for t in revoked:
        if t.global_id <= 0:
            t.partner, t.min_cost = None, np.inf
    result.links = [(a, b, s) for a, b, s in links if a.global_id > 0]
    result.reconnections = [(k, t) for k, t in reconnections if t.global_id > 0 and k.global_id == t.global_id]
    result.revoked = [t for t in revoked if t.global_id <= 0]
    return result
