// Motion LoD re-fit (Ahn et al., motion LoD for crowds, seeds/000, Section 5.2): the objective
// E = alpha Ed + beta Es + gamma Ea of Eqs. 5-8 with its analytic gradient, the hard
// bone-length constraints and their Jacobians, and the per-frame SLSQP solve over a whole clip.
//
// One level's problem is over P points (every joint and end site of the original skeleton,
// point 0 the root). Per frame the unknowns are the positions x (P, 3) of the non-root points;
// the root stays at its original position. Python builds the problem (which lengths, angles and
// handed groups a level holds: python/animlod/motion_lod/objective.py, build_problem) and the
// core evaluates and solves it. Frames do not couple, so the solve runs chunks of consecutive
// frames on several threads (optionally warm-starting each frame from the previous one).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "animlod/status.hpp"

namespace animlod {

// Static structure of one level's per-frame problem; non-owning views. Lengths in the asset's
// units; every index is a point index in [0, P).
struct MotionRefitProblem {
  size_t point_count = 0;                     // P (>= 2)
  const int32_t* length_pairs = nullptr;      // (Np, 2) pairs whose length Es holds (Eq. 7)
  const double* key_lengths = nullptr;        // (Np,) their key-posture lengths b(0), > 0
  size_t length_pair_count = 0;               // Np
  const int32_t* coincident_pairs = nullptr;  // (Nc, 2) pairs at zero key length, held as vectors
  size_t coincident_pair_count = 0;           // Nc
  const int32_t* handed_quads = nullptr;      // (Nh, 4) (parent, a, b, c): det[a-p, b-p, c-p] keeps
  const double* key_volumes = nullptr;        // (Nh,) its key-posture sign (non-zero volumes)
  size_t handed_quad_count = 0;               // Nh
  const int32_t* angle_triples = nullptr;     // (Na, 3) (parent, frozen joint, child) for Ea (Eq. 8)
  const double* key_cosines = nullptr;        // (Na,) cos theta in the key posture (Eq. 4)
  size_t angle_triple_count = 0;              // Na
  // (Nf, 4) (parent, a, b, c) of a rigid group whose child c lies nearly in the plane of the
  // parent and the base children a, b: distances pin c out of that plane only to second order,
  // so the hard option holds its height over the plane, (V - V0) / A0 with V = det[a-p, b-p, c-p].
  const int32_t* flat_quads = nullptr;
  const double* flat_volumes = nullptr;       // (Nf,) V0, the key-posture volumes
  const double* flat_areas = nullptr;         // (Nf,) A0 = |(a - p) x (b - p)| in the key posture, > 0
  size_t flat_quad_count = 0;                 // Nf
  double distance_weight = 0.2;               // alpha of Eq. 5
  double string_weight = 0.4;                 // beta
  double angle_weight = 0.4;                  // gamma
  double length_scale = 1.0;                  // L: Ed and Es are divided by L^2 (unit-free E)
};

// Equality constraints of the hard option: Np + 3 Nc + Nf rows.
size_t motion_refit_equality_count(const MotionRefitProblem& problem);

// Checks indices (in range, no pair or triple repeating a point), finite positive key lengths,
// finite key cosines in [-1, 1], non-zero key volumes, finite flat volumes over finite positive
// areas, weights >= 0 with alpha > 0, L > 0.
// Errors name the array and the element, e.g. "angle_triples[3]: point 41 is outside [0, 38)".
Status validate_motion_refit_problem(const MotionRefitProblem& problem);

// E (Eq. 5) per frame and its gradient.
// x, original: (F, P, 3) candidate and original positions x^o; x's row 0 (the root) is ignored.
// out_values: (F,) E per frame. out_gradient: (F, P, 3) dE/dx (zero for the root), or nullptr.
// Errors: an invalid problem (validate_motion_refit_problem).
Status motion_refit_objective(const MotionRefitProblem& problem, const double* x, const double* original,
                              size_t frame_count, double* out_values, double* out_gradient);

// The hard equalities, scaled by 1/L: (|x_a - x_b| - b(0)) / L per length pair, then
// (x_a - x_b) / L (3 rows) per coincident pair, then (V - V0) / (A0 L) per flat quad (the change
// of its child's height over the base plane); zero when every length and height holds.
// x: (F, P, 3). out_values: (F, m) with m = motion_refit_equality_count. out_jacobian:
// (F, m, P, 3) derivatives (root column zero), or nullptr.
Status motion_refit_equalities(const MotionRefitProblem& problem, const double* x, size_t frame_count,
                               double* out_values, double* out_jacobian);

// The handedness inequalities (<= 0 when satisfied): -sign(V0) det[a-p, b-p, c-p] / L^3 per
// handed quad, keeping each rigid group of three children on its key posture's side of flat.
// x: (F, P, 3). out_values: (F, Nh). out_jacobian: (F, Nh, P, 3) (root column zero), or nullptr.
Status motion_refit_handedness(const MotionRefitProblem& problem, const double* x, size_t frame_count,
                               double* out_values, double* out_jacobian);

// How the per-frame SLSQP solves run (nlopt's LD_SLSQP).
struct MotionRefitOptions {
  // Hold every length of Es as an equality (and the handedness of rigid groups as inequalities):
  // bones keep their key lengths exactly instead of approximately (Fig. 7).
  bool hard_constraints = true;
  double ftol_rel = 1e-8;       // stop when E changes by less than this fraction (or by < 1e-22)
  int max_evaluations = 400;    // per solve
  // Largest |b - b(0)| / L accepted with hard constraints; a solve ending further off is retried.
  // SLSQP holds the lengths to a tenth of it. Tight at no cost in evaluations on the dev clips:
  // a rigid group whose children lie close to, but above _FLAT of, their base plane
  // (objective.py) is pinned out of it by distances only weakly, which multiplies a length
  // error in its shape (before flat quads, 3.4e-5 of the figure in the walk's forward kinematics
  // at 1e-6).
  double feasibility_tolerance = 1e-8;
  // Start each frame from the previous frame's result inside a chunk (when its E is below the
  // cold start's). With hard constraints the previous result moved by the root's displacement
  // (feasible: lengths are translation invariant); without, the previous correction x* - x^o
  // added to this frame's original. Off by default: a warm start carries the previous frame's
  // minimum of the angle terms (one of several) into the next frame, and on the dev clips
  // every frame from its cold start ends as low or lower (the Bandai run's two coarsest levels:
  // E 3x lower) at about the same cost once free points are eliminated (bench/bench_motion.py).
  bool warm_start = false;
  // Solve in variables where E's Hessian at the start, each term's part made positive
  // semidefinite, is the identity (y = R (x - x_start), R^T R = that matrix): SLSQP's first
  // quasi-Newton matrix is then close to the right one and it needs fewer iterations. Off: the
  // scaled displacements (x - x^o) / L, as the Python reference (motion_lod/refit.py) when
  // eliminate_points is off too.
  bool precondition = true;
  // Leave out points whose optimum follows in closed form from another's (a leaf held by one
  // length lies on the ray to its original position), that hard constraints put onto another
  // point (a zero-length pair), or that no constraint touches (frozen joints and the end sites
  // below them: minimised by Newton's method for given positions of the others, so that SLSQP
  // sees neither their variables nor the curved valleys of their angle terms), and, with hard
  // constraints, trees of points held by lengths alone that hang from one other point (a leg,
  // a finger: placed by Newton's method over their bone directions). SLSQP's cost grows with the
  // cube of the variable count. The minima are the same.
  bool eliminate_points = true;
  // With eliminate_points, hard constraints and precondition: a kept joint's kept children held
  // by a minimal rigid set of lengths move as one rigid body, three rotation variables instead of
  // three per child, and their group's lengths, heights and handedness leave SLSQP (they hold by
  // construction). A hand with its finger bases, the hips, the chest. The minima are the same.
  bool rigid_bodies = true;
  // With eliminate_points, hard constraints and precondition: a kept joint held by a length to
  // a point that stays in the solve (a chain: spine, neck, tail, hair) is placed along the
  // bone's direction, two variables instead of three and its length left out of SLSQP (it holds
  // by construction), unless a run of frozen joints hangs between the two. The minima are the
  // same.
  bool bone_directions = true;
  int chunk_frames = 64;        // with warm_start, consecutive frames per task (warm starts run
                                // inside a chunk); without, each frame is a task
  int threads = 0;              // worker threads; 0 uses thread_limit() (animlod/threads.hpp)
};

// One frame whose first solve was not kept.
struct MotionRefitFailure {
  int32_t frame = 0;
  std::string reason;   // "non-finite result", "nlopt result -1",
                        // "a held length or flat group's height is off by ...", ...
  bool fell_back = false;  // false: a cold restart succeeded; true: the fallback positions were kept
};

struct MotionRefitResult {
  std::vector<double> positions;     // (T, P, 3) re-fitted positions (root = original)
  std::vector<double> values;        // (T,) E per frame
  std::vector<int32_t> evaluations;  // (T,) objective evaluations per frame
  std::vector<MotionRefitFailure> failures;  // ordered by frame
};

// Re-fits every frame with SLSQP: minimises E (Eq. 5), with hard constraints also subject to
// motion_refit_equalities == 0 and motion_refit_handedness <= 0.
// original: (T, P, 3) original positions x^o (Ed's targets, and the root's positions).
// fallback: (T, P, 3) positions kept for a frame whose solves fail; with hard constraints they
//   must satisfy the constraints (the frozen key motion does).
// cold_starts: (T, P, 3) where each frame starts (feasible with hard constraints), or nullptr:
//   the original positions (the paper's start), or the fallback with hard constraints.
// With warm_start, each next frame of a chunk starts from the previous result instead when E is
// lower there. A frame whose original positions or cold start have E <= 1e-24
// keeps them (E >= alpha |x - x^o|^2 / L^2, so no point could move by more than ~1e-12 L). A solve is accepted when its
// result is finite, nlopt did not fail (ROUNDOFF_LIMITED is accepted), E did not rise above its
// start, and with hard constraints it is feasible within feasibility_tolerance and keeps every
// handed group's side. Otherwise the frame is solved again from its cold start, and if that
// fails too it keeps the fallback; both are reported in failures.
// Deterministic: the same input gives the same output whatever the thread count.
// Errors: an invalid problem or options, a non-finite position in original, fallback or
// cold_starts (naming the frame and point).
Status motion_refit_solve(const MotionRefitProblem& problem, const double* original, const double* fallback,
                          const double* cold_starts, size_t frame_count, const MotionRefitOptions& options,
                          MotionRefitResult& out);

}  // namespace animlod
