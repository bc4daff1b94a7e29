"""Why each error happened: every FN, IDS and FRAG tagged with the causes the dataset recorded.

Causes are the sensor's (:class:`~simrig.causes.Cause` names: ``occluded``, ``truncated``, ``far``,
``scheduled_occlusion``, ``scheduled_miss``, ``blackout``, ``dropped_frame``, ``out_of_view``, …) plus
``handover`` (the set of cameras that see the actor changed) and ``none`` (nothing recorded: the detector
delivered the actor, or missed it at random, and the tracker lost it). On imported ground truth, which records
no sensor, every error's cause is ``unknown`` (never ``none``: nobody knows that nothing affected it).

* FN at (frame, actor[, camera]): why the detector did not deliver it there — in 2D that camera's causes
  where it missed the actor; in 3D, if no camera detected it, the union over the cameras that had it in
  view (``out_of_view`` when none had). Nothing when the detector delivered it.
* IDS: the miss causes from the frame after the actor's previous match up to the switch, and at least over
  the ``lookback`` frames before it; ``handover`` if the actor's camera set changed in that window.
* FRAG: the miss causes of the gap's frames; ``handover`` if the camera set changed from the last tracked
  frame to the resumption.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from simrig.formats.evaluation import rule_names

from ..causes import CAUSE_NAMES, Cause
from ..dataset.arrow_columns import shared_strings, string_codes
from ..dataset.ground_truth import GroundTruth
from .clear import ClearEvents

IGNORED = "ignored"
KINDS = ("FN", "IDS", "FRAG")
"""The kinds of error, in reporting order."""
IGNORED_KIND = "IGN"
"""Kind of an errors row for an ignored box left untracked: not an error, listed so a user sees what was not
scored and why."""
HANDOVER = "handover"
NONE = "none"
UNKNOWN = "unknown"
ATTRIBUTION_CAUSES = (*[name for name in CAUSE_NAMES if name != "clutter"], HANDOVER, NONE, UNKNOWN)
"""Every tag an error can carry, in reporting order."""
_HANDOVER_BIT = 1 << 62
ERRORS_SCHEMA = pa.schema([
    pa.field("dimension", pa.string()), pa.field("kind", pa.string()), pa.field("frame", pa.int32()),
    pa.field("camera", pa.string()), pa.field("class", pa.string()), pa.field("actor_id", pa.int64()),
    pa.field("track_id", pa.int64()), pa.field("previous_track_id", pa.int64()),
    pa.field("causes", pa.list_(pa.string())), pa.field("consequence", pa.float64()),
])
"""One row per error: ``dimension`` 3d or 2d; ``kind`` FN, IDS or FRAG (or IGN: an ignored box left
untracked); ``camera`` empty in 3D; track ids −1
where they do not apply (an FN has none; FRAG gives the track that resumed). ``consequence`` [nats]: how much
missing that vehicle alone changes the ego's plan (3D FN only, :mod:`simrig.scoring.planner`; NaN where not
weighed)."""


@dataclass(frozen=True)
class Attributor:
    """Tags errors of one dimension: ``masks`` ``(R,)`` per ground-truth row (miss causes in 3D or in one
    camera), with the rows' camera sets, and a look-back window [frames]."""

    truth: GroundTruth
    masks: np.ndarray
    lookback: int

    def tag(self, label: str, camera: str, dimension: str, events: ClearEvents) -> pa.Table:
        """The errors of one sequence's events as rows of :data:`ERRORS_SCHEMA`."""
        truth = self.truth
        fn_masks = self.masks[truth.rows_of(events.misses[:, 0], events.misses[:, 1])]
        switch_masks = [
            self._window(actor, min(previous + 1, frame - self.lookback), frame,
                         handover_from=min(previous, frame - self.lookback))
            for frame, actor, _, _, previous in events.switches.tolist()
        ]
        frag_masks = [self._window(actor, last + 1, frame - 1, handover_from=last, handover_to=frame)
                      for frame, actor, last in events.fragmentations.tolist()]
        kinds = (["FN"] * len(events.misses) + ["IDS"] * len(events.switches)
                 + ["FRAG"] * len(events.fragmentations))
        frames = np.concatenate([events.misses[:, 0], events.switches[:, 0], events.fragmentations[:, 0]])
        actors = np.concatenate([events.misses[:, 1], events.switches[:, 1], events.fragmentations[:, 1]])
        none = np.full(len(events.misses), -1)
        tracks = np.concatenate([none, events.switches[:, 2], np.full(len(events.fragmentations), -1)])
        previous = np.concatenate([none, events.switches[:, 3], np.full(len(events.fragmentations), -1)])
        masks = np.concatenate([fn_masks, np.array(switch_masks + frag_masks, dtype=np.int64)])
        n = len(kinds)
        causes = (_cause_name_lists(masks) if truth.causes_known
                  else pa.array([[UNKNOWN]] * n, type=pa.list_(pa.string())))
        return pa.table({
            "dimension": [dimension] * n, "kind": kinds, "frame": frames.astype(np.int32),
            "camera": [camera] * n, "class": [label] * n, "actor_id": actors.astype(np.int64),
            "track_id": tracks.astype(np.int64), "previous_track_id": previous.astype(np.int64),
            "causes": causes, "consequence": np.full(n, np.nan),
        }, schema=ERRORS_SCHEMA)

    def tag_ignored(self, label: str, camera: str, misses: np.ndarray, rules: np.ndarray) -> pa.Table:
        """Rows of kind ``IGN`` for ignored ground truth no tracker box was matched to (not scored, so no FN):
        ``misses`` ``(n, 2)`` (frame, actor id); causes: the rules that ignored it (``ignored_range``, …) and
        why the detector did not deliver it. ``rules``: ``(R,)`` :class:`~simrig.formats.evaluation.IgnoreRule`
        bits of this camera."""
        rows = self.truth.rows_of(misses[:, 0], misses[:, 1])
        n = len(rows)
        masks = self.masks[rows] if self.truth.causes_known else np.zeros(n, dtype=np.int64)
        causes = _name_lists(np.column_stack([rules[rows], masks]), lambda rule, mask: (
            [f"{IGNORED}_{name}" for name in rule_names(rule)] + ([] if mask == 0 else _cause_names(mask))))
        return pa.table({
            "dimension": ["2d"] * n, "kind": [IGNORED_KIND] * n, "frame": misses[:, 0].astype(np.int32),
            "camera": [camera] * n, "class": [label] * n, "actor_id": misses[:, 1].astype(np.int64),
            "track_id": np.full(n, -1, dtype=np.int64), "previous_track_id": np.full(n, -1, dtype=np.int64),
            "causes": causes, "consequence": np.full(n, np.nan),
        }, schema=ERRORS_SCHEMA)

    def _window(self, actor: int, first: int, last: int, *, handover_from: int, handover_to: int | None = None
                ) -> int:
        """Union of the actor's masks over frames [first, last], plus the handover bit if the set of cameras
        that see it changed over [handover_from, handover_to] (``handover_to`` defaults to ``last``)."""
        handover_to = last if handover_to is None else handover_to
        rows = self._actor_rows(actor)
        frames = self.truth.frame[rows]
        mask = int(np.bitwise_or.reduce(self.masks[rows[(frames >= first) & (frames <= last)]], initial=0))
        sets = self.truth.camera_sets[rows[(frames >= handover_from) & (frames <= handover_to)]]
        sets = sets[sets > 0]
        if len(sets) and np.any(sets != sets[0]):
            mask |= _HANDOVER_BIT
        return mask

    def _actor_rows(self, actor: int) -> np.ndarray:
        return np.nonzero(self.truth.actor_id == actor)[0]


