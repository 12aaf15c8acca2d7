// Motion LoD re-fit, the solve (seeds/000, Section 5.2: "SQP is applied to solve this
// problem"): one small SLSQP problem per frame (nlopt's LD_SLSQP through its C library), since
// E (Eq. 5) does not couple frames. Phases per frame: pick the start (the cold start, or with
// warm starts the previous frame's result within a chunk of consecutive frames), precondition,
// solve, check, and retry from the cold start or fall back when the check fails. Chunks (single
// frames without warm starts) run on std::threads; a chunk's result depends only on its own
// frames, so the output does not depend on the thread count.
//
// The Python reference of the same loop is python/animlod/motion_lod/refit.py.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <nlopt.h>

#include "animlod/motion_refit.hpp"
#include "motion_refit_detail.hpp"
#include "motion_refit_reduction.hpp"
#include "worker_threads.hpp"

namespace animlod {

namespace {

// E below this at a cold start counts as solved there (see motion_refit_solve).
constexpr double kNegligibleObjective = 1e-24;
// SLSQP also stops when E changes by less than this between iterations (nlopt's ftol_abs), as
// well as by less than ftol_rel of itself. E >= alpha |x - x^o|^2 / L^2, so a change this small
// moves points by ~1e-11 L, far below the float32 keys the levels are written with (~6e-8 L).
// It only acts where E < kObjectiveResolution / ftol_rel: where a level reproduces the clip
// almost exactly (Xbot's finest levels, E ~ 1e-20), there E's own rounding (changing each
// position by one ulp changes E by ~1e-7 of itself) is above ftol_rel, and SLSQP kept iterating
// on rounding noise until its line search failed: 16 evaluations per frame instead of 7 at Xbot's
// 47-joint level, ending at the same E to 8 digits (bench/bench_motion.py).
constexpr double kObjectiveResolution = 1e-22;

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One thread's state for the frame being solved; nlopt's callbacks read it through their data
// pointer. Variables are over the reduced points (motion_refit_reduction.hpp; all non-root points
// when the solve is not preconditioned).
struct FrameContext {
  const MotionRefitProblem* problem = nullptr;
  detail::PointReduction* reduction = nullptr;
  size_t point_count = 0;
  size_t variable_count = 0;         // n (PointReduction::variable_count)
  bool precondition = false;
  const double* original = nullptr;  // (P, 3) this frame's x^o
  std::vector<double> start;         // (n,) reduced x_start of the preconditioned variables
  Eigen::MatrixXd factor;            // lower L with L L^T = E's (clipped) Hessian at x_start
  std::vector<double> reduced;       // (n,) reduced positions of the current variables
  std::vector<double> x;             // (P, 3) positions of the current variables
  std::vector<double> gradient;      // (P, 3)
  std::vector<double> jacobian;      // (rows, P, 3)
  std::vector<double> values;        // (rows,) every row before the kept ones are picked
  std::vector<double> placed_at;     // (n,) the variables x was last filled for, when placed
  bool placed = false;
};

// Positions from variables: reduced positions y = y^o + L z (plain), or y = y_start + L^-T v
// (preconditioned), then the full positions (the root is always the original root).
void to_positions(FrameContext& c, const double* v) {
  const size_t n = c.variable_count;
  // nlopt asks for E and the constraints at the same point one after the other.
  if (c.placed && std::equal(v, v + n, c.placed_at.begin())) return;
  c.placed = true;
  std::copy(v, v + n, c.placed_at.begin());
  if (!c.precondition) {
    c.reduction->gather(c.original, c.reduced.data());
    const double scale = c.problem->length_scale;
    for (size_t i = 0; i < n; ++i) c.reduced[i] += scale * v[i];
  } else {
    Eigen::Map<Eigen::VectorXd> d(c.reduced.data(), static_cast<Eigen::Index>(n));
    d = Eigen::Map<const Eigen::VectorXd>(v, static_cast<Eigen::Index>(n));
    if (n > 0) c.factor.triangularView<Eigen::Lower>().transpose().solveInPlace(d);
    for (size_t i = 0; i < n; ++i) c.reduced[i] += c.start[i];
  }
  c.reduction->fill(c.reduced.data(), c.original, c.x.data());
}

// Derivative rows over full positions (rows, P, 3) to rows over the variables: over reduced
// positions, times L (plain) or L^-1 (preconditioned). out: (rows, n) row-major, as nlopt wants.
void to_variables(FrameContext& c, const double* rows_in, size_t rows, double* out) {
  const size_t n = c.variable_count;
  c.reduction->reduce_rows(rows_in, rows, out);
  if (!c.precondition) {
    const double scale = c.problem->length_scale;
    for (size_t i = 0; i < rows * n; ++i) out[i] *= scale;
    return;
  }
  // out as a column-major (n, rows) matrix holds the rows as columns.
  Eigen::Map<Eigen::MatrixXd> columns(out, static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(rows));
  c.factor.triangularView<Eigen::Lower>().solveInPlace(columns);
}

double objective_callback(unsigned, const double* v, double* grad, void* data) {
  auto& c = *static_cast<FrameContext*>(data);
  to_positions(c, v);
  const double value =
      detail::refit_objective_frame(*c.problem, c.x.data(), c.original, grad ? c.gradient.data() : nullptr);
  if (grad) to_variables(c, c.gradient.data(), 1, grad);
  return value;
}

// The rows `kept` marks of c.values and c.jacobian (all rows), packed into result and, when
// grad is not nullptr, their derivatives over the variables.
void keep_rows(FrameContext& c, const std::vector<uint8_t>& kept, unsigned m, double* result, double* grad) {
  const size_t stride = 3 * c.point_count;
  size_t row = 0;  // the kept rows, packed to the front
  for (size_t k = 0; k < kept.size(); ++k) {
    if (!kept[k]) continue;
    result[row] = c.values[k];
    if (grad && row != k) std::copy_n(c.jacobian.begin() + static_cast<long>(k * stride), stride,
                                      c.jacobian.begin() + static_cast<long>(row * stride));
    ++row;
  }
  if (grad) to_variables(c, c.jacobian.data(), m, grad);
}

void equality_callback(unsigned m, double* result, unsigned, const double* v, double* grad, void* data) {
  auto& c = *static_cast<FrameContext*>(data);
  to_positions(c, v);
  detail::refit_equalities_frame(*c.problem, c.x.data(), c.values.data(), grad ? c.jacobian.data() : nullptr);
  keep_rows(c, c.reduction->kept_equalities(), m, result, grad);
}

void handedness_callback(unsigned m, double* result, unsigned, const double* v, double* grad, void* data) {
  auto& c = *static_cast<FrameContext*>(data);
  to_positions(c, v);
  detail::refit_handedness_frame(*c.problem, c.x.data(), c.values.data(), grad ? c.jacobian.data() : nullptr);
  keep_rows(c, c.reduction->kept_handed(), m, result, grad);
}

std::string format(const char* pattern, double value) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

struct Outcome {
  double value = 0.0;
  int evaluations = 0;
  std::string reason;  // empty when the solve is accepted
};

// One SLSQP solve of one frame from `start` (P, 3); writes the result positions (P, 3).
class FrameSolver {
 public:
  FrameSolver(const MotionRefitProblem& problem, const MotionRefitOptions& options)
      : problem_(problem),
        options_(options),
        hard_(options.hard_constraints && motion_refit_equality_count(problem) > 0),
        reduction_(problem, hard_, options.eliminate_points, options.rigid_bodies && options.precondition,
                   options.bone_directions && options.precondition) {
    const size_t p = problem.point_count;
    const size_t m = motion_refit_equality_count(problem);
    c_.problem = &problem_;
    c_.reduction = &reduction_;
    c_.point_count = p;
    c_.variable_count = reduction_.variable_count();
    c_.precondition = options.precondition;
    c_.start.assign(c_.variable_count, 0.0);
    c_.reduced.assign(c_.variable_count, 0.0);
    c_.placed_at.assign(c_.variable_count, 0.0);
    c_.x.assign(3 * p, 0.0);
    c_.gradient.assign(3 * p, 0.0);
    c_.values.assign(std::max(m, problem.handed_quad_count), 0.0);
    c_.jacobian.assign(std::max(m, problem.handed_quad_count) * 3 * p, 0.0);
    if (options.precondition) {
      full_hessian_.assign(9 * (p - 1) * (p - 1), 0.0);
      hessian_.resize(c_.variable_count, c_.variable_count);
    }
    variables_.assign(c_.variable_count, 0.0);
    equality_values_.assign(m, 0.0);
    handed_values_.assign(problem.handed_quad_count, 0.0);

    if (c_.variable_count == 0) return;  // every point free or placed: nothing for SLSQP
    opt_.reset(nlopt_create(NLOPT_LD_SLSQP, static_cast<unsigned>(c_.variable_count)));
    if (!opt_) return;
    nlopt_set_min_objective(opt_.get(), objective_callback, &c_);
    const size_t kept = reduction_.kept_equality_count();
    if (hard_ && kept > 0) {
      const std::vector<double> tolerance(kept, 0.1 * options.feasibility_tolerance);
      nlopt_add_equality_mconstraint(opt_.get(), static_cast<unsigned>(kept), equality_callback, &c_,
                                     tolerance.data());
    }
    const size_t handed = reduction_.kept_handed_count();
    if (hard_ && handed > 0) {
      const std::vector<double> zero(handed, 0.0);
      nlopt_add_inequality_mconstraint(opt_.get(), static_cast<unsigned>(handed), handedness_callback, &c_,
                                        zero.data());
    }
    nlopt_set_ftol_rel(opt_.get(), options.ftol_rel);
    nlopt_set_ftol_abs(opt_.get(), kObjectiveResolution);
    nlopt_set_maxeval(opt_.get(), options.max_evaluations);
  }

