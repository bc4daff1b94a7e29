"""Which open-loop tracking metric predicts how the car drives: rank correlations of every metric with every
closed-loop outcome of a closed-loop bench, with bootstrap intervals (``simrig report`` on such a bench).

A *configuration* is a tracker at one detector setting (the suite's base or one sweep value) on one scenario. Its
metric and its outcome are means over the suite's seeds (the least time to collision capped at
:data:`TTC_CAP_S` first, so that a drive where nothing ever closed in counts as a safe one, not as infinity). Per
scenario, Spearman's ρ and Kendall's τ-b over the configurations say whether the metric orders them as driving
does; each metric and outcome is first oriented so that higher is better (:data:`METRICS`, :data:`OUTCOMES`), so a
positive correlation is agreement. Over scenarios: the mean of the per-scenario correlations. This is the
system-level agreement a benchmark's user relies on ("if my tracker scores higher, does it drive better?"), as
NAVSIM (Dauner et al., NeurIPS 2024) compared its open-loop score with closed-loop results across planners.

Intervals: 95 % BCa bootstrap over seeds (:func:`bca_interval`) — each replicate draws the seeds with replacement
(one draw shared by every configuration and scenario, so configurations stay paired) and recomputes the means and
the correlations; the jackknife (each seed left out once) gives the acceleration. Where the replicates lie almost
wholly on one side of the estimate (:func:`lopsided`) the interval is the jackknife's instead
(:func:`jackknife_interval`). A difference between two metrics is bootstrapped on the same replicates (paired).

Both correlations are computed here, vectorised over the replicates (ranks by :func:`scipy.stats.rankdata`, τ-b as
Σ sgn·sgn / √(Σ sgn² Σ sgn²) over pairs), rather than by :func:`scipy.stats.spearmanr` and
:func:`scipy.stats.kendalltau` once per replicate, which would take minutes for a suite's 2000 × 36 × scenarios
calls; the tests check both against scipy.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.stats import rankdata

from simrig.seeding import stream_generator

METRICS = (("AMOTA", "3d_AMOTA", 1), ("HOTA", "2d_HOTA", 1), ("IDF1", "2d_IDF1", 1), ("MOTA", "3d_MOTA", 1),
           ("ATVE", "3d_ATVE", -1), ("PKL", "3d_PKL", -1), ("dACC", "3d_dACC", -1), ("HZ_MISS", "3d_HZ_MISS", -1),
           ("HZ_FAKE", "3d_HZ_FAKE", -1))
"""(name, results column, +1 if higher is better else −1) of each open-loop metric."""
OUTCOMES = (("collision", "drive_collision", -1), ("least TTC", "drive_min_ttc_s", 1),
            ("hard brakes", "drive_hard_brakes", -1), ("progress lost", "drive_progress_lost_m", -1))
"""(name, results column, orientation) of each closed-loop outcome: collision rate, least time to collision,
hard brakes per drive, progress lost against the ground-truth drive [m]."""
TTC_CAP_S = 10.0
"""[s] least times to collision above this (and ``inf``) count as this: beyond it nothing was in conflict."""
REPLICATES = 2000
"""Bootstrap replicates."""
BOOTSTRAP_SEED = 20241
"""Seed of the bootstrap's draws (a fixed stream: the report is the same bytes from the same bench)."""
MIN_CONFIGURATIONS = 6
"""A scenario needs at least this many configurations with values for its correlations to be computed (over fewer,
a rank correlation takes a handful of values and its intervals say little)."""
MIN_SEEDS = 5
"""The bench needs at least this many seeds: the intervals resample them (the jackknife leaves each out; with
fewer, a correlation of means over 3 seeds has no interval worth printing)."""


class TooFewCells(ValueError):
    """The bench has too few configurations or seeds to correlate (the message says which)."""


