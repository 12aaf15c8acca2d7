// Every options struct of the core as a Python class (options_class.hpp), bound before the
// functions that take them so that their signatures name the classes.
#include <string>

#include <pybind11/pybind11.h>

#include "animlod/aqem.hpp"
#include "animlod/ffd_lattice.hpp"
#include "animlod/lod_selector.hpp"
#include "animlod/motion_features.hpp"
#include "animlod/motion_refit.hpp"
#include "animlod/tdag.hpp"
#include "animlod/tdag_player.hpp"
#include "options_class.hpp"

namespace animlod::bindings {

namespace {
std::string positive(float value) { return value > 0.0f ? "" : "must be > 0"; }
}  // namespace

void bind_options(py::module_& m) {
  OptionsClass<MotionFeatureOptions>(m, "MotionFeatureOptions")
      .field("feature_threshold", &MotionFeatureOptions::feature_threshold)
      .field("min_angle_change", &MotionFeatureOptions::min_angle_change)
      .field("boundary_is_feature", &MotionFeatureOptions::boundary_is_feature)
      .choice("feature_weighting", &MotionFeatureOptions::feature_weighting)
      .field("max_feature_weight", &MotionFeatureOptions::max_feature_weight)
      .field("noise_mads", &MotionFeatureOptions::noise_mads)
      .finish();

  // progress is an argument of simplify_animated, not a field: a callback is no setting to
  // compare, print or send to a worker.
  OptionsClass<AqemOptions>(m, "AqemOptions")
      .field("target_ratios", &AqemOptions::target_ratios)
      .field("target_face_counts", &AqemOptions::target_face_counts)
      .field("max_error", &AqemOptions::max_error)
      .field("use_motion_features", &AqemOptions::use_motion_features)
      .nested("motion_features", &AqemOptions::motion_features)
      .field("boundary_quadrics", &AqemOptions::boundary_quadrics)
      .field("tip_quadrics", &AqemOptions::tip_quadrics)
      .field("check_inversion", &AqemOptions::check_inversion)
      .field("fold_limit", &AqemOptions::fold_limit)
      .field("max_frames", &AqemOptions::max_frames)
      .field("frame_subset", &AqemOptions::frame_subset)
      .field("quadric_memory_limit", &AqemOptions::quadric_memory_limit)
      .choice("placement", &AqemOptions::placement)
      .field("weld", &AqemOptions::weld)
      .field("record_positions", &AqemOptions::record_positions)
      .finish();

  OptionsClass<TdagOptions>(m, "TdagOptions")
      .choice("governing", &TdagOptions::governing)
      .field("governing_frame", &TdagOptions::governing_frame)
      .field("history_weight", &TdagOptions::history_weight)
      .choice("affine_base", &TdagOptions::affine_base)
      .field("boundary_quadrics", &TdagOptions::boundary_quadrics)
      .field("check_inversion", &TdagOptions::check_inversion)
      .field("use_motion_features", &TdagOptions::use_motion_features)
      .field("weld", &TdagOptions::weld)
      .finish();

  OptionsClass<PlayerOptions>(m, "PlayerOptions")
      .field("tolerance", &PlayerOptions::tolerance)
      .field("first_frame", &PlayerOptions::first_frame)
      .field("frame_count", &PlayerOptions::frame_count)
      .field("measure_error", &PlayerOptions::measure_error)
      .finish();

  OptionsClass<FfdFitOptions>(m, "FfdFitOptions")
      .field("smoothness", &FfdFitOptions::smoothness)
      .field("ridge", &FfdFitOptions::ridge)
      .finish();

  OptionsClass<MotionRefitOptions>(m, "MotionRefitOptions")
      .field("hard_constraints", &MotionRefitOptions::hard_constraints)
      .field("ftol_rel", &MotionRefitOptions::ftol_rel)
      .field("max_evaluations", &MotionRefitOptions::max_evaluations)
      .field("feasibility_tolerance", &MotionRefitOptions::feasibility_tolerance)
      .field("warm_start", &MotionRefitOptions::warm_start)
      .field("precondition", &MotionRefitOptions::precondition)
      .field("eliminate_points", &MotionRefitOptions::eliminate_points)
      .field("rigid_bodies", &MotionRefitOptions::rigid_bodies)
      .field("bone_directions", &MotionRefitOptions::bone_directions)
      .field("chunk_frames", &MotionRefitOptions::chunk_frames)
      .field("threads", &MotionRefitOptions::threads)
      .finish();

  // The selector and the update rate read these in the render loop, without a Status.
  OptionsClass<LodSelectorOptions>(m, "LodSelectorOptions")
      .checked_field("hysteresis", &LodSelectorOptions::hysteresis, [](float h) { return h >= 0.0f ? std::string() : std::string("must be >= 0"); })
      .checked_field("pixel_error", &LodSelectorOptions::pixel_error, positive)
      .finish();

  OptionsClass<AnimationRateOptions>(m, "AnimationRateOptions")
      .checked_field("full_rate_coverage", &AnimationRateOptions::full_rate_coverage, positive)
      .checked_field("max_interval", &AnimationRateOptions::max_interval,
                     [](int frames) { return frames >= 1 ? std::string() : std::string("must be >= 1 frame"); })
      .finish();
}

}  // namespace animlod::bindings
