"""``simrig detector fit --embeddings``: the appearance model's settings from a log of a real re-ID model.

The log is a Parquet table, a row per observed object: ``frame`` (integer), ``camera`` (any value; pairs are
taken within one camera), ``identity`` (any value), ``embedding`` (a list of floats, one length) and,
optionally, ``sequence`` (any value: pairs never cross sequences). Embeddings are normalised to unit length.

What is fitted (the model of :mod:`simrig.sensor.appearance` at its reference condition: the log says nothing
of occlusion, truncation, range or the side seen, so their effects are folded into the fitted noise):

* from the same-identity pairs of one camera g frames apart, the mean cosine similarity m(g) at every gap of
  :data:`GAPS` with at least :data:`MIN_PAIRS` pairs — which sets ``sigma``, the two drifts' norms and their
  correlation times (at the log's frame rate);
* from same-identity pairs seen by two cameras at the same frame (when the log has them), the mean cosine
  similarity — two cameras see the same drifts at one instant and differ by their images' noise alone, so this
  separates ``sigma`` from the drifts (a slow drift is told from a lasting appearance only by the longest gaps:
  a log shorter than a few of its correlation times determines ``slow_drift_sigma`` and ``slow_drift_time_s``
  poorly, and the summary says so);
* from different-identity pairs of one camera 1–30 frames apart, the mean and the standard deviation of the
  cosine similarity — which set the effective ``dimension``. ``lookalike_weight`` and ``colours`` are given, not
  fitted (default 0.3 and 8, the realistic presets'): they move the different-identity mean by only about
  w / colours, which a log of a few dozen identities cannot tell from the dimension.

The fit is simulated moments: the model's moments are computed by simulation from fixed random numbers (so
they are smooth in the settings) and matched by weighted least squares (each moment divided by its
standard error), for effective dimensions walked from 1 / variance of the different-identity cosine in steps
of about 15 % while the misfit falls; the dimension with the smallest misfit wins.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simrig.seeding import stream_generator

from ..dataset.outputs import write_text_atomic
from ..errors import SimrigError
from ..reading import check_regular
from ..sensor.processes import ar1_coefficient
from .reid import (
    EmbeddingLog,
    cross_camera_pairs,
    different_identity_pairs,
    format_table,
    reid_table,
    same_identity_pairs,
    within_sequences,
)

GAPS = (1, 2, 3, 4, 6, 8, 11, 15, 20, 27, 36, 48, 64, 85, 113, 150, 200, 240)
"""[frames] gaps whose mean same-identity cosine is matched."""
MIN_PAIRS = 30
"""Pairs a gap needs to take part."""
MAX_PAIRS = 5000
"""Pairs sampled per gap and for the different-identity moments."""
SIMULATED_PAIRS = 3000
COLUMNS = ("frame", "camera", "identity", "embedding")
MAX_NORM, MAX_TIME_S = 10.0, 3600.0
"""The schema's bounds on the drifts' and noise's norms and on the correlation times [s]."""
POOR_FIT = 9.0
"""Mean squared standardised residual above which the summary warns that the model does not fit the log."""
FITTED = ("dimension", "sigma", "drift_sigma", "drift_time_s", "slow_drift_sigma", "slow_drift_time_s")


@dataclass(frozen=True)
class Moments:
    """What the fit matches: mean same-identity cosine per gap (with standard errors) and the different-identity
    cosine's mean and standard deviation (with theirs)."""

    gaps: np.ndarray
    same_mean: np.ndarray
    same_error: np.ndarray
    different_mean: float
    different_sd: float
    different_mean_error: float
    different_sd_error: float
    cross_mean: float | None = None
    """Mean same-identity cosine of two cameras at one frame (None without such pairs)."""
    cross_error: float | None = None


