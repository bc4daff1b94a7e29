"""Outside formats: one home per format for reading its ground truth, reading its tracks, writing both, and the
rules its official tool applies. simrig's own dataset and tracks files stay in :mod:`simrig.dataset`.

* :mod:`simrig.formats.motchallenge` — MOTChallenge text (TrackEval's ``MotChallenge2DBox``);
* :mod:`simrig.formats.kitti` — KITTI tracking labels (TrackEval's ``Kitti2DBox``);
* :mod:`simrig.formats.nuscenes` — the nuScenes tables and tracking-results JSON (nuscenes-devkit 1.2.0),
  with the devkit's gap interpolation (:mod:`simrig.formats.nuscenes.interpolation`).

Each format is a package of ``ground_truth`` (``simrig import``), ``tracks`` (``simrig score`` reading a
tracker's output) and ``writer`` (``simrig export``). Shared by them: :mod:`simrig.formats.importing` and
:mod:`simrig.formats.imported_truth` (an import as a simrig dataset), :mod:`simrig.formats.tracks` (reading
tracks in any format), :mod:`simrig.formats.export` (the export entry point), :mod:`simrig.formats.text_rows`
(parsing text rows) and :mod:`simrig.formats.evaluation` (the evaluation region: which 2D ground truth the
official tools ignore, applied by the scorer and written into the exports alike).
"""

OUTSIDE_FORMATS = ("motchallenge", "kitti", "nuscenes")
"""The outside formats simrig imports, reads tracks in and exports to."""
