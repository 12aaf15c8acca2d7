"""Evaluate glTF animation samplers at fixed frame times (glTF 2.0 specification, Appendix C).

Vectorised over the sample times: one ``searchsorted`` finds every frame's key interval.
"""

from __future__ import annotations

import numpy as np

from .. import rotations

INTERPOLATIONS = ("LINEAR", "STEP", "CUBICSPLINE")

# A key time may sit a float32 rounding below k / fps; this slack (in frames) keeps that frame.
_FRAME_SLACK = 1e-3


# glTF clips are sampled at their keys' rate, but no more sparsely than a frame rate that keeps a
# sparse clip's level smooth, nor more densely than an exporter's rate needs.
MIN_SAMPLE_RATE, MAX_SAMPLE_RATE = 30.0, 240.0
# The share of a clip's time its finest key spacing must cover to set the clip's rate.
_DENSE_SHARE = 0.1


def key_sample_rate(key_times: list[np.ndarray]) -> float:
    """The frame rate at which to sample a clip keyed at ``key_times`` (each of its samplers'
    input): the rate of its finest key spacing that covers a tenth of its time or more, over
    every sampler's steps taken together. A reduced clip (steps of 1/60 and 2/60 s) keeps its
    60 fps; keys set close together for an instant change, or one odd step, cover too little
    time to set it. Rounded to a whole rate where it is one but for float32 rounding, within
    [MIN_SAMPLE_RATE, MAX_SAMPLE_RATE]; MIN_SAMPLE_RATE where there are no two keys."""
    steps = np.concatenate([np.diff(np.asarray(times, np.float64).ravel()) for times in key_times] or [[]])
    steps = np.sort(steps[np.isfinite(steps) & (steps > 0.0)])
    if steps.size == 0:
        return MIN_SAMPLE_RATE
    covered = np.cumsum(steps) / steps.sum()
    rate = 1.0 / float(steps[np.searchsorted(covered, _DENSE_SHARE)])
    if abs(rate - round(rate)) <= 1e-3 * rate:
        rate = float(round(rate))
    return min(max(rate, MIN_SAMPLE_RATE), MAX_SAMPLE_RATE)


def frame_times(duration: float, fps: float) -> np.ndarray:
    """Sample times ``(T,)`` in seconds: ``k / fps`` from 0, the last one at ``duration`` itself
    (T >= 1). A clip that ends between two frames (1.25 s at 30 fps) gets a last, shorter step to
    its end (1.2333, 1.25): its last pose is sampled, not the pose of its last whole frame."""
    duration = max(duration, 0.0)
    return np.minimum(np.arange(frame_count(duration, fps)) / fps, duration)


def frame_count(duration: float, fps: float) -> int:
    """How many samples :func:`frame_times` takes of a clip of ``duration`` seconds."""
    return int(np.ceil(max(duration, 0.0) * fps - _FRAME_SLACK)) + 1


def sample_keyframes(
    times: np.ndarray, values: np.ndarray, interpolation: str, at: np.ndarray, rotation: bool = False
) -> np.ndarray:
    """Interpolate one sampler's keys at the times ``at``.

    Parameters
    ----------
    times : (N,) strictly increasing key times, N >= 1.
    values : (N, C) key values, or (N, 3, C) for CUBICSPLINE (in-tangent, value, out-tangent).
    interpolation : "LINEAR", "STEP" or "CUBICSPLINE".
    at : (T,) sample times; before the first key or after the last the end values hold.
    rotation : True for (x, y, z, w) quaternions: LINEAR becomes slerp, and cubic results are
        normalised, as the specification asks.

    Returns
    -------
    (T, C) float64 values.
    """
    times = np.asarray(times, np.float64)
    values = np.asarray(values, np.float64)
    at = np.asarray(at, np.float64)
    keys = values[:, 1] if interpolation == "CUBICSPLINE" else values
    if times.shape[0] == 1:
        return np.repeat(keys[:1], at.shape[0], axis=0)
    if interpolation == "STEP":
        return keys[np.clip(np.searchsorted(times, at, side="right") - 1, 0, times.shape[0] - 1)]
    start = np.clip(np.searchsorted(times, at, side="right") - 1, 0, times.shape[0] - 2)
    span = times[start + 1] - times[start]
    s = np.clip((at - times[start]) / span, 0.0, 1.0)
    if interpolation == "LINEAR":
        if rotation:
            return rotations.slerp(keys[start], keys[start + 1], s)
        return keys[start] + s[:, None] * (keys[start + 1] - keys[start])
    # Cubic Hermite spline, Appendix C: tangents are scaled by the key interval length.
    s2, s3 = s * s, s * s * s
    result = (
        (2 * s3 - 3 * s2 + 1)[:, None] * keys[start]
        + ((s3 - 2 * s2 + s) * span)[:, None] * values[start, 2]
        + (-2 * s3 + 3 * s2)[:, None] * keys[start + 1]
        + ((s3 - s2) * span)[:, None] * values[start + 1, 0]
    )
    return rotations.normalize(result) if rotation else result
