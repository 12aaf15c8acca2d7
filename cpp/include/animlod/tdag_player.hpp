// A double-buffered player of a TDAG (Shamir and Pascucci 2001, Section 5 and its future
// work): it walks the frames with a fixed tolerance and hands out meshes at one of the three
// temporal approximation levels, while the cut update for the next frame runs on a second
// thread, on a second cut ("two working meshes - one for reading and one for writing").
#pragma once

#include <cstdint>
#include <memory>

#include "animlod/status.hpp"
#include "animlod/tdag.hpp"

namespace animlod {

class TdagPlayer {
 public:
  explicit TdagPlayer(const TemporalDag& dag);
  ~TdagPlayer();  // waits for the update thread
  TdagPlayer(const TdagPlayer&) = delete;
  TdagPlayer& operator=(const TdagPlayer&) = delete;

  // Starts the walk at `first_frame` with a fresh query, and the update for the frame after it
  // on the second thread. Errors: frame outside [0, F), tolerance negative or NaN.
  Status start(double tolerance, int32_t first_frame = 0);
  // Hands out frame `frame()` at `level` and moves on. Level 3 waits for the cut of that frame
  // (computed on the second thread) and swaps it in; levels 1 and 2 never wait: they use the
  // newest cut already swapped in. Errors: not started, past the last frame.
  Status next(ApproximationLevel level, TdagMesh& out);
  // Hands out frame `frame()` at level 3 when its cut is ready, else at level 2 without
  // waiting (the paper's scheme: the reading thread fills the gaps). Returns the level used.
  Status next_available(TdagMesh& out, ApproximationLevel& used);

  int32_t frame() const;  // the frame next() hands out
  bool done() const;      // every frame has been handed out

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Statistics of one approximation level over a walk: seconds per frame (the call that makes
// the mesh, which includes writing out positions and faces), the distance between each input
// vertex and the vertex standing for it in the handed-out mesh (asset units; an upper bound of
// the two-sided Hausdorff distance, see tdag.hpp), and the mesh sizes.
struct PlayerLevelStats {
  double mean_seconds = 0.0;
  double max_seconds = 0.0;
  double mean_error = 0.0;  // mean over frames of the largest vertex distance of the frame
  double max_error = 0.0;   // largest over frames
  double mean_vertices = 0.0;
  double mean_faces = 0.0;
  double median_seconds = 0.0;  // robust to the odd preempted frame
};

// Which frames play_temporal_dag walks and at what tolerance.
struct PlayerOptions {
  double tolerance = 0.0;     // asset units
  int32_t first_frame = 0;    // the frame the walk starts from
  int32_t frame_count = -1;   // frames to walk after the first; -1: to the last frame
  bool measure_error = true;  // compute the errors (not timed)
};

struct PlayerReport {
  int32_t frames = 0;            // frames measured (after the first)
  PlayerLevelStats levels[3];    // levels 1 (affine), 2 (residual), 3 (full), each from the cut of the frame before
  PlayerLevelStats full_query;   // a fresh query at (frame, tolerance) and its mesh, per frame
  double mean_splits = 0.0;      // per level-3 update
  double mean_collapses = 0.0;
  double sequential_seconds_per_frame = 0.0;      // level-3 walk on one thread
  double double_buffered_seconds_per_frame = 0.0; // level-3 walk with TdagPlayer (two threads)
  double median_update_seconds = 0.0;     // the cut update of level 3 alone (TdagCut::advance)
  double median_fresh_cut_seconds = 0.0;  // the fresh query's cut alone (TdagCut::query)
};

// Walks the frames from options.first_frame and measures every level on every frame, a fresh
// query, and the level-3 walk single- and double-buffered. Errors: those of TdagCut::query.
Status play_temporal_dag(const TemporalDag& dag, const PlayerOptions& options, PlayerReport& out);

}  // namespace animlod
