"""Which 2D ground-truth boxes are ignored when scoring, and by which rule (the scenario's ``[evaluation]``
table, :class:`~simrig.scenarios.evaluation_schema.EvaluationConfig`, documents each rule and the peer it
comes from). The scorer and the exports both read it here, so TrackEval on an export ignores what simrig
ignores."""

from __future__ import annotations

import enum

import numpy as np
from pydantic import ValidationError

from simrig.dataset.ground_truth import SOURCE_KINDS, GroundTruth, per_label, project_tracks
from simrig.dataset.tracks_file import TrackRows
from simrig.errors import SimrigError
from simrig.scenarios import describe_errors
from simrig.scenarios.evaluation_schema import EvaluationConfig


class EvaluationError(SimrigError):
    """Evaluation settings that are not valid; the message names the key (and the file when one set it)."""


class IgnoreRule(enum.IntFlag):
    """Why a 2D ground-truth box is ignored (bit flags: a box may break several rules)."""

    RANGE = enum.auto()
    """Its centre is at or beyond its class range from the ego (BEV)."""
    HEIGHT = enum.auto()
    """Its pixel box is shorter than the minimum height."""
    VISIBILITY = enum.auto()
    """Its visible fraction is at or below the minimum."""
    TRUNCATION = enum.auto()
    """More of it is outside the image than the maximum truncation."""
    SOURCE = enum.auto()
    """The source of an imported dataset marks it as a distractor (a MOTChallenge distractor class, a KITTI
    ``DontCare`` region or ``Van``/``Person_sitting`` box: see :mod:`simrig.formats.importing`): a tracker box
    matched to it is removed."""
    UNEVALUATED = enum.auto()
    """The source has it as ground truth that its benchmark does not evaluate (MOTChallenge: a class other than
    pedestrian and the distractors, or ``consider`` 0). Unlike the other rules, a tracker box matched to it is
    kept (a false positive), as TrackEval's ``MotChallenge2DBox`` preprocessing keeps it."""


IGNORE_RULE_NAMES: tuple[str, ...] = tuple(rule.name.lower() for rule in IgnoreRule)
"""``range``, ``height``, ``visibility``, ``truncation``, ``source``, ``unevaluated``: the rules in bit order."""


def evaluation_of(scenario: dict, override: EvaluationConfig | dict | None = None) -> EvaluationConfig:
    """The evaluation settings of a dataset's resolved ``scenario`` (its ``evaluation`` table; the defaults for
    a dataset written before the table existed), with ``override``'s keys on top (validated again)."""
    if isinstance(override, EvaluationConfig):
        return override
    base = dict(scenario.get("evaluation") or {})
    try:
        return EvaluationConfig.model_validate({**base, **(override or {})})
    except ValidationError as error:
        where = f"{', '.join(f'{k}={v!r}' for k, v in (override or {}).items())} on top of " if override else ""
        raise EvaluationError(f"evaluation settings ({where}scenario {scenario.get('name')!r}'s [evaluation]): "
                              f"{describe_errors(error)}") from None


def evaluation_overrides(pairs: list[tuple[str, object]] | None) -> dict:
    """``[evaluation]`` keys from ``KEY=VALUE`` pairs (``simrig score --evaluation``); a dotted key sets one
    entry of a table (``range_m.car=60``).

    >>> evaluation_overrides([("min_height_px", 40), ("range_m.car", 60)])
    {'min_height_px': 40, 'range_m': {'car': 60}}
    """
    out: dict = {}
    seen: set[str] = set()
    for key, value in pairs or []:
        if key in seen:
            raise EvaluationError(f"--evaluation {key} given twice")
        seen.add(key)
        head, _, entry = key.partition(".")
        if entry:
            table = out.setdefault(head, {})
            if not isinstance(table, dict):
                raise EvaluationError(f"--evaluation {key}: {head} is set as a number too")
            table[entry] = value
        else:
            out[key] = value
    return out


