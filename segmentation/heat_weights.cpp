#include "segmentation/heat_weights.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>

#include <Eigen/SparseCholesky>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "segmentation/detail/triangle_bvh.hpp"
#include "segmentation/voxel_occupancy.hpp"
#include "skinning/errors.hpp"

namespace skelcd::segmentation {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

template <class Body>
void for_range(std::int64_t n, bool parallel, Body&& body) {
  if (parallel && n > 256) {
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, n, 64),
                      [&](const tbb::blocked_range<std::int64_t>& r) {
                        for (auto i = r.begin(); i != r.end(); ++i) body(i);
                      });
  } else {
    for (std::int64_t i = 0; i < n; ++i) body(i);
  }
}

void validate_inputs(const skinning::Positions& V, const skinning::Triangles& F,
                     const std::vector<BoneSegment>& bones, const HeatWeightsOptions& options,
                     const char* where) {
  const std::string w(where);
  if (bones.empty()) throw InvalidInput(w + ": the skeleton has no bones");
  if (F.rows() == 0) throw InvalidInput(w + ": the mesh has no triangles");
  for (std::size_t b = 0; b < bones.size(); ++b) {
    if (!bones[b].head.allFinite() || !bones[b].tail.allFinite()) {
      throw InvalidInput(w + ": bone " + std::to_string(b) + " has a non-finite end point");
    }
  }
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    if (!V.row(i).allFinite()) {
      throw InvalidInput(w + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      if (F(f, c) < 0 || F(f, c) >= V.rows()) {
        throw InvalidInput(w + ": triangle " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, c)) + " outside [0, " + std::to_string(V.rows()) +
                           ")");
      }
    }
  }
  if (!(options.heat_constant > 0.0) || !std::isfinite(options.heat_constant)) {
    throw InvalidInput(w + ": heat_constant must be positive and finite");
  }
  if (!(options.tie_tolerance >= 0.0) || !(options.min_distance_fraction > 0.0)) {
    throw InvalidInput(w + ": tie_tolerance must be >= 0 and min_distance_fraction > 0");
  }
  if (options.grid_resolution < 1 || options.grid_resolution > 1024 ||
      options.smoothing_iterations < 0) {
    throw InvalidInput(w + ": grid_resolution must be in [1, 1024], smoothing_iterations >= 0");
  }
}

// The nearest visible bones of one vertex at `x`: bones sorted by distance, the first one whose
// nearest point `visible` accepts sets d; later ones within the tie tolerance that are visible
// share the source. With none visible, the nearest (and its ties) regardless.
template <class Visible>
void sources_of_vertex(const Eigen::Vector3d& x, const std::vector<BoneSegment>& bones,
                       double tie_tolerance, Visible&& visible, std::vector<double>& dist,
                       std::vector<std::int32_t>& order, std::vector<std::int32_t>& out,
                       double& d_out, bool& fell_back) {
  const auto nb = bones.size();
  for (std::size_t b = 0; b < nb; ++b) dist[b] = (bones[b].closest_point(x) - x).norm();
  // Most vertices see their nearest bone: try the nearest (and its ties) before sorting all.
  const double d0 = *std::min_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(nb));
  out.clear();
  for (std::size_t b = 0; b < nb; ++b) {
    if (dist[b] <= d0 * (1.0 + tie_tolerance) &&
        visible(x, bones[b].closest_point(x))) {
      out.push_back(static_cast<std::int32_t>(b));
    }
  }
  // When a bone at the minimum distance itself is visible, the answer is settled: it and the
  // visible bones within the tie tolerance (what the sorted search below would also find).
  bool nearest_visible = false;
  for (const auto b : out) nearest_visible |= dist[static_cast<std::size_t>(b)] == d0;
  if (nearest_visible) {
    fell_back = false;
    d_out = d0;
    return;
  }
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    return dist[ua] < dist[ub] || (dist[ua] == dist[ub] && a < b);
  });
  out.clear();
  std::optional<double> nearest;
  for (const auto b : order) {
    const double d = dist[static_cast<std::size_t>(b)];
    if (nearest && d > *nearest * (1.0 + tie_tolerance)) break;
    if (visible(x, bones[static_cast<std::size_t>(b)].closest_point(x))) {
      if (!nearest) nearest = d;
      out.push_back(b);
    }
  }
  fell_back = !nearest;
  if (fell_back) {
    for (const auto b : order) {
      if (dist[static_cast<std::size_t>(b)] > d0 * (1.0 + tie_tolerance)) break;
      out.push_back(b);
    }
    nearest = d0;
  }
  std::sort(out.begin(), out.end());
  d_out = *nearest;
}

}  // namespace

