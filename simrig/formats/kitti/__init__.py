"""KITTI tracking: label files as ground truth (:mod:`.ground_truth`) and as a tracker's output (:mod:`.tracks`),
and per-camera label files written for TrackEval's ``Kitti2DBox`` (:mod:`.writer`)."""
