"""Scoring a tracker's output against a dataset's exact ground truth.

2D per camera (IoU): HOTA, CLEAR MOT and identity metrics, matching TrackEval. 3D (bird's-eye-view centre
distance): the nuScenes AMOTA family and MUTR3D's velocity errors. Every FN, IDS and FRAG is tagged with the
causes the dataset recorded.
"""

from simrig.dataset.tracks_file import TrackSet, read_tracks, write_tracks
from simrig.scoring.results import ScoreReport

from .api import score

__all__ = ["ScoreReport", "TrackSet", "read_tracks", "score", "write_tracks"]
