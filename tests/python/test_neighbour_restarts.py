"""Frames whose re-fit stopped in a worse minimum than their neighbours' are solved again from
the neighbours' solutions (motion_lod.neighbour_restarts), on a model of E with two basins per
frame: a start in a basin ends in that basin's minimum."""

from __future__ import annotations

import numpy as np
import pytest

from animlod.motion_lod.grouped_solve import FrameFailure, RefitResult
from animlod.motion_lod.neighbour_restarts import restart_from_neighbours

GOOD, POOR = 0.0, 1.0  # a solution's basin, stored as its one coordinate


def _model(frame_count: int, poor: list[int], failed_restarts: tuple[int, ...] = ()):
    """The cold re-fit (``poor`` frames in the poor basin, E 20x the good one, the first of them
    40x) and a solver that ends each start in the start's basin; the frames of
    ``failed_restarts`` fail."""
    good_energy = 1e-3 * (1.0 + 0.1 * np.sin(np.arange(frame_count)))
    energy = {GOOD: good_energy, POOR: 20.0 * good_energy}
    if poor:
        energy[POOR][poor[0]] *= 2.0
    basin = np.full(frame_count, GOOD)
    basin[poor] = POOR
    calls = []

    def solve(frames: np.ndarray, starts: np.ndarray) -> RefitResult:
        calls.append(frames.copy())
        ends = starts[:, 0, 0]
        failures = [FrameFailure(k, "no progress", "fallback") for k, f in enumerate(frames) if f in failed_restarts]
        values = np.array([energy[end][f] for end, f in zip(ends, frames)])
        return RefitResult(starts.copy(), values, np.full(frames.size, 7), failures)

    cold = RefitResult(
        np.broadcast_to(basin[:, None, None], (frame_count, 1, 3)).copy(),
        np.array([energy[b][f] for f, b in enumerate(basin)]),
        np.full(frame_count, 10),
        [FrameFailure(int(f), "no progress", "cold restart") for f in poor],
    )
    return cold, solve, calls, good_energy


def _one_clip(result: RefitResult) -> np.ndarray:
    return np.zeros(result.objective.size, dtype=np.int64)


def test_a_frame_in_a_poorer_minimum_than_its_neighbours_is_solved_from_theirs():
    cold, solve, calls, good = _model(12, [4])
    mended = restart_from_neighbours(cold, solve, _one_clip(cold))
    np.testing.assert_array_equal(mended.objective, good)
    assert np.all(mended.positions[:, 0, 0] == GOOD) and not mended.failures
    assert sorted(np.concatenate(calls).tolist()) == [4, 4, 4, 4]  # from frames 2, 3, 5 and 6, in one call
    assert len(calls) == 1 and mended.evaluations[4] == 10 + 4 * 7 and mended.evaluations[3] == 10


def test_a_run_of_poor_frames_is_mended_from_its_ends_inward():
    # Frames 3..8 in the poor basin: only frame 3 stands above both neighbours at first; each
    # mended frame lets the next one in stand above it. (A run with no such frame stays: looking
    # at every frame above one neighbour doubled the Bandai clip's solves and lowered no E.)
    cold, solve, _, good = _model(14, [3, 4, 5, 6, 7, 8])
    mended = restart_from_neighbours(cold, solve, _one_clip(cold))
    np.testing.assert_array_equal(mended.objective, good)


def test_a_restart_that_fails_or_does_not_lower_e_is_not_kept():
    cold, solve, calls, _ = _model(10, [5], failed_restarts=(5,))
    mended = restart_from_neighbours(cold, solve, _one_clip(cold))
    np.testing.assert_array_equal(mended.positions, cold.positions)
    np.testing.assert_array_equal(mended.objective, cold.objective)
    assert mended.failures == cold.failures and len(calls) == 1
    smooth, solve, calls, _ = _model(10, [])
    restart_from_neighbours(smooth, solve, _one_clip(smooth))
    assert not calls  # no peak, no solve


@pytest.mark.parametrize("poor, neighbours", [(6, [7, 8]), (5, [3, 4])])
def test_frames_of_two_clips_played_one_after_another_are_not_neighbours(poor, neighbours):
    """Soldier's clips joined into one motion: a clip's first frame was started from the last
    frames of the clip before (other poses). Such restarts took ~200 SLSQP evaluations a frame
    against ~10, and Soldier's skinned chain went from 3.3 to 17 s of CPU."""
    clip_of = np.repeat([0, 1], 6)  # frame 6 starts the second clip
    cold, solve, _, good = _model(12, [poor])
    cold.positions[:, 0, 1] = np.arange(12)  # each solution tagged with its frame
    started_from = []

    def tagged(frames: np.ndarray, starts: np.ndarray) -> RefitResult:
        started_from.extend(starts[:, 0, 1].astype(int).tolist())
        return solve(frames, starts)

    mended = restart_from_neighbours(cold, tagged, clip_of)
    np.testing.assert_array_equal(mended.objective, good)
    assert sorted(started_from) == neighbours