RULE_DTYPE = np.int8
"""The type of :func:`ignore_rules`' bit masks (six rules)."""


def ignore_rules(truth: GroundTruth, config: EvaluationConfig) -> np.ndarray:
    """``(R, C)`` :class:`IgnoreRule` bits (:data:`RULE_DTYPE`) of every ground-truth box in every camera (0:
    scored, or not in view). Vectorised over the boxes in view."""
    rules = np.zeros(truth.in_view.shape, dtype=RULE_DTYPE)
    if not config.ignore or rules.size == 0:
        return rules
    row, camera = np.nonzero(truth.in_view)  # the order of the ground truth's view_* arrays
    limit = per_label(truth.label, config.class_range_m)
    bits = np.where((truth.ego_distance >= limit)[row], int(IgnoreRule.RANGE), 0).astype(RULE_DTYPE)
    boxes = truth.view_boxes2d
    bits[boxes[:, 3] - boxes[:, 1] < config.min_height_px] |= int(IgnoreRule.HEIGHT)
    visible = 1.0 - truth.view_occlusion
    bits[np.isfinite(visible) & (visible <= config.min_visible_fraction)] |= int(IgnoreRule.VISIBILITY)
    bits[truth.view_truncation > config.max_truncation] |= int(IgnoreRule.TRUNCATION)
    if truth.source_ignored is not None:
        marked = truth.source_ignored[row, camera]
        bits[marked == 1 + SOURCE_KINDS.index("distractor")] |= int(IgnoreRule.SOURCE)
        bits[marked == 1 + SOURCE_KINDS.index("unevaluated")] |= int(IgnoreRule.UNEVALUATED)
    rules[row, camera] = bits
    return rules


def projected_in_range(truth: GroundTruth, tracks3d: TrackRows, config: EvaluationConfig) -> TrackRows:
    """A 3D tracker's boxes projected into the cameras (:func:`~simrig.dataset.ground_truth.project_tracks`)
    for 2D scoring, those whose centre is at or beyond its class range from the ego (BEV, the range the
    :attr:`IgnoreRule.RANGE` rule ignores ground truth at) dropped first, as the nuScenes devkit's
    ``filter_eval_boxes`` drops predictions beyond the range. With ``ignore`` off every box is kept, as every
    ground-truth box is scored."""
    if config.ignore and len(tracks3d):
        limit = per_label(tracks3d.label, config.class_range_m)
        tracks3d = tracks3d.take(truth.distance_from_ego(tracks3d.frame, tracks3d.boxes[:, :2]) < limit)
    return project_tracks(truth, tracks3d)


KEEPS_MATCHES = int(IgnoreRule.UNEVALUATED)
"""Rules whose boxes leave a tracker box matched to them in place (every other rule removes it)."""


def rule_names(mask: int) -> list[str]:
    """Names of the rules in ``mask``.

    >>> rule_names(int(IgnoreRule.RANGE | IgnoreRule.HEIGHT))
    ['range', 'height']
    """
    return [name for name, rule in zip(IGNORE_RULE_NAMES, IgnoreRule, strict=True) if mask & int(rule)]


def ignored_counts(rules: np.ndarray) -> dict[str, int]:
    """How many boxes of ``rules`` (any shape of :class:`IgnoreRule` bits) are ignored, and by each rule (a box
    that breaks two rules counts under both; ``ignored`` once).

    >>> ignored_counts(np.array([0, 1, 3]))
    {'ignored': 2, 'range': 2, 'height': 1, 'visibility': 0, 'truncation': 0, 'source': 0, 'unevaluated': 0}
    """
    rules = np.asarray(rules)
    out = {"ignored": int(np.count_nonzero(rules))}
    out |= {name: int(np.count_nonzero(rules & int(rule))) for name, rule in zip(IGNORE_RULE_NAMES, IgnoreRule,
                                                                                  strict=True)}
    return out