@dataclass(frozen=True)
class Correlations:
    """Per scenario (and ``"all"``: the mean over scenarios), metric and outcome: the point estimate and the
    bootstrap replicates of Spearman's ρ and Kendall's τ-b (``*_boot`` shape ``(REPLICATES,)``).
    ``means[scenario]``: the configuration means (columns = metric and outcome columns, oriented as stored)."""

    scenarios: tuple[str, ...]
    seeds: tuple[int, ...]
    configurations: dict[str, int]
    spearman: dict[tuple[str, str, str], float]
    kendall: dict[tuple[str, str, str], float]
    spearman_boot: dict[tuple[str, str, str], np.ndarray]
    kendall_boot: dict[tuple[str, str, str], np.ndarray]
    means: dict[str, pd.DataFrame]
    spearman_jack: dict[tuple[str, str, str], np.ndarray] = field(default_factory=dict)
    kendall_jack: dict[tuple[str, str, str], np.ndarray] = field(default_factory=dict)
    """Jackknife replicates (each seed left out once), for the intervals' acceleration."""

    def interval(self, kind: str, scenario: str, metric: str, outcome: str) -> tuple[float, float]:
        """The 95 % interval of ``kind`` (``spearman`` or ``kendall``) (:func:`interval_of`)."""
        key = (scenario, metric, outcome)
        return interval_of(getattr(self, kind)[key], getattr(self, f"{kind}_boot")[key],
                           getattr(self, f"{kind}_jack").get(key), bound=1.0)

    def uses_jackknife(self, kind: str, scenario: str, metric: str, outcome: str) -> bool:
        """Whether :meth:`interval` gives the jackknife's interval (:func:`takes_jackknife`)."""
        key = (scenario, metric, outcome)
        return takes_jackknife(getattr(self, kind)[key], getattr(self, f"{kind}_boot")[key],
                               getattr(self, f"{kind}_jack").get(key))

    def difference(self, scenario: str, first: str, second: str, outcome: str) -> tuple[float, float, float]:
        """Spearman ρ(first) − ρ(second) with outcome, and its paired 95 % interval (as :meth:`interval`)."""
        key_a, key_b = (scenario, first, outcome), (scenario, second, outcome)
        point = self.spearman[key_a] - self.spearman[key_b]
        jack = None
        if key_a in self.spearman_jack and key_b in self.spearman_jack:
            jack = self.spearman_jack[key_a] - self.spearman_jack[key_b]
        boot = self.spearman_boot[key_a] - self.spearman_boot[key_b]
        return (point, *interval_of(point, boot, jack, bound=2.0))


def takes_jackknife(point: float, boot: np.ndarray, jack: np.ndarray | None) -> bool:
    """Whether the jackknife's interval stands in for BCa's: fewer than 10 % of the bootstrap replicates lie on one
    side of the estimate (:func:`lopsided`) and the jackknife has an interval of some width (with few
    configurations every seed left out can give the same ranks: then BCa's stands)."""
    return jack is not None and lopsided(point, boot) and _usable(jackknife_interval(point, jack))


def interval_of(point: float, boot: np.ndarray, jack: np.ndarray | None, *, bound: float) -> tuple[float, float]:
    """The 95 % interval of a statistic within [−bound, bound]: BCa's (:func:`bca_interval`), or the jackknife's
    (:func:`jackknife_interval`, clipped to the range) where :func:`takes_jackknife`."""
    if takes_jackknife(point, boot, jack):
        low, high = jackknife_interval(point, jack)
        return max(low, -bound), min(high, bound)
    return bca_interval(point, boot, jack)


def _usable(interval: tuple[float, float]) -> bool:
    """A finite interval at least 0.01 wide (the precision the report prints)."""
    low, high = interval
    return bool(np.isfinite(low) and np.isfinite(high) and high - low >= 0.01)


def lopsided(point: float, boot: np.ndarray, tail: float = 0.1) -> bool:
    """Whether fewer than ``tail`` of the finite bootstrap replicates lie on one side of ``point`` (BCa's bias
    correction is then so large that its interval shrinks to a sliver at one end of the replicates). A correlation of
    means over resampled seeds can sit almost wholly on one side of the estimate (a resample repeats seeds, so its
    means average fewer of them): the bootstrap then says more about that than about the estimate's spread, and
    the jackknife's interval is given instead (:meth:`Correlations.interval`)."""
    finite = boot[np.isfinite(boot)]
    if not len(finite) or not np.isfinite(point):
        return False
    below = np.mean(finite < point)
    return bool(below < tail or below > 1 - tail)


def jackknife_interval(point: float, jack: np.ndarray, level: float = 0.95) -> tuple[float, float]:
    """``point`` ± t(level, n − 1) × the jackknife standard error of the replicates ``jack`` (each seed left out
    once): √((n − 1)/n · Σ (θ₍ᵢ₎ − θ̄)²)."""
    from scipy.stats import t

    finite = jack[np.isfinite(jack)]
    if len(finite) < 3 or not np.isfinite(point):
        return (float("nan"), float("nan"))
    n = len(finite)
    error = float(np.sqrt((n - 1) / n * ((finite - finite.mean()) ** 2).sum()))
    half = float(t.ppf((1 + level) / 2, n - 1)) * error
    return point - half, point + half


