"""What every export format is handed (:class:`ExportInput`) and the error an export raises."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simrig.dataset import Dataset
from simrig.dataset.ground_truth import GroundTruth
from simrig.dataset.tracks_file import TrackRows
from simrig.errors import SimrigError
from simrig.scenarios.evaluation_schema import EvaluationConfig


class ExportError(SimrigError):
    """An export could not be written (unknown format, output folder in the way)."""


@dataclass(frozen=True, eq=False)
class ExportInput:
    """What every format gets: the dataset, its ground truth, the :class:`~simrig.formats.evaluation.IgnoreRule`
    bits of every box ``(R, C)`` (what ``simrig score`` ignores with the same settings), and the tracker's rows
    (``None`` without ``--tracks``): ``rows2d`` as the scorer compares them, ``rows3d`` when the tracker gave 3D
    boxes."""

    dataset: Dataset
    truth: GroundTruth
    evaluation: EvaluationConfig
    ignored: np.ndarray
    rows2d: TrackRows | None
    rows3d: TrackRows | None
    tracker_name: str
