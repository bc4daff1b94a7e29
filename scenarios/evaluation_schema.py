"""Scenario keys of the ``[evaluation]`` table: which 2D ground-truth boxes are *ignored* when scoring.

An ignored box is a distractor, as in the peers' benchmarks: not a miss when nobody tracks it, and a tracker
box matched to it (Hungarian on IoU ≥ 0.5, TrackEval's ``MotChallenge2DBox`` preprocessing) is removed, not a
false positive. A box is ignored when any enabled rule says so; each default comes from a peer:

========================  ==========================================================  ============================
key                       ignored when                                                default (peer)
========================  ==========================================================  ============================
``range_m``               BEV distance of the box centre from the ego ≥ the range     nuScenes class ranges: car,
                          of its class [m]                                            truck, bus 50 m; motorcycle
                                                                                      40 m (devkit
                                                                                      ``filter_eval_boxes``)
``min_height_px``         pixel box (clipped to the image) shorter than this [px]     25 px (KITTI "moderate";
                                                                                      TrackEval's KITTI
                                                                                      ``min_height``)
``min_visible_fraction``  visible fraction (1 − rendered occlusion) at or below this  0: nothing visible (nuScenes
                          (not applied where the render did not measure it)           drops boxes with no sensor
                                                                                      points)
``max_truncation``        fraction of the projected box outside the image above this  0.5 (KITTI "hard")
========================  ==========================================================  ============================

``ignore = false`` scores every box in view (simrig before this table existed). ``classes = "any"`` scores
class-agnostic (MOTChallenge style: one sequence per camera, a tracker's class is not compared).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from .base import NonNegativeFloat, PositiveFloat, Strict

VEHICLE_CLASS_RANGE_M: dict[str, float] = {"car": 50.0, "truck": 50.0, "bus": 50.0, "motorcycle": 40.0}
NUSCENES_CLASS_RANGE_M: dict[str, float] = {**VEHICLE_CLASS_RANGE_M, "pedestrian": 40.0, "bicycle": 40.0}
"""[m] nuScenes' evaluation range per class (BEV distance from the ego; in range when strictly closer; devkit
``configs/tracking_nips_2019.json``). The 3D score always uses it; the 2D evaluation region uses it unless
``range_m`` says otherwise. Pedestrians and bicycles come only from imported ground truth, so a scenario's
default ``range_m`` lists the vehicles."""

ClassRanges = dict[Literal["car", "truck", "bus", "motorcycle", "pedestrian", "bicycle"], PositiveFloat]


class EvaluationConfig(Strict):
    """Which 2D ground truth counts when scoring (see the module docstring for each rule's peer)."""

    ignore: bool = True
    """Apply the rules below; false: every box in a camera's view is scored."""
    range_m: PositiveFloat | ClassRanges = Field(default_factory=lambda: dict(VEHICLE_CLASS_RANGE_M))
    """[m] one range for every class, or a range per class (classes left out keep nuScenes' range)."""
    min_height_px: NonNegativeFloat = 25.0
    """[px] boxes shorter than this are ignored (0: no height rule)."""
    min_visible_fraction: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.0
    """[-] boxes whose visible fraction is at or below this are ignored."""
    max_truncation: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.5
    """[-] boxes truncated by more than this are ignored (1: no truncation rule)."""
    classes: Literal["each", "any"] = "each"
    """``each``: a tracker box is compared with ground truth of its own class; ``any``: class-agnostic."""

    def class_range_m(self, label: str) -> float:
        """[m] the range of class ``label``."""
        if isinstance(self.range_m, dict):
            return float(self.range_m.get(label, NUSCENES_CLASS_RANGE_M[label]))
        return float(self.range_m)