  bool ok() const { return opt_ != nullptr || c_.variable_count == 0; }

  double energy(const double* x, const double* original) const {
    return detail::refit_objective_frame(problem_, x, original, nullptr);
  }

  // The largest |residual| of the held lengths and flat groups' heights at x (P, 3).
  double largest_violation(const double* x) {
    detail::refit_equalities_frame(problem_, x, equality_values_.data(), nullptr);
    double violation = 0.0;
    for (double v : equality_values_) violation = std::max(violation, std::abs(v));
    return violation;
  }

  Outcome solve(const double* original, const double* start, double* result) {
    const size_t n = c_.variable_count;
    c_.original = original;
    c_.placed = false;
    reduction_.set_start(start, original);
    reduction_.gather(start, c_.start.data());
    if (c_.precondition) {
      std::fill(variables_.begin(), variables_.end(), 0.0);
      // The start with its eliminated points placed: to_positions at v = 0, which needs no
      // factor (on the first frame there is none yet; solving with its 0 x 0 matrix broke
      // Eigen's size check, tests/fuzz/crashes/motion_refit).
      std::copy(c_.start.begin(), c_.start.end(), c_.reduced.begin());
      reduction_.fill(c_.reduced.data(), c_.original, c_.x.data());
      prepare_preconditioner();
    } else {
      reduction_.gather(original, c_.reduced.data());
      for (size_t i = 0; i < n; ++i) variables_[i] = (c_.start[i] - c_.reduced[i]) / problem_.length_scale;
      to_positions(c_, variables_.data());
    }
    Outcome outcome;
    const double start_value = energy(c_.x.data(), original);
    // A start is feasible up to the rounding of the clip's keys: a joint whose translation keys
    // differ from the key posture's by float noise (not a translating joint) moves its held
    // lengths by ~1e-7 L, and holding them then costs E. Only a feasible start bounds the result.
    const bool feasible_start = !hard_ || largest_violation(c_.x.data()) <= options_.feasibility_tolerance;
    double minimum = 0.0;
    nlopt_result code = NLOPT_SUCCESS;
    outcome.evaluations = 1;
    if (opt_) {
      code = nlopt_optimize(opt_.get(), variables_.data(), &minimum);
      outcome.evaluations = nlopt_get_numevals(opt_.get());
    }
    to_positions(c_, variables_.data());
    std::copy(c_.x.begin(), c_.x.end(), result);
    const bool finite = std::all_of(c_.x.begin(), c_.x.end(), [](double v) { return std::isfinite(v); });
    outcome.value = finite ? energy(result, original) : std::numeric_limits<double>::infinity();
    if (!std::isfinite(outcome.value)) {
      outcome.reason = "non-finite result";
    } else if (code < 0 && code != NLOPT_ROUNDOFF_LIMITED) {
      // NLopt documents ROUNDOFF_LIMITED as usually still a useful result: it passes the checks.
      outcome.reason = "nlopt result " + std::to_string(static_cast<int>(code));
    } else if (hard_) {
      const double violation = largest_violation(result);
      if (violation > options_.feasibility_tolerance) {
        outcome.reason = format("a held length or flat group's height is off by %.3g L", violation);
      } else if (!handed_values_.empty()) {
        detail::refit_handedness_frame(problem_, result, handed_values_.data(), nullptr);
        if (*std::max_element(handed_values_.begin(), handed_values_.end()) > 0.0)
          outcome.reason = "a rigid group turned into its mirror image";
      }
    }
    // From a feasible start (see motion_refit_solve), a result above it is never progress.
    if (outcome.reason.empty() && feasible_start && outcome.value > start_value)
      outcome.reason = "objective rose above its start";
    return outcome;
  }

