// Conservative inclusion-based CCD solver (docs/ccd.md, "The conservative solver").
//  - For fixed t, F(t, u, v) is affine in (u, v); for fixed (u, v) it is affine in t. Over a slab
//    [t0, t1] x Q (Q a convex polygon of (u, v)), every linear functional w . F therefore reaches its
//    extremes at {t0, t1} x vertices(Q). Q is the (u, v) box, cut by u + v <= 1 for vertex-face.
//  - Each vertex value is computed with a proven error bound err_k per component, scaled by the
//    magnitude of the difference vectors (docs/ccd.md, "Corner evaluation").
//  - A box is dropped only if, for some direction w, w . F > s |w|_1 + err_w at every vertex (or
//    < -(...) at every vertex): then |F| > s on the whole box. Directions tried: the three axes,
//    then directions taken from the geometry at the box's middle time (plane normal, in-plane edge
//    normals, ...) — any w is sound; good ones drop boxes along near-degenerate contact curves.
//  - Boxes are explored best first by their start time t0 (ties: the newest first, i.e. depth first
//    within a time). When a box is accepted as a (possible) contact, every box still open starts
//    at or after it, and every dropped box held no point within min_separation: toi_lower = its t0
//    is at or before the first contact, and the search stops there.

#include "ccd/detail/inclusion_solver.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "ccd/detail/float_bounds.hpp"

namespace skelcd::ccd::detail {
namespace {

using Eigen::Vector3d;

// Boxes narrower than this are not split further along that dimension (2^-60 is below the
// resolution of any parameter the geometry can distinguish in double).
constexpr double kMinWidth = 0x1p-60;
// Open boxes (a binary heap on the stack). If it ever fills up, the box in hand is reported as a
// possible contact — the safe answer — since it starts earliest of all open boxes.
constexpr int kHeapCapacity = 1024;
// At most 5 vertices for a box cut by u + v <= 1.
constexpr int kMaxVertices = 5;
constexpr int kMaxDirections = 10;

struct Box {
  double t0, t1, u0, u1, v0, v1;
  std::int64_t order;  // creation count: among equal t0, the newest is explored first
};

// Min-heap on (t0, newest first).
bool later(const Box& a, const Box& b) { return a.t0 > b.t0 || (a.t0 == b.t0 && a.order < b.order); }

class BoxHeap {
 public:
  [[nodiscard]] bool empty() const { return size_ == 0; }
  [[nodiscard]] bool full() const { return size_ + 2 > kHeapCapacity; }
  void push(const Box& b) {
    assert(size_ < kHeapCapacity);
    boxes_[static_cast<std::size_t>(size_++)] = b;
    std::push_heap(boxes_.begin(), boxes_.begin() + size_, later);
  }
  Box pop() {
    std::pop_heap(boxes_.begin(), boxes_.begin() + size_, later);
    return boxes_[static_cast<std::size_t>(--size_)];
  }

