"""Every ratio of every metric, computed in one place from summed counts (per sequence, per camera, per class
or overall: the same functions, whatever was summed). Denominators follow TrackEval: ``max(1, …)``.
"""

from __future__ import annotations

import numpy as np

from .counts import Counts


def _ratio(numerator, denominator):
    return numerator / np.maximum(1.0, denominator)


def hota_ratios(c: Counts) -> dict[str, float]:
    """HOTA family from :class:`~simrig.scoring.hota.HOTA` counts: each value is the mean over the 19 α;
    ``HOTA(0)`` and ``LocA(0)`` are the values at α = 0.05."""
    tp, fn, fp = c["HOTA_TP"], c["HOTA_FN"], c["HOTA_FP"]
    det_a = _ratio(tp, tp + fn + fp)
    ass_a = _ratio(c["AssA_sum"], tp)
    hota = np.sqrt(det_a * ass_a)
    loc_a = np.maximum(1e-10, c["LocA_sum"]) / np.maximum(1e-10, tp)
    per_alpha = {
        "HOTA": hota,
        "DetA": det_a,
        "AssA": ass_a,
        "LocA": loc_a,
        "DetRe": _ratio(tp, tp + fn),
        "DetPr": _ratio(tp, tp + fp),
        "AssRe": _ratio(c["AssRe_sum"], tp),
        "AssPr": _ratio(c["AssPr_sum"], tp),
    }
    out = {name: float(np.mean(values)) for name, values in per_alpha.items()}
    out["HOTA(0)"] = float(hota[0])
    out["LocA(0)"] = float(loc_a[0])
    return out


def clear_ratios(c: Counts) -> dict[str, float]:
    """CLEAR MOT from :class:`~simrig.scoring.clear.CLEAR` counts. MOTP is the mean IoU of matches (higher is
    better, TrackEval's convention); MOTA is not clipped."""
    tp, fn, fp, idsw = c["CLR_TP"], c["CLR_FN"], c["CLR_FP"], c["IDSW"]
    gt_ids = c["MT"] + c["PT"] + c["ML"]
    return {
        "MOTA": float(_ratio(tp - fp - idsw, tp + fn)),
        "MOTP": float(_ratio(c["MOTP_sum"], tp)),
        "MODA": float(_ratio(tp - fp, tp + fn)),
        "CLR_Re": float(_ratio(tp, tp + fn)),
        "CLR_Pr": float(_ratio(tp, tp + fp)),
        "MTR": float(_ratio(c["MT"], gt_ids)),
        "PTR": float(_ratio(c["PT"], gt_ids)),
        "MLR": float(_ratio(c["ML"], gt_ids)),
        **{name: int(c[name]) for name in ("CLR_TP", "CLR_FN", "CLR_FP", "IDSW", "Frag", "MT", "PT", "ML")},
    }


def identity_ratios(c: Counts) -> dict[str, float]:
    """IDF1, IDP, IDR from :class:`~simrig.scoring.identity.Identity` counts."""
    id_tp, id_fn, id_fp = c["IDTP"], c["IDFN"], c["IDFP"]
    return {
        "IDF1": float(_ratio(id_tp, id_tp + 0.5 * id_fp + 0.5 * id_fn)),
        "IDP": float(_ratio(id_tp, id_tp + id_fp)),
        "IDR": float(_ratio(id_tp, id_tp + id_fn)),
        **{name: int(c[name]) for name in ("IDTP", "IDFN", "IDFP")},
    }