 private:
  // E's Hessian (each term's part positive semidefinite) at the placed start c_.x, over the
  // reduced coordinates (T^T H T), and its Cholesky factor.
  void prepare_preconditioner() {
    const auto n = static_cast<Eigen::Index>(c_.variable_count);
    if (n == 0) return;  // every point free or placed: no variables to precondition
    detail::refit_hessian_frame(problem_, c_.x.data(), true, full_hessian_.data());
    reduction_.reduce_matrix(full_hessian_.data(), hessian_.data());
    Eigen::LLT<Eigen::MatrixXd> llt(hessian_);  // symmetric: row-major = column-major
    if (llt.info() == Eigen::Success) {
      c_.factor = llt.matrixL();
    } else {  // not expected (the matrix is >= 2 alpha / L^2 I); Ed's curvature alone then
      const double scale = problem_.length_scale;
      c_.factor = Eigen::MatrixXd::Identity(n, n) * std::sqrt(2.0 * problem_.distance_weight) / scale;
    }
  }

  struct NloptDeleter {
    void operator()(nlopt_opt opt) const { nlopt_destroy(opt); }
  };

  const MotionRefitProblem& problem_;
  const MotionRefitOptions& options_;
  bool hard_ = false;
  detail::PointReduction reduction_;
  FrameContext c_;
  std::vector<double> full_hessian_;
  RowMajor hessian_;
  std::unique_ptr<std::remove_pointer_t<nlopt_opt>, NloptDeleter> opt_;
  std::vector<double> variables_;
  std::vector<double> equality_values_;
  std::vector<double> handed_values_;
};

Status check_options(const MotionRefitOptions& options) {
  if (!(options.ftol_rel >= 0.0 && std::isfinite(options.ftol_rel)))
    return Status::error("ftol_rel: expected a finite number >= 0, got " + std::to_string(options.ftol_rel));
  if (options.max_evaluations < 1)
    return Status::error("max_evaluations: must be at least 1, got " + std::to_string(options.max_evaluations));
  if (!(options.feasibility_tolerance > 0.0 && std::isfinite(options.feasibility_tolerance)))
    return Status::error("feasibility_tolerance: expected a finite positive number, got " +
                         std::to_string(options.feasibility_tolerance));
  if (options.chunk_frames < 1)
    return Status::error("chunk_frames: must be at least 1, got " + std::to_string(options.chunk_frames));
  if (options.threads < 0) return Status::error("threads: must be >= 0, got " + std::to_string(options.threads));
  return Status::success();
}

Status check_positions(const double* positions, size_t frame_count, size_t point_count, const char* name) {
  for (size_t i = 0; i < frame_count * point_count * 3; ++i)
    if (!std::isfinite(positions[i]))
      return Status::error(std::string(name) + ": frame " + std::to_string(i / (3 * point_count)) + ", point " +
                           std::to_string(i / 3 % point_count) + " is not finite");
  return Status::success();
}

}  // namespace

Status motion_refit_solve(const MotionRefitProblem& problem, const double* original, const double* fallback,
                          const double* cold_starts, size_t frame_count, const MotionRefitOptions& options,
                          MotionRefitResult& out) {
  Status status = validate_motion_refit_problem(problem);
  if (status) status = check_options(options);
  if (status) status = check_positions(original, frame_count, problem.point_count, "original");
  if (status) status = check_positions(fallback, frame_count, problem.point_count, "fallback");
  if (status && cold_starts) status = check_positions(cold_starts, frame_count, problem.point_count, "cold_starts");
  if (!status) return status;

  const size_t p = problem.point_count;
  const size_t stride = 3 * p;
  out.positions.assign(frame_count * stride, 0.0);
  out.values.assign(frame_count, 0.0);
  out.evaluations.assign(frame_count, 0);
  out.failures.clear();
  // Without warm starts every frame starts cold and is a task of its own: the threads share
  // short solves (a trial re-fit's 16 frames) and uneven frames evenly, with the same results.
  const auto chunk_frames = options.warm_start ? static_cast<size_t>(options.chunk_frames) : size_t{1};
  const size_t chunk_count = (frame_count + chunk_frames - 1) / chunk_frames;
  std::vector<std::vector<MotionRefitFailure>> chunk_failures(chunk_count);
  std::atomic<size_t> next_chunk{0};
  std::atomic<bool> out_of_memory{false};
  const bool hard = options.hard_constraints && motion_refit_equality_count(problem) > 0;

  auto worker = [&]() {
    FrameSolver solver(problem, options);
    if (!solver.ok()) {
      out_of_memory = true;
      return;
    }
    std::vector<double> start(stride);
    for (size_t chunk = next_chunk++; chunk < chunk_count; chunk = next_chunk++) {
      const size_t first = chunk * chunk_frames;
      const size_t last = std::min(frame_count, first + chunk_frames);
      for (size_t t = first; t < last; ++t) {
        const double* o = original + t * stride;
        // Cold start: the caller's, or the original positions (the paper), or with hard
        // constraints the fallback, which is feasible and on the key posture's side of every
        // mirror image.
        const double* cold = cold_starts ? cold_starts + t * stride : hard ? fallback + t * stride : o;
        if (t == first || !options.warm_start) {
          std::copy(cold, cold + stride, start.begin());
        } else {
          const double* previous = out.positions.data() + (t - 1) * stride;
          const double* previous_original = original + (t - 1) * stride;
          for (size_t i = 0; i < stride; ++i)  // hard: move by the root; else keep the correction
            start[i] = previous[i] + (hard ? o[i % 3] - previous_original[i % 3] : o[i] - previous_original[i]);
        }
        double* result = out.positions.data() + t * stride;
        // E >= alpha |x - x^o|^2 / L^2 (Eq. 6): where E is this small at the original positions
        // or the cold start, no point can move by more than ~1e-12 L, so that is the optimum (a
        // group no frozen joint touches; lengths then hold too, so it is feasible).
        const double cold_value = solver.energy(cold, o);
        const double original_value = solver.energy(o, o);
        if (std::min(cold_value, original_value) <= kNegligibleObjective) {
          const double* solved = original_value <= cold_value ? o : cold;
          std::copy(solved, solved + stride, result);
          out.values[t] = std::min(cold_value, original_value);
          out.evaluations[t] = 1;
          continue;
        }
        // Of the warm and the cold start the lower E (both feasible with hard constraints).
        if (solver.energy(start.data(), o) > cold_value) std::copy(cold, cold + stride, start.begin());
        Outcome outcome = solver.solve(o, start.data(), result);
        int evaluations = outcome.evaluations;
        if (!outcome.reason.empty()) {
          const Outcome second = solver.solve(o, cold, result);
          evaluations += second.evaluations;
          MotionRefitFailure failure;
          failure.frame = static_cast<int32_t>(t);
          failure.reason = outcome.reason;
          failure.fell_back = !second.reason.empty();
          chunk_failures[chunk].push_back(failure);
          outcome = second;
          if (failure.fell_back) {
            std::copy(fallback + t * stride, fallback + (t + 1) * stride, result);
            outcome.value = solver.energy(result, o);
          }
        }
        out.values[t] = outcome.value;
        out.evaluations[t] = evaluations;
      }
    }
  };

  detail::run_workers(static_cast<unsigned>(options.threads), chunk_count, worker);  // threads >= 0 (checked)
  if (out_of_memory) return Status::error("motion refit: nlopt could not allocate its SLSQP solver");
  for (auto& failures : chunk_failures)
    out.failures.insert(out.failures.end(), failures.begin(), failures.end());
  return Status::success();
}

}  // namespace animlod