def bca_interval(point: float, boot: np.ndarray, jack: np.ndarray | None, level: float = 0.95) -> tuple[float, float]:
    """The bias-corrected and accelerated bootstrap interval (Efron 1987) of a statistic with value ``point``,
    bootstrap replicates ``boot`` and jackknife replicates ``jack`` (no acceleration without them). A correlation of
    means over resampled seeds is pulled toward 0 (a resample repeats seeds, so its means are noisier): percentile
    intervals then leave the estimate at their edge, which the bias correction undoes."""
    from scipy.stats import norm

    finite = boot[np.isfinite(boot)]
    if not len(finite) or not np.isfinite(point):
        return (float("nan"), float("nan"))
    below = (np.sum(finite < point) + 0.5 * np.sum(finite == point)) / len(finite)
    z0 = norm.ppf(np.clip(below, 0.5 / len(finite), 1 - 0.5 / len(finite)))
    acceleration = 0.0
    if jack is not None and np.isfinite(jack).sum() >= 3:
        spread = np.nanmean(jack) - jack[np.isfinite(jack)]
        denominator = 6.0 * (spread ** 2).sum() ** 1.5
        acceleration = float((spread ** 3).sum() / denominator) if denominator > 0 else 0.0
    quantiles = []
    for alpha in ((1 - level) / 2, (1 + level) / 2):
        z = z0 + norm.ppf(alpha)
        quantiles.append(100 * norm.cdf(z0 + z / (1 - acceleration * z)))
    low, high = np.percentile(finite, quantiles)
    return float(low), float(high)


def oriented_values(results: pd.DataFrame) -> pd.DataFrame:
    """One row per (scenario, configuration, seed): every metric and outcome, oriented so higher is better, the
    least TTC capped at :data:`TTC_CAP_S`. ``configuration`` is ``tracker`` plus the detector setting."""
    frame = results.copy()
    value = frame["value"].map(lambda v: "" if pd.isna(v) else f"{v:g}")
    setting = np.where(frame["sweep"] == "", "", " @ " + frame["sweep"] + "=" + value)
    frame["configuration"] = frame["tracker"] + setting
    frame["drive_min_ttc_s"] = frame["drive_min_ttc_s"].clip(upper=TTC_CAP_S)
    for _, column, sign in (*METRICS, *OUTCOMES):
        frame[column] = sign * frame[column].astype(float)
    columns = [column for _, column, _ in (*METRICS, *OUTCOMES)]
    return frame[["scenario", "configuration", "seed", *columns]]