HeatSources nearest_visible_bones(const skinning::Positions& V, const skinning::Triangles& F,
                                  const std::vector<BoneSegment>& bones,
                                  const HeatWeightsOptions& options, HeatWeightsStats* stats) {
  validate_inputs(V, F, bones, options, "nearest_visible_bones");
  const auto start = Clock::now();
  const auto nv = static_cast<std::int64_t>(V.rows());

  // Where distances are measured from and how visibility is decided.
  std::optional<skinning::Positions> smoothed;
  std::optional<VoxelOccupancy> occupancy;
  std::optional<detail::TriangleBvh> bvh;
  if (options.distance == DistanceMode::coarse) {
    smoothed = taubin_smooth(V, F, options.smoothing_iterations);
    occupancy.emplace(*smoothed, F, options.grid_resolution);
  } else {
    bvh.emplace(V, F);
  }
  const skinning::Positions& X = smoothed ? *smoothed : V;

  // Per vertex, independent: one list of source bones each, gathered into CSR afterwards.
  std::vector<std::vector<std::int32_t>> per_vertex(static_cast<std::size_t>(nv));
  Eigen::VectorXd distance(nv);
  std::vector<char> fell_back(static_cast<std::size_t>(nv), 0);
  const auto nb = bones.size();
  const auto body = [&](std::int64_t i) {
    thread_local std::vector<double> dist;
    thread_local std::vector<std::int32_t> order;
    dist.resize(nb);
    order.resize(nb);
    const Eigen::Vector3d x = X.row(i).transpose();
    const auto vid = static_cast<std::int32_t>(i);
    double d = 0.0;
    bool fb = false;
    auto& out = per_vertex[static_cast<std::size_t>(i)];
    if (occupancy) {
      sources_of_vertex(
          x, bones, options.tie_tolerance,
          [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
            return occupancy->segment_inside(a, b);
          },
          dist, order, out, d, fb);
    } else {
      sources_of_vertex(
          x, bones, options.tie_tolerance,
          [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
            return !bvh->segment_hits(a, b, vid);
          },
          dist, order, out, d, fb);
    }
    distance[i] = d;
    fell_back[static_cast<std::size_t>(i)] = fb ? 1 : 0;
  };
  for_range(nv, options.parallel, body);

  HeatSources out;
  out.distance = std::move(distance);
  out.offsets.resize(static_cast<std::size_t>(nv) + 1, 0);
  for (std::int64_t i = 0; i < nv; ++i) {
    const auto& list = per_vertex[static_cast<std::size_t>(i)];
    out.offsets[static_cast<std::size_t>(i) + 1] =
        out.offsets[static_cast<std::size_t>(i)] + static_cast<std::int32_t>(list.size());
    out.bones.insert(out.bones.end(), list.begin(), list.end());
    out.fallback_vertices += fell_back[static_cast<std::size_t>(i)];
  }
  if (stats) {
    stats->fallback_vertices = out.fallback_vertices;
    if (occupancy) {
      stats->cell_size = occupancy->cell_size();
      stats->grid_dims = occupancy->dims();
    }
    stats->distance_s = seconds_since(start);
  }
  return out;
}

struct HeatWeightsSolver::Impl {
  std::int32_t num_vertices = 0;
  std::int32_t num_bones = 0;
  HeatSources sources;
  CotangentLaplacian laplacian;
  Eigen::VectorXd source_weight;        // #W: M_ii H_ii (1 for an isolated vertex)
  std::vector<char> isolated;           // #W
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  HeatWeightsStats stats;
  bool parallel = true;
};