def read_embedding_log(path: Path | str) -> EmbeddingLog:
    """Read and check a log (see the module docstring); every problem is one :class:`SimrigError` line naming the
    file and the column or row."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = Path(path)
    try:
        check_regular(path, "--embeddings", SimrigError)  # a folder, a FIFO or a device named as such
    except FileNotFoundError:
        raise SimrigError(f"--embeddings {str(path)!r}: no such file (a Parquet table with columns "
                          f"{', '.join(COLUMNS)})") from None
    try:
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as error:
        raise SimrigError(f"--embeddings {str(path)!r}: not a Parquet table ({str(error).splitlines()[0]})") from None
    missing = [name for name in COLUMNS if name not in table.column_names]
    if missing:
        raise SimrigError(f"{path}: missing column(s) {', '.join(missing)} (has {', '.join(table.column_names)})")
    column = table.column("embedding")
    if not (pa.types.is_list(column.type) or pa.types.is_large_list(column.type)) or not (
            pa.types.is_floating(column.type.value_type) or pa.types.is_integer(column.type.value_type)):
        raise SimrigError(f"{path}: column embedding must hold lists of numbers, has {column.type}")
    column = column.combine_chunks()
    if column.null_count:
        raise SimrigError(f"{path}: column embedding: row {int(np.argmax(column.is_null().to_numpy(False)))} is null")
    lengths = np.diff(column.offsets.to_numpy())
    if not len(lengths):
        raise SimrigError(f"{path}: no rows")
    if np.any(lengths != lengths[0]):
        other = int(np.argmax(lengths != lengths[0]))
        raise SimrigError(f"{path}: column embedding: row 0 has {lengths[0]} values but row {other} has "
                          f"{lengths[other]}; one length expected")
    if lengths[0] < 2:
        raise SimrigError(f"{path}: column embedding: {lengths[0]} value(s) per row; at least 2 expected")
    vectors = column.flatten().to_numpy(zero_copy_only=False).astype(float).reshape(len(lengths), int(lengths[0]))
    bad = ~np.isfinite(vectors).all(axis=1)
    if bad.any():
        raise SimrigError(f"{path}: column embedding: row {int(np.argmax(bad))} holds NaN or infinity "
                          f"({int(bad.sum())} of {len(bad)} rows do)")
    norms = np.linalg.norm(vectors, axis=1)
    if np.any(norms == 0):
        raise SimrigError(f"{path}: column embedding: row {int(np.argmax(norms == 0))} is all zeros")
    frame = table.column("frame")
    if not pa.types.is_integer(frame.type) or frame.null_count:
        raise SimrigError(f"{path}: column frame must hold integers without nulls, has {frame.type}")
    frames = frame.to_numpy().astype(np.int64)
    if frames.min() < 0:
        raise SimrigError(f"{path}: column frame: row {int(np.argmin(frames))} is negative ({frames.min()})")
    codes = {name: _codes(table.column(name), path, name) for name in ("camera", "identity")}
    sequence = (_codes(table.column("sequence"), path, "sequence") if "sequence" in table.column_names
                else np.zeros(len(frames), dtype=np.int64))
    if len(np.unique(codes["identity"])) < 2:
        raise SimrigError(f"{path}: column identity: only one identity "
                          f"({table.column('identity')[0].as_py()!r}); different-identity pairs need at least two")
    return EmbeddingLog(sequence, frames, codes["camera"], codes["identity"], vectors / norms[:, None])


def _codes(column, path: Path, name: str) -> np.ndarray:
    """Integer codes of a column's values (any type without nulls)."""
    if column.null_count:
        raise SimrigError(f"{path}: column {name} has {column.null_count} null value(s)")
    return np.unique(np.asarray(column.to_pylist(), dtype=object).astype(str), return_inverse=True)[1].astype(np.int64)