def correlate(results: pd.DataFrame, *, replicates: int = REPLICATES, seed: int = BOOTSTRAP_SEED) -> Correlations:
    """The rank correlations of every metric with every outcome (module docstring) of a closed-loop bench's
    ``results``; :class:`TooFewCells` when a scenario has fewer than :data:`MIN_CONFIGURATIONS` configurations or
    the bench fewer than :data:`MIN_SEEDS` seeds."""
    values = oriented_values(results)
    seeds = tuple(sorted(values["seed"].unique()))
    if len(seeds) < MIN_SEEDS:
        raise TooFewCells(f"{len(seeds)} seed{'s' * (len(seeds) != 1)}: the intervals over seeds need at least "
                          f"{MIN_SEEDS}")
    draws = stream_generator("seed_bootstrap", seed).integers(0, len(seeds), size=(replicates, len(seeds)))
    scenarios = tuple(dict.fromkeys(values["scenario"]))
    names = [(m, mc) for m, mc, _ in METRICS] + [(o, oc) for o, oc, _ in OUTCOMES]
    spearman, kendall, spearman_boot, kendall_boot, means, counts = {}, {}, {}, {}, {}, {}
    spearman_jack, kendall_jack = {}, {}
    for scenario in scenarios:
        rows = values[values["scenario"] == scenario]
        cube = {column: rows.pivot_table(index="configuration", columns="seed", values=column, dropna=False,
                                         aggfunc="first").reindex(columns=list(seeds)).to_numpy(float)
                for _, column in names}
        configurations = rows.pivot_table(index="configuration", columns="seed", values=names[0][1],
                                          aggfunc="first", dropna=False).index
        if len(configurations) < MIN_CONFIGURATIONS:
            raise TooFewCells(f"scenario {scenario}: {len(configurations)} configurations (trackers × detector "
                              f"settings); the correlations need at least {MIN_CONFIGURATIONS}")
        counts[scenario] = len(configurations)
        with warnings.catch_warnings():  # a configuration without a value in a resample: NaN, left out
            warnings.simplefilter("ignore", RuntimeWarning)
            point = {column: np.nanmean(cube[column], axis=1) for _, column in names}  # (C,)
            boot = {column: np.nanmean(cube[column][:, draws], axis=2) for _, column in names}  # (C, B)
        jack = {column: _left_out_means(cube[column]) for _, column in names}  # (C, S)
        means[scenario] = pd.DataFrame(point, index=configurations)
        for metric, metric_column in names[:len(METRICS)]:
            for outcome, outcome_column in names[len(METRICS):]:
                key = (scenario, metric, outcome)
                x, y = point[metric_column][:, None], point[outcome_column][:, None]
                spearman[key] = float(spearman_rho(x, y)[0])
                kendall[key] = float(kendall_tau_b(x, y)[0])
                spearman_boot[key] = spearman_rho(boot[metric_column], boot[outcome_column])
                kendall_boot[key] = kendall_tau_b(boot[metric_column], boot[outcome_column])
                spearman_jack[key] = spearman_rho(jack[metric_column], jack[outcome_column])
                kendall_jack[key] = kendall_tau_b(jack[metric_column], jack[outcome_column])
    for metric, _, _ in METRICS:
        for outcome, _, _ in OUTCOMES:
            key = ("all", metric, outcome)
            for store in (spearman, kendall, spearman_boot, kendall_boot, spearman_jack, kendall_jack):
                with warnings.catch_warnings():  # a metric constant on every scenario: NaN, said in the tables
                    warnings.simplefilter("ignore", RuntimeWarning)
                    store[key] = np.nanmean([store[(s, metric, outcome)] for s in scenarios], axis=0)
            spearman[key], kendall[key] = float(spearman[key]), float(kendall[key])
    return Correlations(scenarios, seeds, counts, spearman, kendall, spearman_boot, kendall_boot, means,
                        spearman_jack, kendall_jack)


def _left_out_means(values: np.ndarray) -> np.ndarray:
    """``(C, S)`` → ``(C, S)``: column j the mean of each row over every seed but seed j (NaN left out)."""
    present = np.isfinite(values)
    total, count = np.where(present, values, 0.0).sum(axis=1, keepdims=True), present.sum(axis=1, keepdims=True)
    left_total = total - np.where(present, values, 0.0)
    left_count = count - present
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(left_count > 0, left_total / np.maximum(left_count, 1), np.nan)


def spearman_rho(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Spearman's ρ of each column pair of ``x`` and ``y`` ``(C, B)`` (average ranks for ties; rows with a NaN in
    either dropped per column): ``(B,)``, NaN where a column is constant."""
    out = np.full(x.shape[1], np.nan)
    keep = np.isfinite(x) & np.isfinite(y)
    full = keep.all(axis=0)
    if full.any():
        out[full] = _pearson(rankdata(x[:, full], axis=0), rankdata(y[:, full], axis=0))
    for column in np.flatnonzero(~full):
        rows = keep[:, column]
        if rows.sum() >= 3:
            out[column] = _pearson(rankdata(x[rows, column])[:, None], rankdata(y[rows, column])[:, None])[0]
    return out


def _pearson(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    dx, dy = x - x.mean(axis=0), y - y.mean(axis=0)
    denominator = np.sqrt((dx * dx).sum(axis=0) * (dy * dy).sum(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denominator > 0, (dx * dy).sum(axis=0) / np.where(denominator > 0, denominator, 1), np.nan)


def kendall_tau_b(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Kendall's τ-b of each column pair of ``x`` and ``y`` ``(C, B)`` over the rows finite in both: ``(B,)``, NaN
    where a column is constant."""
    keep = np.isfinite(x) & np.isfinite(y)
    sx = np.sign(x[:, None, :] - x[None, :, :])
    sy = np.sign(y[:, None, :] - y[None, :, :])
    both = keep[:, None, :] & keep[None, :, :]
    sx, sy = np.where(both, sx, 0.0), np.where(both, sy, 0.0)
    denominator = np.sqrt((sx * sx).sum(axis=(0, 1)) * (sy * sy).sum(axis=(0, 1)))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denominator > 0, (sx * sy).sum(axis=(0, 1)) / np.where(denominator > 0, denominator, 1),
                        np.nan)
