// Motion features of a deforming mesh (Yang et al. 2019, "Rotation connected graph" and
// "Weight allocation"): the regions where parts move relative to each other, found from how
// every edge's dihedral angle changes over the frames, and the vertex weights of Eq. 6.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"

namespace animlod {

// How motion features become the vertex weights of Eq. 6.
enum class FeatureWeighting {
  // The default. An edge's motion is its amplitude a_i: the range (max - min) of its dihedral
  // angle over all frames, which does not depend on the frame rate. The threshold adapts to the
  // measured spread of the amplitudes, T = median + noise_mads * MAD over the interior edges
  // (and at least min_angle_change): on captured data the bulk of the edges carries noise and
  // ordinary deformation, and a feature is an outlier far outside it. A vertex weighs
  // 1 + (max_feature_weight - 1) * clamp((a - T) / T, 0, 1) with a the largest amplitude of its interior
  // edges: bounded (a feature's collapse costs at most max_feature_weight times its quadric error) and
  // exactly 1 where nothing moves above T, so that a mesh without features simplifies exactly
  // as with use_motion_features off.
  amplitude,
  // The paper's rule: g_i = the largest change of the dihedral angle between consecutive frames,
  // THR = mean of g_i, and every vertex of a feature of w vertices weighs w (Eq. 6). On captured
  // sequences the noise makes features of thousands of vertices whose weight freezes them.
  paper,
};

// How motion features are found (paper, "Rotation connected graph") and weighted (Eq. 6).
struct MotionFeatureOptions {
  // Radians. An edge is "connected" when its motion (g_i for paper, the amplitude a_i for
  // amplitude) exceeds this threshold; 0 selects the adaptive threshold of the weighting: the
  // mean of g_i over the interior edges for paper (the paper averages over all edges; boundary
  // edges have no dihedral angle, g_i = 0, and are features anyway, so counting them would only
  // lower THR on open meshes), median + noise_mads * MAD of a_i for amplitude.
  double feature_threshold = 0.0;
  // Radians. The motion must also exceed this floor (the paper's 1 degree), so that rounding noise
  // on a rigidly moving mesh finds no feature (paper, Fig. 4).
  double min_angle_change = 0.017453292519943295;
  // Boundary edges have no dihedral angle; the paper counts them as connected. (They are
  // reported as features either way; amplitude weighting gives them no weight of their own, as
  // the boundary quadrics already keep open borders.)
  bool boundary_is_feature = true;
  // How a motion becomes a vertex weight (see FeatureWeighting).
  FeatureWeighting feature_weighting = FeatureWeighting::amplitude;
  // amplitude: the largest vertex weight, >= 1.
  double max_feature_weight = 4.0;
  // amplitude: the adaptive threshold in median absolute deviations above the median, >= 0.
  double noise_mads = 30.0;
};

// Per edge, per vertex and per feature results. Edges are the mesh's undirected edges sorted by
// (lower vertex index, higher vertex index).
struct MotionFeatures {
  std::vector<int32_t> edges;           // (E, 2) vertex pairs, lower index first
  std::vector<float> angle_change;      // (E,) g_i in radians: max change of the dihedral angle
                                        //      between consecutive frames (0 on boundary edges)
  std::vector<uint8_t> connected;       // (E,) 1 when the edge joins a motion feature
  double threshold = 0.0;               // the threshold used, radians (THR on g_i for paper, T
                                        // on a_i for amplitude)
  std::vector<int32_t> vertex_feature;  // (V,) index of the vertex's feature, -1 outside all
  std::vector<int32_t> feature_sizes;   // (C,) vertex count w of each feature, features ordered
                                        //      by their lowest vertex index
  std::vector<float> vertex_weights;    // (V,) weights of Eq. 6 (see FeatureWeighting)
  std::vector<float> amplitude;         // (E,) a_i in radians: range of the dihedral angle over
                                        //      all frames, unwrapped (0 on boundary edges)
};

// The checks of `options` that need no mesh: a negative or NaN threshold, max_feature_weight
// below 1 or not finite, negative or non-finite noise_mads. compute_motion_features runs them.
Status check_motion_feature_options(const MotionFeatureOptions& options);

// Finds the motion features of `mesh` over all its frames.
// Errors: the input checks of validate_animated_mesh (NaN, index out of range, degenerate,
// duplicate or non-manifold faces, unreferenced vertices), each naming the element; a negative
// or NaN threshold, max_feature_weight below 1 or negative noise_mads.
Status compute_motion_features(const AnimatedMeshView& mesh, const MotionFeatureOptions& options,
                               MotionFeatures& out);

}  // namespace animlod
