"""The one-draw-call segmentation renderer gives the node-per-actor renderer's counts, pixel for pixel.

``tests/data/visibility_counts.npz`` holds frames of four scenarios (surround and stereo rigs, highway and
roundabout, all four classes, a scripted truck occluding a car) with the ``visible_px`` and
``silhouette_px`` that pyrender's node-per-actor segmentation (one draw call per actor, simrig up to commit
3704a39) produced, recorded by ``tests/data/record_visibility.py`` before the renderer was replaced. The
frames' inputs are stored too, so the comparison does not depend on today's traffic.
"""

from pathlib import Path

import numpy as np
import pytest
from simrig.scenarios import load_scenario

from simrig.geometry import project_boxes
from simrig.render.meter import VisibilityMeter
from simrig.render.scene import RigScene
from simrig.render.visibility import Visibility
from simrig.rig import build_rig
from simrig.types import EgoPose

RECORDED = np.load(Path(__file__).parent / "data" / "visibility_counts.npz")
SCENARIOS = sorted({key.split("/")[0] for key in RECORDED.files})


class _Frame:
    def __init__(self, ego, classes, boxes):
        self.ego, self.classes, self.boxes = EgoPose(*ego), classes.astype(object), boxes


@pytest.mark.parametrize("name", SCENARIOS)
def test_visibility_table_equals_the_node_per_actor_renderers(name):
    scenario = load_scenario(name)
    rig = build_rig(scenario.rig)
    meter = VisibilityMeter(rig, scenario.render.visibility_scale, RigScene())
    offsets = RECORDED[f"{name}/offsets"]
    boxes, classes = RECORDED[f"{name}/boxes"], RECORDED[f"{name}/classes"]
    visible, silhouette = [], []
    for index, ego in enumerate(RECORDED[f"{name}/ego"]):
        actors = slice(offsets[index], offsets[index + 1])
        frame = _Frame(ego, classes[actors], boxes[actors])
        result = meter.measure(frame, project_boxes(frame.boxes, rig, frame.ego))
        visible.append(result.visible_px.T.ravel())
        silhouette.append(result.silhouette_px.T.ravel())
    visible, silhouette = np.concatenate(visible), np.concatenate(silhouette)
    expected_visible = RECORDED[f"{name}/visible_px"]
    assert (expected_visible > 0).sum() >= 20  # the recorded frames do show actors
    np.testing.assert_array_equal(visible, expected_visible)
    np.testing.assert_array_equal(silhouette, RECORDED[f"{name}/silhouette_px"])
    old = Visibility.from_counts(expected_visible, RECORDED[f"{name}/silhouette_px"])
    new = Visibility.from_counts(visible, silhouette)
    np.testing.assert_array_equal(new.occlusion, old.occlusion)  # NaNs in the same places too
