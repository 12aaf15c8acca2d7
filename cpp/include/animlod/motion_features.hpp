// Motion features of a deforming mesh (Yang et al. 2019, "Rotation connected graph" and
// "Weight allocation"): the regions where parts move relative to each other, found from the
// change of every edge's dihedral angle between consecutive frames.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"

namespace animlod {

struct MotionFeatureOptions {
  // Radians. An edge is "connected" when its factor g_i exceeds this threshold; 0 selects an
  // adaptive THR = mean of g_i over the interior edges. (The paper averages over all edges;
  // boundary edges have no dihedral angle, g_i = 0, and are features anyway, so counting them
  // would only lower THR on open meshes.)
  double feature_threshold = 0.0;
  // Radians. g_i must also exceed this floor (the paper's 1 degree), so that rounding noise on a
  // rigidly moving mesh finds no feature (paper, Fig. 4).
  double min_angle_change = 0.017453292519943295;
  // Boundary edges have no dihedral angle; the paper counts them as connected.
  bool boundary_is_feature = true;
};

// Per edge, per vertex and per feature results. Edges are the mesh's undirected edges sorted by
// (lower vertex index, higher vertex index).
struct MotionFeatures {
  std::vector<int32_t> edges;           // (E, 2) vertex pairs, lower index first
  std::vector<float> angle_change;      // (E,) g_i in radians: max change of the dihedral angle
                                        //      between consecutive frames (0 on boundary edges)
  std::vector<uint8_t> connected;       // (E,) 1 when the edge joins a motion feature
  double threshold = 0.0;               // the THR used, radians
  std::vector<int32_t> vertex_feature;  // (V,) index of the vertex's feature, -1 outside all
  std::vector<int32_t> feature_sizes;   // (C,) vertex count w of each feature, features ordered
                                        //      by their lowest vertex index
  std::vector<float> vertex_weights;    // (V,) w of the vertex's feature, 1 outside (Eq. 6)
};

// Finds the motion features of `mesh` over all its frames.
// Errors: the input checks of validate_animated_mesh (NaN, index out of range, degenerate,
// duplicate or non-manifold faces, unreferenced vertices), each naming the element.
Status compute_motion_features(const AnimatedMeshView& mesh, const MotionFeatureOptions& options,
                               MotionFeatures& out);

}  // namespace animlod