 private:
  std::array<Box, kHeapCapacity> boxes_;
  int size_ = 0;
};

double round_up_after(double x) { return std::nextafter(x, std::numeric_limits<double>::infinity()); }

// Vertices of Q = box (n (u, v) box) cut by u + v <= 1 (vertex-face) — a superset of the true Q:
// cut points are rounded toward larger u or v, i.e. beyond the cut line.
int polygon(const Box& b, bool triangle_domain, std::array<double, kMaxVertices>& us,
            std::array<double, kMaxVertices>& vs) {
  if (!triangle_domain || b.u1 + b.v1 <= 1.0) {
    us = {b.u0, b.u1, b.u1, b.u0, 0.0};
    vs = {b.v0, b.v0, b.v1, b.v1, 0.0};
    return 4;
  }
  int n = 0;
  us[static_cast<std::size_t>(n)] = b.u0;
  vs[static_cast<std::size_t>(n++)] = b.v0;
  if (b.u1 + b.v0 <= 1.0) {
    us[static_cast<std::size_t>(n)] = b.u1;
    vs[static_cast<std::size_t>(n++)] = b.v0;
    us[static_cast<std::size_t>(n)] = b.u1;
    vs[static_cast<std::size_t>(n++)] = std::min(round_up_after(1.0 - b.u1), b.v1);
  } else {
    us[static_cast<std::size_t>(n)] = std::min(round_up_after(1.0 - b.v0), b.u1);
    vs[static_cast<std::size_t>(n++)] = b.v0;
  }
  if (b.u0 + b.v1 <= 1.0) {
    us[static_cast<std::size_t>(n)] = std::min(round_up_after(1.0 - b.v1), b.u1);
    vs[static_cast<std::size_t>(n++)] = b.v1;
    us[static_cast<std::size_t>(n)] = b.u0;
    vs[static_cast<std::size_t>(n++)] = b.v1;
  } else {
    us[static_cast<std::size_t>(n)] = b.u0;
    vs[static_cast<std::size_t>(n++)] = std::min(round_up_after(1.0 - b.u0), b.v1);
  }
  return n;
}

bool splittable(double lo, double hi) {
  if (!(hi - lo > kMinWidth)) return false;
  const double mid = 0.5 * (lo + hi);
  return lo < mid && mid < hi;
}

}  // namespace

InclusionResult solve_inclusion(const InclusionProblem& p, const CcdOptions& options) {
  InclusionResult result;
  const double s = options.min_separation;

  // Error bound per component (docs/ccd.md, "Corner evaluation"): a computed vertex value differs
  // from the exact one by at most 8 eps S_k (rounding lemma, k = 7), S_k >= |D| + |E| + |G| at
  // either end, plus underflow of the 4 products by factors in [0, 1].
  Vector3d err, sum, dir_err;
  double extent = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double s0 = (std::abs(p.d_t0[k]) + std::abs(p.e_t0[k])) + std::abs(p.g_t0[k]);
    const double s1 = (std::abs(p.d_t1[k]) + std::abs(p.e_t1[k])) + std::abs(p.g_t1[k]);
    sum[k] = std::max(s0, s1);
    if (!std::isfinite(sum[k]) || !std::isfinite(s)) {
      // Non-finite input: nothing can be proven; the safe answer.
      result = {true, 0.0, 1.0, CcdStatus::contact, 0};
      return result;
    }
    err[k] = add_up(rounding_bound(7, sum[k]), 8 * kUnderflowUnit);
    // For w . F: sum_k |w_k| (err_k + 4 eps (S_k + err_k)) bounds the error (the dot product adds
    // at most 3 roundings to terms bounded by |w_k| (S_k + err_k)).
    dir_err[k] = add_up(err[k], 4 * kEps * add_up(sum[k], err[k]));
    extent = std::max({extent, std::abs(p.d_t0[k]), std::abs(p.e_t0[k]), std::abs(p.g_t0[k]),
                       std::abs(p.d_t1[k]), std::abs(p.e_t1[k]), std::abs(p.g_t1[k])});
  }
  Vector3d exclude, accept;
  const double tolerance = options.relative_distance_tolerance * extent;
  for (int k = 0; k < 3; ++k) {
    exclude[k] = add_up(s, err[k]);
    accept[k] = exclude[k] + tolerance;
  }
  // Speed of the (u, v) parameters' effect, for choosing where to split: |dF/du| <= max |E|.
  const double e_rate = std::max(p.e_t0.cwiseAbs().maxCoeff(), p.e_t1.cwiseAbs().maxCoeff());
  const double g_rate = std::max(p.g_t0.cwiseAbs().maxCoeff(), p.g_t1.cwiseAbs().maxCoeff());

  BoxHeap heap;
  std::int64_t created = 0;
  heap.push({p.t_begin, 1.0, 0.0, 1.0, 0.0, 1.0, created++});
  std::array<double, kMaxVertices> us{}, vs{};
  // Values of F at the slab's vertices: column a * kMaxVertices + i is vertex i at time t_a
  // (unused columns repeat vertex 0, which changes no minimum or maximum).
  Eigen::Matrix<double, 3, 2 * kMaxVertices> f;
  Eigen::Matrix<double, kMaxDirections, 3> w;
  const double inf = std::numeric_limits<double>::infinity();

