"""Gap filling before the AMOTA family (``simrig score --interpolation``), checked by arithmetic on tiny tracks;
agreement with the nuScenes devkit itself is in ``test_import.py`` (where a devkit environment exists)."""

from __future__ import annotations

import numpy as np
import pytest

from simrig.formats.nuscenes.interpolation import gaps


def test_a_two_frame_gap_gets_the_devkits_inverted_weights_or_the_linear_ones():
    frame = np.array([0, 3])
    ident = np.array([7, 7])
    x = np.array([0.0, 3.0])
    shipped = gaps(frame, ident, "devkit")
    assert shipped.frame.tolist() == [1, 2]
    assert shipped.left.tolist() == [0, 0] and shipped.right.tolist() == [1, 1]
    # frame 1 is nearer the left box, yet the devkit gives the right box the weight (3 − 1) / 3
    assert shipped.blend(x).tolist() == pytest.approx([2.0, 1.0])
    assert gaps(frame, ident, "corrected").blend(x).tolist() == pytest.approx([1.0, 2.0])
    assert len(gaps(frame, ident, "none").frame) == 0


def test_a_one_frame_gap_is_the_midpoint_either_way_and_equal_values_stay_equal():
    frame, ident = np.array([4, 6]), np.array([1, 1])
    values = np.array([[0.1, 0.7], [0.3, 0.7]])
    for variant in ("devkit", "corrected"):
        filled = gaps(frame, ident, variant)
        assert filled.frame.tolist() == [5]
        assert filled.blend(values)[0].tolist() == pytest.approx([0.2, 0.7])
        assert filled.blend(values)[0, 1] == 0.7 * 0.5 + 0.7 * 0.5  # the devkit's own order of operations


def test_filled_rows_follow_frame_then_the_order_ids_first_appear_and_no_gap_no_row():
    # id 9 appears first (frame 0), id 2 second; both miss frame 2; id 5 has no gap
    frame = np.array([0, 1, 1, 3, 3, 0, 1, 2])
    ident = np.array([9, 2, 9, 9, 2, 5, 5, 5])
    filled = gaps(frame, ident, "devkit")
    assert filled.frame.tolist() == [2, 2]
    assert ident[filled.right].tolist() == [9, 2]


def test_an_unknown_variant_is_refused():
    with pytest.raises(ValueError, match="interpolation 'linear'"):
        gaps(np.array([0, 2]), np.array([1, 1]), "linear")
