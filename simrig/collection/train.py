"""Training the learned association (:mod:`simrig.trackers.learned`) on a collection's (track, detection) pairs,
and what it learned.

A logistic regression (scikit-learn's ``LogisticRegression``, L2, ``C`` = 1) on the standardised features and
their squares. What it learned is reported as permutation importances (Breiman, "Random Forests", 2001; the
method of scikit-learn's ``permutation_importance``): the drop in ROC AUC on held-out pairs when one feature's
values are shuffled across pairs (the feature and its square together), averaged over ``repeats`` shuffles.
Needs the ``learn`` extra (``pip install 'simrig-mot[learn]'``).
"""

from __future__ import annotations

import numpy as np

from simrig.seeding import stream_generator
from simrig.trackers.association_features import TRACK_FEATURES
from simrig.trackers.learned import AssociationModel, design


def _sklearn():
    try:
        from sklearn.linear_model import LogisticRegression
        from sklearn.metrics import roc_auc_score
    except ImportError:
        raise ImportError("training needs scikit-learn: pip install 'simrig-mot[learn]'") from None
    return LogisticRegression, roc_auc_score


def fit_association(features: np.ndarray, same: np.ndarray, *, threshold: float = 0.5, c: float = 1.0,
                    trained_on: dict | None = None) -> AssociationModel:
    """The model of P(same object) fitted to (P, F) ``features`` and (P,) ``same``; ``trained_on`` is recorded."""
    logistic, _ = _sklearn()
    if len(same) == 0 or same.all() or not same.any():
        raise ValueError(f"same: training needs pairs of both kinds, got {int(same.sum())} same of {len(same)}")
    x = design(np.asarray(features, float))
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    fit = logistic(C=c, max_iter=2000).fit((x - mean) / scale, np.asarray(same, bool))
    return AssociationModel(tuple(mean.tolist()), tuple(scale.tolist()), tuple(fit.coef_[0].tolist()),
                            float(fit.intercept_[0]), threshold, trained_on=dict(trained_on or {}))


def roc_auc(model: AssociationModel, features: np.ndarray, same: np.ndarray) -> float:
    """ROC AUC of the model's probabilities on held-out pairs."""
    _, score = _sklearn()
    return float(score(same, model.probability(features)))


def permutation_importances(model: AssociationModel, features: np.ndarray, same: np.ndarray, *, repeats: int = 5,
                            seed: int = 0) -> dict[str, float]:
    """Per feature, the mean drop in ROC AUC when its values are shuffled across the pairs (module docstring)."""
    _, score = _sklearn()
    generator = stream_generator("feature_shuffles", seed)
    base = score(same, model.probability(features))
    drops = {}
    for column, name in enumerate(TRACK_FEATURES):
        losses = []
        for _ in range(repeats):
            shuffled = features.copy()
            shuffled[:, column] = generator.permutation(shuffled[:, column])
            losses.append(base - score(same, model.probability(shuffled)))
        drops[name] = float(np.mean(losses))
    return drops
