// Points of a re-fit frame solved in closed form or by substitution (see the header). Motion LoD
// re-fit (seeds/000, Eqs. 5-7): a leaf's Ed + Es terms alpha |x_e - x^o_e|^2 + beta (|x_e - x_p|
// - b)^2 (over L^2) are minimal on the ray from x_p to x^o_e; a coincident pair held as an
// equality puts both points at one place; free points follow the others through their own
// minimisation (motion_refit_free_points.hpp); trees, bodies and directions are placed by their
// own classes.
#include "motion_refit_reduction.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "motion_refit_detail.hpp"
#include "union_find.hpp"

namespace animlod::detail {

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
constexpr double kIdentity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

// (P,) 1 for the points no held length, coincident pair, handed or flat group touches (not the root).
std::vector<uint8_t> free_points(const MotionRefitProblem& problem, bool eliminate) {
  std::vector<uint8_t> free(problem.point_count, eliminate ? 1 : 0);
  set_points_of(problem.length_pairs, problem.length_pair_count, 2, 0, free);
  set_points_of(problem.coincident_pairs, problem.coincident_pair_count, 2, 0, free);
  set_points_of(problem.handed_quads, problem.handed_quad_count, 4, 0, free);
  set_points_of(problem.flat_quads, problem.flat_quad_count, 4, 0, free);
  free[0] = 0;
  return free;
}

// (P,) points a rigid body may not hold: the coincident pairs' (substituted) and the trees'.
std::vector<uint8_t> body_exclusions(const MotionRefitProblem& problem, const PendantTrees& trees) {
  std::vector<uint8_t> excluded(problem.point_count, 0);
  set_points_of(problem.coincident_pairs, problem.coincident_pair_count, 2, 1, excluded);
  for (size_t k = 0; k < problem.point_count; ++k)
    if (trees.contains(k)) excluded[k] = 1;
  return excluded;
}

// out = a b (3 x 3, row-major).
void multiply(const double* a, const double* b, double* out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

}  // namespace

PointReduction::PointReduction(const MotionRefitProblem& problem, bool hard_constraints, bool eliminate,
                               bool rigid_bodies, bool bone_directions)
    : problem_(problem),
      hard_(hard_constraints),
      free_points_(problem, free_points(problem, eliminate)),
      trees_(problem, eliminate && hard_constraints),
      bodies_(problem, body_exclusions(problem, trees_), eliminate && hard_constraints && rigid_bodies) {
  const size_t p = problem.point_count;
  index_.assign(p, -1);
  substitute_.resize(p);
  std::iota(substitute_.begin(), substitute_.end(), 0);
  leaf_anchor_.assign(p, -1);
  leaf_length_.assign(p, 0.0);
  jacobians_.assign(p, Matrix3{1, 0, 0, 0, 1, 0, 0, 0, 1});
  const size_t pairs = problem.length_pair_count;
  kept_equalities_.assign(motion_refit_equality_count(problem), 1);
  for (size_t k = 0; k < pairs; ++k)
    if (trees_.inner_pairs()[k]) kept_equalities_[k] = 0;
  for (size_t r = 0; r < kept_equalities_.size(); ++r)
    if (bodies_.inner_equalities()[r]) kept_equalities_[r] = 0;
  kept_handed_.resize(problem.handed_quad_count);
  for (size_t k = 0; k < problem.handed_quad_count; ++k) kept_handed_[k] = bodies_.inner_handed()[k] ? 0 : 1;
  kept_handed_count_ = static_cast<size_t>(std::count(kept_handed_.begin(), kept_handed_.end(), 1));

  // Coincident pairs held exactly: every point of a tied set sits at its lowest index.
  if (eliminate && hard_constraints) {
    UnionFind tied(p);  // a set's root is its lowest index
    for (size_t k = 0; k < problem.coincident_pair_count; ++k) {
      tied.unite(problem.coincident_pairs[2 * k], problem.coincident_pairs[2 * k + 1]);
      std::fill_n(kept_equalities_.begin() + static_cast<long>(first_coincident_row(problem, k)), 3, uint8_t{0});
    }
    for (size_t k = 0; k < p; ++k) substitute_[k] = tied.find(static_cast<int32_t>(k));
  }

  // Leaves: in one term of E, a held length.
  if (eliminate) {
    std::vector<int> terms(p, 0);
    auto count = [&](const int32_t* rows, size_t n, size_t width) {
      for (size_t i = 0; i < n * width; ++i) ++terms[rows[i]];
    };
    count(problem.length_pairs, pairs, 2);
    count(problem.coincident_pairs, problem.coincident_pair_count, 2);
    count(problem.angle_triples, problem.angle_triple_count, 3);
    count(problem.handed_quads, problem.handed_quad_count, 4);
    count(problem.flat_quads, problem.flat_quad_count, 4);
    for (size_t k = 0; k < pairs; ++k) {
      for (int side = 0; side < 2; ++side) {
        const int32_t leaf = problem.length_pairs[2 * k + side];
        const int32_t anchor = problem.length_pairs[2 * k + 1 - side];
        // A tree's points and anchors are placed by the tree (the anchor is one of its leaves
        // only when nothing else holds either: then it stays a variable).
        if (leaf == 0 || terms[leaf] != 1 || leaf_anchor_[anchor] >= 0 || trees_.contains(leaf) ||
            trees_.contains(anchor))
          continue;
        leaf_anchor_[leaf] = anchor;
        leaf_length_[leaf] = problem.key_lengths[k];
        kept_equalities_[k] = 0;
        break;
      }
    }
  }
  // The points no reduction so far places: variables, unless they hang along a direction.
  std::vector<uint8_t> unplaced(p, 0);
  for (size_t k = 1; k < p; ++k)
    unplaced[k] = !free_points_.contains(k) && substitute_[k] == static_cast<int32_t>(k) && leaf_anchor_[k] < 0 &&
                  !trees_.contains(k) && bodies_.body_of(k) < 0;
  // Directions along the held lengths among those points (and the root).
  std::vector<uint8_t> candidate(unplaced), tied(p, 0);
  set_points_of(problem.coincident_pairs, problem.coincident_pair_count, 2, 1, tied);
  candidate[0] = 1;
  for (size_t k = 1; k < p; ++k) candidate[k] = candidate[k] && !tied[k];
  // A length that spans a run of frozen joints (a cluster of free points held at both of its
  // ends) stays an equality: as a direction, every step of SLSQP moved the runs below it and
  // their nested minima at once, and it crawled (the bench's tail at 10 joints: twice the
  // evaluations, E +9%).
  std::vector<uint8_t> hangable(kept_equalities_.begin(), kept_equalities_.begin() + static_cast<long>(pairs));
  std::vector<int32_t> held_by(p, -1);  // stamp: the last cluster that holds the point
  for (size_t c = 0; c < free_points_.cluster_count(); ++c) {
    for (int32_t point : free_points_.held_points(c)) held_by[point] = static_cast<int32_t>(c);
    for (size_t k = 0; k < pairs; ++k)
      if (held_by[problem.length_pairs[2 * k]] == static_cast<int32_t>(c) &&
          held_by[problem.length_pairs[2 * k + 1]] == static_cast<int32_t>(c))
        hangable[k] = 0;
  }
  directions_ = BoneDirections(problem, candidate, hangable, eliminate && hard_constraints && bone_directions);
  for (size_t i = 0; i < directions_.count(); ++i) kept_equalities_[directions_.pair(i)] = 0;

  free_index_.assign(p, -1);
  auto add_slot = [&](int32_t width) {
    slot_offset_.push_back(static_cast<int32_t>(variable_count_));
    slot_width_.push_back(width);
    variable_count_ += static_cast<size_t>(width);
    return static_cast<int32_t>(slot_width_.size() - 1);
  };
  for (size_t k = 1; k < p; ++k) {
    if (free_points_.contains(k)) free_index_[k] = static_cast<int32_t>(free_count_++);
    else if (unplaced[k] && directions_.direction_of(k) < 0) index_[k] = add_slot(3);
  }
  for (size_t b = 0; b < bodies_.count(); ++b) body_slot_.push_back(add_slot(bodies_.width(b)));
  for (size_t i = 0; i < directions_.count(); ++i) direction_slot_.push_back(add_slot(2));
  free_blocks_.resize(free_points_.cluster_count());
  for (size_t c = 0; c < free_blocks_.size(); ++c)
    for (int32_t point : free_points_.cluster_points(c))
      for (int a = 0; a < 3; ++a) free_blocks_[c].push_back(3 * free_index_[point] + a);
  kept_equality_count_ = static_cast<size_t>(std::count(kept_equalities_.begin(), kept_equalities_.end(), 1));
  coupled_.resize(p);
  auto couple = [&](const int32_t* rows, size_t n, size_t width) {  // every two points of a term
    for (const int32_t* row = rows; row < rows + n * width; row += width)
      for (size_t i = 0; i < width; ++i)
        for (size_t j = 0; j < width; ++j)
          if (row[i] > 0 && row[j] > 0) coupled_[row[i]].push_back(row[j]);
  };
  for (size_t k = 1; k < p; ++k) coupled_[k].push_back(static_cast<int32_t>(k));  // Ed
  couple(problem.length_pairs, pairs, 2);                                         // Es
  couple(problem.coincident_pairs, problem.coincident_pair_count, 2);
  couple(problem.angle_triples, problem.angle_triple_count, 3);  // Ea
  for (std::vector<int32_t>& row : coupled_) {
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  }
  build_links();
}

int32_t PointReduction::link_source(size_t k) const {
  if (k == 0 || free_index_[k] >= 0 || index_[k] >= 0) return -1;
  if (substitute_[k] != static_cast<int32_t>(k)) return substitute_[k];
  if (bodies_.body_of(k) >= 0) return bodies_.base(bodies_.body_of(k));
  if (directions_.direction_of(k) >= 0) return directions_.parent(static_cast<size_t>(directions_.direction_of(k)));
  if (trees_.contains(k)) return trees_.anchor(k);
  return leaf_anchor_[k];
}

const double* PointReduction::own_slot_derivative(size_t k) const {
  if (bodies_.body_of(k) >= 0) return bodies_.derivative(k);
  if (directions_.direction_of(k) >= 0) return directions_.derivative(k);
  return nullptr;
}

const double* PointReduction::source_derivative(size_t k) const {
  if (trees_.contains(k)) return trees_.derivative(k);
  if (leaf_anchor_[k] >= 0) return jacobians_[k].data();
  return kIdentity;
}

int32_t PointReduction::own_slot(size_t k) const {
  if (bodies_.body_of(k) >= 0) return body_slot_[bodies_.body_of(k)];
  if (directions_.direction_of(k) >= 0) return direction_slot_[directions_.direction_of(k)];
  return -1;
}

void PointReduction::build_links() {
  const size_t p = problem_.point_count;
  std::vector<std::vector<int32_t>> slots(p);
  std::vector<uint8_t> done(p, 0);
  // Depth first: a point's links are its source's, plus its own slot for a body's member or a
  // direction's point.
  auto visit = [&](auto& self, size_t k) -> void {
    if (done[k]) return;
    done[k] = 1;
    if (k == 0 || free_index_[k] >= 0) return;
    if (index_[k] >= 0) {
      slots[k] = {index_[k]};
    } else {
      const int32_t source = link_source(k);
      self(self, static_cast<size_t>(source));
      slots[k] = slots[source];
      if (own_slot(k) >= 0) slots[k].push_back(own_slot(k));
    }
    link_order_.push_back(static_cast<int32_t>(k));
  };
  for (size_t k = 0; k < p; ++k) visit(visit, k);
  link_offsets_.assign(p + 1, 0);
  for (size_t k = 0; k < p; ++k) link_offsets_[k + 1] = link_offsets_[k] + static_cast<int32_t>(slots[k].size());
  for (size_t k = 0; k < p; ++k) link_slots_.insert(link_slots_.end(), slots[k].begin(), slots[k].end());
  link_blocks_.assign(link_slots_.size(), Matrix3{});
}

void PointReduction::update_links() {
  for (int32_t k : link_order_) {
    Matrix3* out = link_blocks_.data() + link_offsets_[k];
    if (index_[k] >= 0) {
      std::copy(kIdentity, kIdentity + 9, out->begin());
      continue;
    }
    const int32_t source = link_source(k);
    const Matrix3* in = link_blocks_.data() + link_offsets_[source];
    const int32_t inherited = link_offsets_[source + 1] - link_offsets_[source];
    if (trees_.contains(k) || leaf_anchor_[k] >= 0) {  // d x_k / d x_anchor times the anchor's
      const double* j = source_derivative(k);
      for (int32_t i = 0; i < inherited; ++i) multiply(j, in[i].data(), out[i].data());
    } else {  // a substitute, a body's member or a direction's point moves with its source
      std::copy(in, in + inherited, out);
      if (const double* own = own_slot_derivative(k)) std::copy_n(own, 9, out[inherited].begin());
    }
  }
}

void PointReduction::set_start(const double* x, const double* original) {
  free_points_.set_start(x, original);
  bodies_.set_start(x);
  directions_.set_start(x, original);
}

void PointReduction::fill(const double* y, const double* original, double* x) {
  const size_t p = problem_.point_count;
  std::copy(original, original + 3, x);
  for (size_t k = 1; k < p; ++k)
    if (index_[k] >= 0) std::copy_n(y + slot_offset_[index_[k]], 3, x + 3 * k);
  for (size_t i = 0; i < directions_.count(); ++i) directions_.place(i, y + slot_offset_[direction_slot_[i]], x);
  for (size_t k = 1; k < p; ++k)
    if (substitute_[k] != static_cast<int32_t>(k)) std::copy(x + 3 * substitute_[k], x + 3 * substitute_[k] + 3, x + 3 * k);
  for (int32_t b : bodies_.order()) bodies_.place(static_cast<size_t>(b), y + slot_offset_[body_slot_[b]], x);
  trees_.place(x, original);
  const double alpha = problem_.distance_weight, beta = problem_.string_weight;
  const double pull = hard_ ? 0.0 : alpha / (alpha + beta);  // dr / dd
  for (size_t k = 1; k < p; ++k) {
    const int32_t anchor = leaf_anchor_[k];
    if (anchor < 0) continue;
    double u[3];
    double d = 0.0;
    for (int a = 0; a < 3; ++a) {
      u[a] = original[3 * k + a] - x[3 * anchor + a];
      d += u[a] * u[a];
    }
    d = std::sqrt(d);
    double tangent = 0.0;  // r / d, the part of J across the ray
    double r = leaf_length_[k];
    if (d > 1e-12 * problem_.length_scale) {
      for (double& v : u) v /= d;
      if (!hard_) r = (alpha * d + beta * leaf_length_[k]) / (alpha + beta);
      tangent = r / d;
    } else {  // the anchor on the leaf's original position: along the original bone
      double norm = 0.0;
      for (int a = 0; a < 3; ++a) {
        u[a] = original[3 * k + a] - original[3 * anchor + a];
        norm += u[a] * u[a];
      }
      norm = std::sqrt(norm);
      if (norm > 0.0) {
        for (double& v : u) v /= norm;
      } else {
        u[0] = 1.0, u[1] = 0.0, u[2] = 0.0;
      }
      if (!hard_) r = beta * leaf_length_[k] / (alpha + beta);
    }
    Matrix3& j = jacobians_[k];  // I - pull u u^T - (r / d) (I - u u^T)
    for (int a = 0; a < 3; ++a) {
      x[3 * k + a] = x[3 * anchor + a] + r * u[a];
      for (int b = 0; b < 3; ++b) {
        const double eye = a == b ? 1.0 : 0.0;
        j[3 * a + b] = eye - pull * u[a] * u[b] - tangent * (eye - u[a] * u[b]);
      }
    }
  }
  free_points_.minimise(x, original);
}

void PointReduction::gather(const double* x, double* y) const {
  for (size_t k = 1; k < problem_.point_count; ++k)
    if (index_[k] >= 0) std::copy_n(x + 3 * k, 3, y + slot_offset_[index_[k]]);
  for (int32_t slot : body_slot_) std::fill_n(y + slot_offset_[slot], slot_width_[slot], 0.0);
  for (size_t i = 0; i < directions_.count(); ++i) directions_.coordinates(i, x, y + slot_offset_[direction_slot_[i]]);
}

void PointReduction::reduce_rows(const double* rows, size_t count, double* out) const {
  const size_t p = problem_.point_count;
  std::fill(out, out + count * variable_count_, 0.0);
  // Reverse accumulation, children before their sources: a point's total derivative (its own
  // row plus what the points placed from it pass back) goes to its slot and, through
  // d x / d x_source, to its source. Linear in the points, where the links are as many as a
  // point's ancestors in a chain of directions.
  for (size_t r = 0; r < count; ++r) {
    totals_.assign(rows + r * 3 * p, rows + (r + 1) * 3 * p);
    double* o = out + r * variable_count_;
    for (auto it = link_order_.rbegin(); it != link_order_.rend(); ++it) {
      const auto k = static_cast<size_t>(*it);
      const double* g = totals_.data() + 3 * k;
      if (g[0] == 0.0 && g[1] == 0.0 && g[2] == 0.0) continue;  // most points of an equality's row
      if (index_[k] >= 0) {
        for (int b = 0; b < 3; ++b) o[slot_offset_[index_[k]] + b] += g[b];
        continue;
      }
      double* up = totals_.data() + 3 * link_source(k);
      const double* j = source_derivative(k);
      for (int b = 0; b < 3; ++b) up[b] += j[b] * g[0] + j[3 + b] * g[1] + j[6 + b] * g[2];  // J^T g
      if (const double* own = own_slot_derivative(k)) {
        const int32_t slot = own_slot(k);
        for (int b = 0; b < slot_width_[slot]; ++b)
          o[slot_offset_[slot] + b] += own[b] * g[0] + own[3 + b] * g[1] + own[6 + b] * g[2];
      }
    }
  }
}

void PointReduction::reduce_matrix(const double* full, double* out) {
  update_links();
  const size_t p = problem_.point_count;
  const size_t n = 3 * (p - 1);
  const auto nr = static_cast<Eigen::Index>(variable_count_);
  const auto nf = static_cast<Eigen::Index>(3 * free_count_);
  Eigen::Map<RowMatrix> reduced(out, nr, nr);
  RowMatrix coupling = RowMatrix::Zero(nr, nf);  // T^T M over the free points' columns
  RowMatrix free = RowMatrix::Zero(nf, nf);
  reduced.setZero();
  // Ja^T `block` (3 x 3, row-major; its first `columns` columns) added to the rows of every slot
  // of point a's links, in the matrix whose column block starts at `base` (rows `stride` apart).
  auto add = [&](size_t a, const double* block, double* base, Eigen::Index stride, int columns) {
    for (int32_t link = link_offsets_[a]; link < link_offsets_[a + 1]; ++link) {
      const double* ja = link_blocks_[link].data();
      const int32_t slot = link_slots_[link];
      double* row = base + slot_offset_[slot] * stride;
      for (int r = 0; r < slot_width_[slot]; ++r)
        for (int c = 0; c < columns; ++c) {
          double sum = 0.0;
          for (int i = 0; i < 3; ++i) sum += ja[3 * i + r] * block[3 * i + c];
          row[r * stride + c] += sum;
        }
    }
  };
  for (size_t a = 1; a < p; ++a) {
    const int32_t fa = free_index_[a];
    const bool linked_a = link_offsets_[a + 1] > link_offsets_[a];
    if (!linked_a && fa < 0) continue;
    for (const int32_t b : coupled_[a]) {  // the other blocks of row a are zero
      const int32_t fb = free_index_[b];
      if (link_offsets_[b + 1] == link_offsets_[b] && fb < 0) continue;
      const double* m_ab = full + 3 * (a - 1) * n + 3 * (b - 1);
      if (fa >= 0) {  // a free row: only the free-free block is needed (M is symmetric)
        if (fb >= 0)
          for (int i = 0; i < 3; ++i)
            for (int c = 0; c < 3; ++c) free(3 * fa + i, 3 * fb + c) = m_ab[i * n + c];
        continue;
      }
      if (fb >= 0) {  // Ja^T M_ab into the coupling with free point b
        double block[9];
        for (int i = 0; i < 3; ++i)
          for (int c = 0; c < 3; ++c) block[3 * i + c] = m_ab[i * n + c];
        add(a, block, &coupling(0, 3 * fb), nf, 3);
        continue;
      }
      for (int32_t link = link_offsets_[b]; link < link_offsets_[b + 1]; ++link) {
        const double* jb = link_blocks_[link].data();
        double block[9];  // M_ab Jb
        for (int i = 0; i < 3; ++i)
          for (int c = 0; c < 3; ++c) {
            double sum = 0.0;
            for (int k = 0; k < 3; ++k) sum += m_ab[i * n + k] * jb[3 * k + c];
            block[3 * i + c] = sum;
          }
        add(a, block, &reduced(0, slot_offset_[link_slots_[link]]), nr, slot_width_[link_slots_[link]]);
      }
    }
  }
  if (nf == 0 || nr == 0) return;
  // The free points follow the others (x_f = argmin E): E's Hessian over the reduced points is
  // the Schur complement A - B C^-1 B^T, C block diagonal by cluster (one small solve each).
  for (const std::vector<int32_t>& block : free_blocks_) {
    const Eigen::LLT<Eigen::MatrixXd> llt(free(block, block));
    if (llt.info() != Eigen::Success) continue;
    const Eigen::MatrixXd b = coupling(Eigen::all, block);
    reduced -= b * llt.solve(Eigen::MatrixXd(b.transpose()));
  }
}

}  // namespace animlod::detail
