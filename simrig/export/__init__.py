"""``simrig export``: a dataset's ground truth (and optionally a tracker's output) in other tools' formats.

* ``motchallenge`` — MOTChallenge folders laid out as TrackEval's ``MotChallenge2DBox`` reads them
  (benchmark ``SIMRIG``, split ``test``), one sequence per (camera, class);
* ``kitti`` — KITTI tracking label files per camera;
* ``nuscenes`` — nuScenes-style tracking JSON (world-frame 3D boxes).

Boxes are what ``simrig score`` compares: the ground truth's pixel boxes of the actors in each camera's view,
and a tracker's own 2D rows or its 3D tracks projected through the rig exactly as the scorer does. The output
folder is written beside its final place and renamed into it at the end, so an interrupted export leaves no
folder that looks complete.
"""

from .api import FORMATS, export

__all__ = ["FORMATS", "export"]
