// The collapse engine with a policy of its own (collapse_engine.hpp): collapse passes that rank
// again from their last ranking make the collapses of passes that evaluate every edge anew.
#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "collapse_engine.hpp"
#include "mesh_preparation.hpp"
#include "test_aqem_meshes.hpp"

namespace {

using animlod::detail::Candidate;
using animlod::detail::CollapseEngine;
using animlod::detail::EngineLevel;
using animlod::detail::EngineRecord;

// The squared length of the edge in frame 0, times the points each endpoint stands for: both
// change at every collapse at the point (the kept point moves to the midpoint and absorbs the
// removed one), so a cost carried over from an earlier ranking where it should not be changes
// the choice.
class MidpointPolicy final : public animlod::detail::CollapsePolicy {
 public:
  explicit MidpointPolicy(const CollapseEngine& engine) : engine_(engine), points_(engine.point_count(), 1.0) {}

  void evaluate(Candidate& candidate) override {
    const double length2 = (engine_.position(candidate.kept, 0) - engine_.position(candidate.removed, 0)).squaredNorm();
    candidate.cost = length2 * (points_[candidate.kept] + points_[candidate.removed]);
    candidate.error = std::sqrt(length2);
  }
  void place(Candidate& candidate, std::vector<Eigen::Vector3d>& placed) override {
    candidate.t = 0.5;
    for (size_t frame = 0; frame < placed.size(); ++frame)
      placed[frame] = 0.5 * (engine_.position(candidate.kept, frame) + engine_.position(candidate.removed, frame));
  }
  void merge(const Candidate& candidate) override { points_[candidate.kept] += points_[candidate.removed]; }
  // Evaluations read the two points only, merges write the kept one: fit for both workers.
  size_t concurrency() const override { return 2; }

 private:
  const CollapseEngine& engine_;
  std::vector<double> points_;  // (P,) input points each point stands for
};

struct Run {
  EngineRecord record;
  std::vector<EngineLevel> levels;
};

Run simplify_in_passes(const animlod::testing::OwnedAnimatedMesh& mesh, const std::vector<size_t>& targets,
                       bool rank_from_last) {
  const animlod::AnimatedMeshView view = mesh.view();
  const animlod::detail::PreparedMesh prepared = animlod::detail::prepare_mesh(view, animlod::detail::WeldInput{});
  const animlod::detail::CarriedData data;
  animlod::detail::EngineOptions options;
  options.collapse_passes = true;
  options.rank_from_last = rank_from_last;
  CollapseEngine engine(view, prepared, data, options);
  MidpointPolicy policy(engine);
  Run run;
  engine.run(policy, targets, run.levels, run.record);
  return run;
}

}  // namespace

TEST_CASE("collapse passes ranking from the last ranking collapse as if every edge were evaluated anew") {
  const animlod::testing::OwnedAnimatedMesh mesh = animlod::testing::sphere(200, 340, 2);  // 135,320 faces
  const size_t faces = mesh.faces.size() / 3;
  const std::vector<size_t> targets = {faces / 2, faces / 8, faces / 40};
  const Run reused = simplify_in_passes(mesh, targets, true);
  const Run anew = simplify_in_passes(mesh, targets, false);
  REQUIRE(reused.levels.size() == targets.size());
  for (const EngineLevel& level : reused.levels) CHECK(level.reached);
  CHECK(reused.record.removed == anew.record.removed);
  CHECK(reused.record.kept == anew.record.kept);
  CHECK(reused.record.positions == anew.record.positions);
  for (size_t l = 0; l < targets.size(); ++l) CHECK(reused.levels[l].faces == anew.levels[l].faces);
}