  bool have_next = false;
  Box next{};
  while (have_next || !heap.empty()) {
    const Box b = have_next ? next : heap.pop();
    have_next = false;
    // Vertex-face: parameters beyond the triangle's hypotenuse (exact: rounding is monotone).
    if (p.triangle_domain && b.u0 + b.v0 > 1.0) continue;

    if (result.boxes >= options.max_iterations) {
      // Out of budget: the safe answer, from the earliest time still open (this box's).
      result.hit = true;
      result.toi_lower = b.t0;
      result.toi_upper = 1.0;
      result.status = CcdStatus::iteration_limit;
      return result;
    }
    ++result.boxes;

    // F at the slab's vertices, in the order the error analysis assumes:
    // F_t0/t1(u, v) = (D + u E) + v G, then F = (1 - t) F_t0 + t F_t1.
    const int n = polygon(b, p.triangle_domain, us, vs);
    const double om0 = 1.0 - b.t0;
    const double om1 = 1.0 - b.t1;
    for (int i = 0; i < kMaxVertices; ++i) {
      const auto ii = static_cast<std::size_t>(i < n ? i : 0);
      const double u = us[ii];
      const double v = vs[ii];
      for (int k = 0; k < 3; ++k) {
        const double f0 = (p.d_t0[k] + u * p.e_t0[k]) + v * p.g_t0[k];
        const double f1 = (p.d_t1[k] + u * p.e_t1[k]) + v * p.g_t1[k];
        f(k, i) = om0 * f0 + b.t0 * f1;
        f(k, kMaxVertices + i) = om1 * f0 + b.t1 * f1;
      }
    }
    const Vector3d lo = f.rowwise().minCoeff();
    const Vector3d hi = f.rowwise().maxCoeff();
    // Written so that NaN never excludes.
    bool excluded = false;
    bool within = true;
    for (int k = 0; k < 3; ++k) {
      if (lo[k] > exclude[k] || -hi[k] > exclude[k]) excluded = true;
      if (!(hi[k] <= accept[k] && -lo[k] <= accept[k])) within = false;
    }
    // Does some direction keep one t-face of the slab clear of zero (while the slab is not)? Then
    // the zeros sit at the other times, and splitting t is what makes progress (below).
    const auto face_clears = [&](const auto& face_lo, const auto& face_hi, const auto& bound) {
      return ((face_lo.array() > bound.array()) || ((-face_hi).array() > bound.array())).any();
    };
    bool face_clear = false;
    if (!excluded && !within) {
      const Vector3d lo0 = f.leftCols<kMaxVertices>().rowwise().minCoeff();
      const Vector3d hi0 = f.leftCols<kMaxVertices>().rowwise().maxCoeff();
      const Vector3d lo1 = f.rightCols<kMaxVertices>().rowwise().minCoeff();
      const Vector3d hi1 = f.rightCols<kMaxVertices>().rowwise().maxCoeff();
      face_clear = face_clears(lo0, hi0, exclude) || face_clears(lo1, hi1, exclude);
    }
    if (!excluded && !within) {
      // Directions from the geometry at the middle time (any direction is sound), scaled to
      // max-norm 1 so that nothing overflows.
      const double tm = 0.5 * (b.t0 + b.t1);
      const Vector3d d = (1 - tm) * p.d_t0 + tm * p.d_t1;
      const Vector3d e = (1 - tm) * p.e_t0 + tm * p.e_t1;
      const Vector3d g = (1 - tm) * p.g_t0 + tm * p.g_t1;
      const Vector3d normal = e.cross(g);
      w.row(0) = normal;                   // off the plane of the two parameter directions
      w.row(1) = normal.cross(e);          // in-plane, across the edge along e
      w.row(2) = normal.cross(g);          // in-plane, across the edge along g
      w.row(3) = normal.cross(e - g);      // in-plane, across the third edge (vertex-face)
      w.row(4) = d;                        // along the offset
      w.row(5) = e.cross(d.cross(e));      // across e toward the offset (parallel cases)
      w.row(6) = g.cross(d.cross(g));
      w.row(7) = e;                        // along e (collinear cases)
      w.row(8) = g;
      w.row(9) = f.rowwise().sum();        // toward the values themselves (near misses)
      // Scale each direction to max-norm about 1 (any scale is sound): w . F then cannot overflow
      // and its products underflow by at most one unit each.
      for (int j = 0; j < kMaxDirections; ++j) {
        const double m = w.row(j).cwiseAbs().maxCoeff();
        if (m > 0.0 && m < inf) {
          w.row(j) *= 1.0 / m;
        } else {
          w.row(j).setZero();  // unusable: its threshold below is 0 and "x > 0" at every vertex
        }                      // cannot hold for w = 0
      }
      // |w . F| > s |w|_2 + err_w implies |F| > s, err_w = sum_k |w_k| dir_err_k + 4 units of
      // underflow; |w|_2 rounded up (sqrt is correctly rounded), and only needed when s > 0.
      const Eigen::Matrix<double, kMaxDirections, 3> aw = w.cwiseAbs();
      Eigen::Matrix<double, kMaxDirections, 1> threshold =
          ((aw.col(0) * dir_err[0] + aw.col(1) * dir_err[1]) + aw.col(2) * dir_err[2]).array() + 4 * kUnderflowUnit;
      if (s > 0.0) {
        for (int j = 0; j < kMaxDirections; ++j) {
          threshold[j] += s * (std::sqrt(aw.row(j).squaredNorm() * kRoundUp) * kRoundUp);
        }
      }
      threshold *= kRoundUp * kRoundUp;
      const Eigen::Matrix<double, kMaxDirections, 2 * kMaxVertices> projected = w.lazyProduct(f);
      const auto wlo = projected.rowwise().minCoeff();
      const auto whi = projected.rowwise().maxCoeff();
      for (int j = 0; j < kMaxDirections; ++j) {
        if (wlo[j] > threshold[j] || -whi[j] > threshold[j]) excluded = true;
      }
      if (!excluded && !face_clear) {
        const auto p0 = projected.leftCols<kMaxVertices>();
        const auto p1 = projected.rightCols<kMaxVertices>();
        const Eigen::Matrix<double, kMaxDirections, 1> lo0 = p0.rowwise().minCoeff(), hi0 = p0.rowwise().maxCoeff();
        const Eigen::Matrix<double, kMaxDirections, 1> lo1 = p1.rowwise().minCoeff(), hi1 = p1.rowwise().maxCoeff();
        face_clear = face_clears(lo0, hi0, threshold) || face_clears(lo1, hi1, threshold);
      }
    }
    if (excluded) continue;

    const bool split_t = splittable(b.t0, b.t1);
    const bool split_u = splittable(b.u0, b.u1);
    const bool split_v = splittable(b.v0, b.v1);
    int dim = -1;  // 0 = t, 1 = u, 2 = v; -1 = accept the box
    if (within) {
      // Proven near-contact: narrow the time interval only.
      if (b.t1 - b.t0 > options.toi_tolerance && split_t) dim = 0;
    } else {
      // Split where F varies most (that is what keeps the box from being decided) — except that
      // when a t-face is clear, time is split first, down to the scale of the acceptance test:
      // otherwise a contact set that is a whole segment of (u, v) at one time (zero-area
      // triangles, parallel edges) multiplies boxes that all start at the same time.
      const double var_t =
          (f.rightCols<kMaxVertices>() - f.leftCols<kMaxVertices>()).cwiseAbs().maxCoeff();
      // Once F varies by less than the acceptance scale over the time range, splitting time cannot
      // help a box become acceptable, and it would move the rest of it behind every other box that
      // starts at the same time: split u or v instead.
      const bool t_matters = var_t > accept.maxCoeff();
      if (face_clear && split_t && t_matters) dim = 0;
      const double var[3] = {var_t, (b.u1 - b.u0) * e_rate, (b.v1 - b.v0) * g_rate};
      const bool can[3] = {split_t && (t_matters || !(split_u || split_v)), split_u, split_v};
      double best_var = -1.0;
      for (int dd = 0; dd < 3 && dim < 0; ++dd) {
        if (can[dd] && var[dd] > best_var) best_var = var[dd];
      }
      for (int dd = 0; dd < 3 && dim < 0; ++dd) {
        if (can[dd] && var[dd] == best_var) dim = dd;
      }
    }
    if (dim >= 0 && heap.full()) dim = -1;  // out of room: report this box (see kHeapCapacity)
    if (dim < 0) {
      // Every open box starts at or after this one: its start is a sound lower bound.
      result.hit = true;
      result.toi_lower = b.t0;
      result.toi_upper = b.t1;
      result.status = CcdStatus::contact;
      return result;
    }
    Box lo_half = b;
    Box hi_half = b;
    if (dim == 0) {
      const double mid = 0.5 * (b.t0 + b.t1);
      lo_half.t1 = mid;
      hi_half.t0 = mid;
    } else if (dim == 1) {
      const double mid = 0.5 * (b.u0 + b.u1);
      lo_half.u1 = mid;
      hi_half.u0 = mid;
    } else {
      const double mid = 0.5 * (b.v0 + b.v1);
      lo_half.v1 = mid;
      hi_half.v0 = mid;
    }
    // The lower half starts with b, before or with every open box, and is the newest: it is
    // next in the heap's order, so it skips the heap.
    hi_half.order = created++;
    lo_half.order = created++;
    heap.push(hi_half);
    next = lo_half;
    have_next = true;
  }
  return result;  // every box dropped: separated
}

}  // namespace skelcd::ccd::detail