HeatWeightsSolver::HeatWeightsSolver(const skinning::Positions& V, const skinning::Triangles& F,
                                     std::vector<BoneSegment> bones,
                                     const HeatWeightsOptions& options)
    : impl_(std::make_unique<Impl>()) {
  validate_inputs(V, F, bones, options, "HeatWeightsSolver");
  auto& m = *impl_;
  m.num_vertices = static_cast<std::int32_t>(V.rows());
  m.num_bones = static_cast<std::int32_t>(bones.size());
  m.parallel = options.parallel;
  m.stats.vertices = V.rows();
  m.stats.bones = m.num_bones;

  // 1. Heat sources: distance to, and identity of, the nearest visible bone.
  m.sources = nearest_visible_bones(V, F, bones, options, &m.stats);

  // 2. Assemble M(−Δ + H) = −L + M H, symmetric positive definite on every vertex that a
  //    non-degenerate triangle uses; an isolated vertex gets the identity row (w_i = p_i).
  const auto start = Clock::now();
  m.laplacian = cotangent_laplacian(V, F);
  m.stats.degenerate_triangles = static_cast<std::int64_t>(m.laplacian.degenerate_triangles.size());
  Eigen::Vector3d lo = V.colwise().minCoeff().transpose();
  Eigen::Vector3d hi = V.colwise().maxCoeff().transpose();
  const double diagonal = (hi - lo).norm();
  const double min_distance =
      diagonal > 0.0 ? options.min_distance_fraction * diagonal : options.min_distance_fraction;
  m.source_weight.resize(m.num_vertices);
  m.isolated.assign(static_cast<std::size_t>(m.num_vertices), 0);
  Eigen::SparseMatrix<double> K = -m.laplacian.stiffness;
  Eigen::VectorXd diagonal_add(m.num_vertices);
  for (std::int32_t i = 0; i < m.num_vertices; ++i) {
    if (m.laplacian.mass[i] > 0.0) {
      const double d = std::max(m.sources.distance[i], min_distance);
      m.source_weight[i] = m.laplacian.mass[i] * options.heat_constant / (d * d);
      diagonal_add[i] = m.source_weight[i];
    } else {
      m.isolated[static_cast<std::size_t>(i)] = 1;
      ++m.stats.isolated_vertices;
      m.source_weight[i] = 1.0;
      diagonal_add[i] = 1.0;
    }
  }
  Eigen::SparseMatrix<double> D(m.num_vertices, m.num_vertices);
  D.reserve(Eigen::VectorXi::Constant(m.num_vertices, 1));
  for (std::int32_t i = 0; i < m.num_vertices; ++i) D.insert(i, i) = diagonal_add[i];
  K += D;
  K.makeCompressed();
  m.ldlt.compute(K);
  if (m.ldlt.info() != Eigen::Success) {
    throw InvalidInput("HeatWeightsSolver: factorising the heat system failed (" +
                       std::to_string(m.num_vertices) + " vertices)");
  }
  m.stats.factorize_s = seconds_since(start);
}

HeatWeightsSolver::~HeatWeightsSolver() = default;

std::int32_t HeatWeightsSolver::num_bones() const { return impl_->num_bones; }
const HeatSources& HeatWeightsSolver::sources() const { return impl_->sources; }
const CotangentLaplacian& HeatWeightsSolver::laplacian() const { return impl_->laplacian; }

Eigen::VectorXd HeatWeightsSolver::solve(std::int32_t bone) const {
  const auto& m = *impl_;
  assert(bone >= 0 && bone < m.num_bones);
  // Right-hand side M H p_j: p_j(i) = 1/k when bone j is one of the k sources of vertex i.
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m.num_vertices);
  for (std::int32_t i = 0; i < m.num_vertices; ++i) {
    const auto begin = m.sources.offsets[static_cast<std::size_t>(i)];
    const auto end = m.sources.offsets[static_cast<std::size_t>(i) + 1];
    for (auto k = begin; k < end; ++k) {
      if (m.sources.bones[static_cast<std::size_t>(k)] == bone) {
        rhs[i] = m.source_weight[i] / static_cast<double>(end - begin);
      }
    }
  }
  return m.ldlt.solve(rhs);
}

HeatWeights HeatWeightsSolver::solve_all() const {
  const auto& m = *impl_;
  const auto start = Clock::now();
  HeatWeights out;
  out.stats = m.stats;
  out.weights.resize(m.num_vertices, m.num_bones);
  for_range(m.num_bones, m.parallel && m.num_vertices > 2000,
            [&](std::int64_t j) { out.weights.col(j) = solve(static_cast<std::int32_t>(j)); });

  // Clamp the negatives that obtuse cotangents allow, then normalise each row to sum 1.
  for (std::int32_t i = 0; i < m.num_vertices; ++i) {
    auto row = out.weights.row(i);
    for (std::int32_t j = 0; j < m.num_bones; ++j) {
      if (row[j] < 0.0) {
        out.stats.most_negative_weight = std::min(out.stats.most_negative_weight, row[j]);
        ++out.stats.clamped_weights;
        row[j] = 0.0;
      }
    }
    const double sum = row.sum();
    if (sum > 0.0 && std::isfinite(sum)) {
      row /= sum;
    } else {
      // Nothing left (cannot happen for an exact solve): the heat source itself.
      row.setZero();
      const auto begin = m.sources.offsets[static_cast<std::size_t>(i)];
      const auto end = m.sources.offsets[static_cast<std::size_t>(i) + 1];
      for (auto k = begin; k < end; ++k) {
        row[m.sources.bones[static_cast<std::size_t>(k)]] = 1.0 / static_cast<double>(end - begin);
      }
    }
  }
  out.stats.solve_s = seconds_since(start);
  return out;
}

}  // namespace skelcd::segmentation