def _cause_name_lists(masks: np.ndarray) -> pa.ListArray:
    """The list<string> column of :func:`_cause_names` of each of ``(n,)`` masks, built once per distinct mask.

    >>> _cause_name_lists(np.array([0, int(Cause.FAR), 0])).to_pylist()
    [['none'], ['far'], ['none']]
    """
    return _name_lists(np.asarray(masks).reshape(-1, 1), _cause_names)


def _name_lists(keys: np.ndarray, names) -> pa.ListArray:
    """The list<string> column of ``names(*key)`` for each row of ``keys`` ``(n, k)`` (integers), each list
    built once per distinct row (an errors table has a handful of distinct ones in 100,000 rows: no Python list
    per row).

    >>> _name_lists(np.array([[1, 0], [2, 3], [1, 0]]), lambda a, b: [str(a)] * b or ["-"]).to_pylist()
    [['-'], ['2', '2', '2'], ['-']]
    """
    keys = np.asarray(keys, dtype=np.int64)
    distinct, inverse = np.unique(keys, axis=0, return_inverse=True)
    lists = pa.array([names(*map(int, key)) for key in distinct], type=pa.list_(pa.string()))
    return lists.take(pa.array(inverse.reshape(-1), type=pa.int64()))


def _cause_names(mask: int) -> list[str]:
    """Tag names of a mask: cause names in bit order, ``handover``; ``["none"]`` when empty.

    >>> _cause_names(int(Cause.OCCLUDED | Cause.FAR))
    ['occluded', 'far']
    >>> _cause_names(0)
    ['none']
    """
    names = [name for name, cause in zip(CAUSE_NAMES, Cause, strict=True) if mask & int(cause)]
    if mask & _HANDOVER_BIT:
        names.append(HANDOVER)
    return names or [NONE]


def errors_by_cause(errors: pa.Table) -> dict[str, dict[str, dict[str, int]]]:
    """Per dimension, per tag: how many FN, IDS and FRAG carry it (an error with two tags counts under both),
    and ``total`` (each error once); last, ``ignored``: under FN, the ignored boxes left untracked (not
    errors, not in ``total``). Counted on the table's codes (no Python object per row or tag)."""
    out: dict[str, dict[str, dict[str, int]]] = {}
    dimension = shared_strings(errors.column("dimension"))
    kind = string_codes(errors.column("kind"), {name: i for i, name in enumerate((*KINDS, IGNORED_KIND))},
                        "errors table: kind")
    counted = kind < len(KINDS)  # not an ignored box
    causes = errors.column("causes").combine_chunks()
    tag_row = pc.list_parent_indices(causes).to_numpy()
    of_counted = counted[tag_row]
    tag = string_codes(pc.list_flatten(causes).filter(pa.array(of_counted)),
                       {name: i for i, name in enumerate(ATTRIBUTION_CAUSES)}, "errors table: cause")
    tag_row = tag_row[of_counted]
    for name in sorted(set(dimension.tolist())):
        mine = dimension == name
        counts = np.zeros((len(ATTRIBUTION_CAUSES) + 1, len(KINDS)), dtype=np.int64)  # the tags, then total
        tagged = mine[tag_row]
        np.add.at(counts, (tag[tagged], kind[tag_row[tagged]]), 1)
        counts[-1] = np.bincount(kind[mine & counted], minlength=len(KINDS))
        table = {cause: dict(zip(KINDS, row.tolist(), strict=True))
                 for cause, row in zip((*ATTRIBUTION_CAUSES, "total"), counts, strict=True)}
        out[name] = {cause: row for cause, row in table.items() if any(row.values()) or cause == "total"}
        ignored = int(np.count_nonzero(mine & ~counted))
        if ignored:
            out[name][IGNORED] = {kind: ignored if kind == "FN" else 0 for kind in KINDS}
    return out