def _measured_moments(log: EmbeddingLog, seed: int = 0) -> Moments:
    """The moments of ``log`` (see the module docstring)."""
    rng = stream_generator("appearance_fit_pairs", seed)
    camera, identity = within_sequences(log)

    def cosines(pairs: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        pick = rng.permutation(len(pairs[0]))[:MAX_PAIRS]
        return np.einsum("pd,pd->p", log.embeddings[pairs[0][pick]], log.embeddings[pairs[1][pick]])

    gaps, means, errors = [], [], []
    for gap in GAPS:
        cosine = cosines(same_identity_pairs(log.frame, camera, identity, gap, gap, rng))
        if len(cosine) < MIN_PAIRS:
            continue
        gaps.append(gap)
        means.append(cosine.mean())
        errors.append(max(cosine.std(ddof=1) / np.sqrt(len(cosine)), 1e-3))
    if len(gaps) < 3:
        raise SimrigError(f"only {len(gaps)} frame gap(s) with {MIN_PAIRS} or more same-identity pairs in one camera; "
                          "the fit needs at least 3 (log each identity over more consecutive frames)")
    different = cosines(different_identity_pairs(log.frame, camera, identity, 1, 30, MAX_PAIRS, rng))
    if len(different) < MIN_PAIRS:
        raise SimrigError(f"only {len(different)} different-identity pairs 1–30 frames apart in one camera; the fit "
                          f"needs {MIN_PAIRS}")
    sd = different.std(ddof=1)
    n = len(different)
    cross_mean = cross_error = None
    cross = cosines(cross_camera_pairs(log.frame, camera, identity))
    if len(cross) >= MIN_PAIRS:
        cross_mean, cross_error = float(cross.mean()), max(float(cross.std(ddof=1) / np.sqrt(len(cross))), 1e-3)
    return Moments(np.array(gaps), np.array(means), np.array(errors), float(different.mean()), float(sd),
                   float(sd / np.sqrt(n)), float(sd / np.sqrt(2 * (n - 1))), cross_mean, cross_error)


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


class _Simulator:
    """The model's moments at gaps ``gaps`` [frames] for effective dimension ``dimension``, from fixed random
    numbers (common to every evaluation)."""

    def __init__(self, dimension: int, gaps: np.ndarray, colours: int, seed: int = 0):
        rng = stream_generator("appearance_fit_model", seed, dimension)
        m, d = SIMULATED_PAIRS, dimension
        self.gaps, self.colours = gaps, colours
        self.own = _unit(rng.standard_normal((2, m, d)))
        self.prototype = _unit(rng.standard_normal((colours, d)))
        self.same_colour = rng.random(m) < 1.0 / colours
        self.colour = rng.integers(colours, size=m)
        # per gap: drift states now and the innovations to g frames later, white noise of both observations
        self.start = rng.standard_normal((2, m, d)) / np.sqrt(d)
        self.innovation = rng.standard_normal((len(gaps), 2, m, d)) / np.sqrt(d)
        self.noise = rng.standard_normal((len(gaps), 2, m, d)) / np.sqrt(d)
        self.stranger = rng.standard_normal((3, m, d)) / np.sqrt(d)  # the other actor's two drifts and noise
        self.other_camera = rng.standard_normal((m, d)) / np.sqrt(d)  # another camera's noise at the same instant

    def moments(self, sigma: float, drifts: np.ndarray, phis: np.ndarray, lookalike: float, period: float
                ) -> tuple[np.ndarray, float, float, float]:
        """Mean same-identity cosine per gap, different-identity cosine mean and sd, and the mean same-identity
        cosine of two cameras at one frame."""
        w = lookalike
        first_colour = self.prototype[self.colour]
        other_colour = np.where(self.same_colour[:, None], first_colour,
                                self.prototype[(self.colour + 1) % self.colours])
        identity = _unit(np.sqrt(1 - w) * self.own[0] + np.sqrt(w) * first_colour)
        stranger = _unit(np.sqrt(1 - w) * self.own[1] + np.sqrt(w) * other_colour)
        drift_now = drifts[0] * self.start[0] + drifts[1] * self.start[1]
        first = _unit(identity + drift_now + sigma * self.noise[0, 0])
        same = np.empty(len(self.gaps))
        for index, gap in enumerate(self.gaps):
            later = sum(scale * (phi**gap * self.start[j] + np.sqrt(1 - phi ** (2 * gap)) * self.innovation[index, j])
                        for j, (scale, phi) in enumerate(zip(drifts, phis, strict=True)))
            second = _unit(identity + later + sigma * self.noise[index, 1])
            anchor = _unit(identity + drift_now + sigma * self.noise[index, 0])
            same[index] = np.einsum("pd,pd->p", anchor, second).mean()
        other = _unit(stranger + drifts[0] * self.stranger[0] + drifts[1] * self.stranger[1]
                      + sigma * self.stranger[2])
        different = np.einsum("pd,pd->p", first, other)
        elsewhere = _unit(identity + drift_now + sigma * self.other_camera)  # the same drifts, its own noise
        cross = float(np.einsum("pd,pd->p", first, elsewhere).mean())
        return same, float(different.mean()), float(different.std(ddof=1)), cross


@dataclass(frozen=True)
class AppearanceFit:
    """The fitted settings (``[sensor.embedding]`` keys), the misfit (sum of squared standardised residuals), the
    moments matched and the model's at the fit."""

    settings: dict
    misfit: float
    moments: Moments
    fitted_same: np.ndarray
    fitted_different: tuple[float, float]
    fitted_cross: float


def fit_appearance(log: EmbeddingLog, frame_rate_hz: float = 10.0, *, lookalike_weight: float = 0.3,
                   colours: int = 8) -> AppearanceFit:
    """Fit the appearance model to ``log`` (frames at ``frame_rate_hz``; ``lookalike_weight`` and ``colours``
    given)."""
    if not (np.isfinite(frame_rate_hz) and frame_rate_hz > 0):
        raise SimrigError(f"--frame-rate-hz: must be a positive number, got {frame_rate_hz}")
    moments = _measured_moments(log)
    period = 1.0 / frame_rate_hz
    first_guess = int(np.clip(round(1.0 / max(moments.different_sd**2, 1e-6)), 2, 1024))
    fits: dict[int, AppearanceFit] = {}
    if not 0 <= lookalike_weight < 1:
        raise SimrigError(f"--lookalike-weight: must be in [0, 1), got {lookalike_weight}")
    start = np.array([np.log(0.4), np.log(0.5), np.log(0.5), np.log(5 * period), np.log(50 * period)])

    def fit_at(dimension: int) -> AppearanceFit:
        dimension = int(np.clip(dimension, 2, 1024))
        if dimension not in fits:
            fits[dimension] = _fit_dimension(moments, dimension, period, lookalike_weight, colours, start)
        return fits[dimension]

    # the misfit is near unimodal in the dimension: walk from the first guess in steps of ~15 % while it improves
    best = fit_at(first_guess)
    for step in (1.15, 1 / 1.15):
        dimension = first_guess
        while True:
            dimension = int(round(dimension * step)) if round(dimension * step) != dimension else dimension + (
                1 if step > 1 else -1)
            if not 2 <= dimension <= 1024:
                break
            candidate = fit_at(dimension)
            if candidate.misfit >= best.misfit:
                break
            best = candidate
    return best


def _fit_dimension(moments: Moments, dimension: int, period: float, lookalike: float, colours: int,
                   start: np.ndarray) -> AppearanceFit:
    """The least-squares fit of the continuous settings at one effective dimension."""
    from scipy.optimize import least_squares

    simulator = _Simulator(dimension, moments.gaps, colours)

    def unpack(x: np.ndarray) -> tuple:
        """Settings within the schema's bounds (norms ≤ 10, correlation times ≤ 3600 s, the slow one the longer)."""
        sigma, fast, slow = np.minimum(np.exp(x[:3]), MAX_NORM)
        tau_fast = min(float(np.exp(x[3])), MAX_TIME_S)
        tau_slow = min(tau_fast + float(np.exp(x[4])), MAX_TIME_S)
        return sigma, np.array([fast, slow]), np.array([tau_fast, tau_slow])

    def model(x: np.ndarray) -> tuple:
        sigma, drifts, taus = unpack(x)
        phis = np.array([ar1_coefficient(period, tau) for tau in taus])
        return simulator.moments(sigma, drifts, phis, lookalike, period)

    def residuals(x: np.ndarray) -> np.ndarray:
        same, mean, sd, cross = model(x)
        cross_residual = [] if moments.cross_mean is None else [(cross - moments.cross_mean) / moments.cross_error]
        return np.concatenate([(same - moments.same_mean) / moments.same_error,
                               [(mean - moments.different_mean) / moments.different_mean_error,
                                (sd - moments.different_sd) / moments.different_sd_error], cross_residual])

    result = least_squares(residuals, start, method="trf", max_nfev=100)
    sigma, drifts, taus = unpack(result.x)
    same, mean, sd, cross = model(result.x)
    settings = {"dimension": dimension, "sigma": sigma, "drift_sigma": drifts[0], "drift_time_s": taus[0],
                "slow_drift_sigma": drifts[1], "slow_drift_time_s": taus[1], "lookalike_weight": lookalike}
    return AppearanceFit({k: (v if k == "dimension" else round(float(v), 4)) for k, v in settings.items()},
                         float(np.sum(result.fun**2)), moments, same, (mean, sd), cross)


def fit_embeddings_to_toml(path: Path, out: Path, frame_rate_hz: float = 10.0, *, lookalike_weight: float = 0.3,
                           colours: int = 8) -> str:
    """Fit the log at ``path`` and write ``out`` (a TOML file with a ``[sensor.embedding]`` table); returns a
    summary: the log's re-ID table, the matched moments and the file's text."""
    import tomli_w

    log = read_embedding_log(path)
    try:
        fit = fit_appearance(log, frame_rate_hz, lookalike_weight=lookalike_weight, colours=colours)
    except SimrigError as error:
        raise SimrigError(f"{path}: {error}") from None
    m = fit.moments
    settings = {**fit.settings, "colours": colours, "viewpoint_weight": 0.0, "occlusion_sigma": 0.0,
                "truncation_sigma": 0.0}
    notes = [
        f"fitted by simrig detector fit --embeddings {path} ({len(log)} rows, frames at {frame_rate_hz:g} Hz)",
        "occlusion, truncation and range are not in the log: their average effect is in sigma and the drifts, so",
        "occlusion_sigma, truncation_sigma and viewpoint_weight are 0; a scenario extending a preset keeps the",
        "preset's distance_scale_m (noise growing with range on top of the log's average)",
        f"misfit {fit.misfit:.1f} over {_moments_count(m)} moments (sum of squared standardised residuals)",
        *([] if fit.misfit <= POOR_FIT * _moments_count(m) else [
            f"WARNING: the model does not fit this log well (misfit {fit.misfit / _moments_count(m):.0f} per moment;"
            " a good fit is near 1): compare the tables above before using these settings"]),
        *([] if fit.settings["slow_drift_time_s"] < MAX_TIME_S else [
            f"slow_drift_time_s is at the schema's bound {MAX_TIME_S:g} s: the log shows no end to the slow drift's "
            "memory"]),
        *([] if len(np.unique(log.identity)) >= 10 else [
            f"WARNING: only {len(np.unique(log.identity))} identities: the different-identity moments are unreliable"]),
        *([] if m.cross_mean is not None else [
            "one camera per identity and frame: the images' own noise is told from the fast drift only by the",
            "shortest gaps (log two cameras seeing the same objects at the same instant to pin sigma)"]),
        *([] if (span := float(m.gaps.max()) / frame_rate_hz) >= 2 * fit.settings["slow_drift_time_s"] else [
            f"the longest gap, {span:g} s, is under twice slow_drift_time_s: a slow drift is told from a lasting "
            "look only by gaps that span its memory, so slow_drift_sigma and slow_drift_time_s are uncertain"]),
    ]
    text = "".join(f"# {note}\n" for note in notes) + tomli_w.dumps({"sensor": {"embedding": settings}})
    lines = ["gap [frames]  mean cos same (this log)  (fitted model)"]
    lines += [f"{gap:>12}  {mean:>19.3f}  {model:>7.3f}"
              for gap, mean, model in zip(m.gaps, m.same_mean, fit.fitted_same, strict=True)]
    lines.append(f"different identities: mean cos {m.different_mean:.3f} (model {fit.fitted_different[0]:.3f}), "
                 f"sd {m.different_sd:.3f} (model {fit.fitted_different[1]:.3f})")
    if m.cross_mean is not None:
        lines.append(f"same identity, two cameras, one frame: mean cos {m.cross_mean:.3f} "
                     f"(model {fit.fitted_cross:.3f})")
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out, text)
    return "\n".join(["the log's re-ID table (left) beside the source's (right):", format_table(reid_table(log)), "",
                      *lines, "", text, f"written to {out}"])


def _moments_count(moments: Moments) -> int:
    """How many moments the fit matched."""
    return len(moments.gaps) + 2 + (moments.cross_mean is not None)
