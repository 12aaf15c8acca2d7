// Distance from points to the surface of a triangle mesh: the nearest-point query behind the
// Hausdorff and RMS errors of python/animlod/metrics.py, run twice per measured frame and level,
// and its largest value alone (the Hausdorff distance of the pipelines' level errors).
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

// Non-owning view of a triangle mesh in one or several frames (same faces, moving vertices).
struct TriangleMeshView {
  const double* vertices = nullptr;  // (T, V, 3)
  const int32_t* faces = nullptr;    // (F, 3) vertex indices
  size_t vertex_count = 0;           // V
  size_t face_count = 0;             // F
  size_t frame_count = 1;            // T (0: nothing to measure)
};

// Writes out (T, N): the squared distance from each point (T, N, 3) to the nearest point of any
// triangle of the mesh in the same frame (degenerate triangles count as their edges). A
// bounding-volume hierarchy over the triangles, built on the first frame and refitted to the
// others (a point's search starts from its nearest triangle of the frame before), queried on
// up to `threads` threads (0: thread_limit(), animlod/threads.hpp); a point's result does not depend on the thread count.
// Errors: no triangle, a face index outside [0, V), a non-finite vertex or point (naming it).
Status point_mesh_squared_distance(const TriangleMeshView& mesh, const double* points, size_t point_count,
                                   unsigned threads, double* out);

// Sets `out` to the largest of those squared distances over every point and frame when it
// exceeds `floor`, to `floor` otherwise: a one-sided Hausdorff distance, squared, against a
// running maximum the caller already holds. Equal to the largest element of what
// point_mesh_squared_distance writes (or `floor`) to the bit, for any thread count; far
// cheaper, as a point's search ends at the first triangle no farther than the largest so far.
// The same errors, and a NaN floor.
Status point_mesh_max_squared_distance(const TriangleMeshView& mesh, const double* points, size_t point_count,
                                       unsigned threads, double floor, double& out);

// point_mesh_max_squared_distance of each segment of the points alone (segment s: each frame's
// points [segment_ends[s - 1], segment_ends[s]), from 0; the last end is point_count), against
// its own floors[s], into out[s], to the bit: several levels' points measured against one mesh
// with one tree, refitted once per frame. Errors: those of point_mesh_max_squared_distance, and
// segment ends that decrease or do not end at point_count.
Status point_mesh_max_squared_distances(const TriangleMeshView& mesh, const double* points, size_t point_count,
                                        const size_t* segment_ends, size_t segment_count, unsigned threads,
                                        const double* floors, double* out);

// The largest of point_mesh_squared_distance's values in each frame alone into out (T,), to the
// bit: a per-frame one-sided Hausdorff distance, squared, where every frame's error is wanted
// (the worst frame relative to its own size), a point's search ending at the first triangle no
// farther than its frame's largest so far. The same errors as point_mesh_squared_distance.
Status point_mesh_frame_max_squared_distances(const TriangleMeshView& mesh, const double* points,
                                              size_t point_count, unsigned threads, double* out);

}  // namespace animlod
