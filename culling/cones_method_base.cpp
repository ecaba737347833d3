#include "culling/cones_method_base.hpp"

#include <algorithm>
#include <cassert>
#include <string>

#include "culling/hierarchy_cache.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling::detail {
namespace {

/// The cone methods' hierarchy: their traversal (collide) reads the binary nodes' volumes, kept as
/// floats rounded outwards (half the bytes); its leaves test the triangles' exact volumes.
BvhOptions cone_bvh(const MethodOptions& options) {
  BvhOptions bvh = options.bvh;
  bvh.node_volumes = true;
  bvh.float_node_volumes = true;
  bvh.split = BvhSplit::median;  // the hierarchy the cone tests and paper 000's figures assume
  return bvh;
}

inline std::size_t sz(std::int32_t i) { return static_cast<std::size_t>(i); }

/// Welded rest positions (row w = rest position of representative_vertex[w]): the hierarchy is
/// split at rest, like the `bvh` method's.
skinning::Positions welded_rest(const skinning::Mesh& mesh, const skinning::Topology& topology) {
  skinning::Positions rest(topology.num_welded_vertices(), 3);
  for (std::int32_t w = 0; w < topology.num_welded_vertices(); ++w) {
    const std::int32_t v = topology.representative_vertex[sz(w)];
    if (v < 0 || v >= mesh.rest_positions.rows()) {
      throw InvalidInput(
          "culling::make_method: representative_vertex[" + std::to_string(w) +
          "] = " + std::to_string(v) + " is not a mesh vertex");
    }
    rest.row(w) = mesh.rest_positions.row(v);
  }
  return rest;
}

}  // namespace

ConeMethodBase::ConeMethodBase(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    Descent descent,
    bool needs_contours,
    const std::vector<std::int32_t>* subset,
    std::shared_ptr<const FeatureTopology> features)
    : MethodBase(name, mesh, topology, options, std::move(features)),
      bvh_(build_hierarchy<3>(
          options.hierarchies.get(),
          topology_.welded_triangles(),
          welded_rest(mesh, topology),
          subset,
          cone_bvh(options))),
      descent_(descent),
      // The cone theorems say "no intersection", not "no pair within a distance": with a contact
      // distance the method culls nothing and equals `bvh` (docs/dual-cone.md).
      cull_enabled_(options.min_separation == 0.0),
      needs_contours_(needs_contours),
      blocks_(
          options.block_pairs,
          block_reserve(options.block_pairs, bvh_.leaf_size(), topology_.num_triangles())) {
  const auto num_faces = static_cast<std::size_t>(topology_.num_triangles());
  bounds_.vertices.reserve(static_cast<std::size_t>(topology_.num_vertices()));
  bounds_.triangles.reserve(num_faces);
  const auto depth = static_cast<std::size_t>(bvh_.depth());
  self_stack_.reserve(4 * depth + 8);
  pair_stack_.reserve(2 * depth + 8);
}

void ConeMethodBase::ensure_contours() const {
  if (!needs_contours_ || contours_built_) return;
  contours_ = NodeContours(bvh_, topology_);
  contours_built_ = true;
}

bool ConeMethodBase::node_culled_without_contours(std::int32_t n, const Interval& interval) {
  if (!needs_contours_) return node_culled(n, interval);
  Eigen::Vector3d axis;
  return contour_tested(bvh_, n) && normal_test(n, axis);
}

void ConeMethodBase::dcd(const Instant& at, FrameResult& out) {
  const skinning::Positions& x = at.x;
  check_positions(x, "detect_dcd", "x");
  ensure_contours();
  stats_ = {};
  stats_.culling_disabled = !cull_enabled_;
  const auto t0 = Clock::now();
  const Interval interval = refit_instant(x);
  const auto t1 = Clock::now();
  // Cone-culled self traversal → triangle pairs → the DCD rules → tests, in blocks of
  // block_pairs pairs (bounded memory), the vertex fans certified once for the instant.
  blocks_.start_dcd(topology_, x, tests_, out);
  traverse(interval, out.counters.bv_tests);
  blocks_.finish();
  const auto t2 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
  out.times.elementary_us += blocks_.test_us();
}

void ConeMethodBase::refit_static(const skinning::Positions& x) {
  check_positions(x, "detect_dcd", "x");
  static_vertex_bounds<3>(x, bounds_.vertices);
  bounds_.derive(topology_, /*with_edges=*/false);
  bvh_.refit_wide(bounds_.triangles);
}

void ConeMethodBase::refit_swept(const skinning::Positions& x_t0, const skinning::Positions& x_t1) {
  check_positions(x_t0, "detect_ccd", "x_t0");
  check_positions(x_t1, "detect_ccd", "x_t1");
  swept_vertex_bounds<3>(x_t0, x_t1, 0.5 * options_.min_separation, bounds_.vertices);
  bounds_.derive(topology_, /*with_edges=*/false);
  bvh_.refit_wide(bounds_.triangles);
}

ConeMethodBase::Interval ConeMethodBase::refit_instant(const skinning::Positions& x) {
  // Static volumes, the hierarchy, the normal cones of the instant.
  static_vertex_bounds<3>(x, bounds_.vertices);
  bounds_.derive(topology_, /*with_edges=*/false);
  bvh_.refit(bounds_.triangles);
  const Interval interval{&x, &x, false};
  if (cull_enabled_) {
    cones_.refit(bvh_, topology_, x);
    refit_extra(interval);
  }
  return interval;
}

std::int64_t ConeMethodBase::count_dcd_pairs(const skinning::Positions& x, std::int64_t cap) {
  check_positions(x, "detect_dcd", "x");
  ensure_contours();
  return count_pairs(x, cap, false);
}

std::int64_t ConeMethodBase::count_dcd_pairs_at_least(
    const skinning::Positions& x, std::int64_t cap) {
  check_positions(x, "detect_dcd", "x");
  return count_pairs(x, cap, true);
}

std::int64_t ConeMethodBase::count_pairs(
    const skinning::Positions& x, std::int64_t cap, bool without_contours) {
  stats_ = {};
  stats_.culling_disabled = !cull_enabled_;
  const Interval interval = refit_instant(x);
  blocks_.pairs().clear();
  counting_ = true;
  without_contours_ = without_contours;
  counted_ = 0;
  count_cap_ = cap;
  std::int64_t bv_tests = 0;
  traverse(interval, bv_tests);
  pair_added();
  counting_ = false;
  without_contours_ = false;
  return counted_;
}

void ConeMethodBase::ccd(const culling::Interval& query, FrameResult& out) {
  const skinning::Positions& x_t0 = query.x_t0;
  const skinning::Positions& x_t1 = query.x_t1;
  check_positions(x_t0, "detect_ccd", "x_t0");
  check_positions(x_t1, "detect_ccd", "x_t1");
  ensure_contours();
  stats_ = {};
  stats_.culling_disabled = !cull_enabled_;
  const auto t0 = Clock::now();
  // Refit: swept volumes, the hierarchy, the continuous normal cones of the interval.
  // No edge volumes: the feature stage forms them from the vertices' (bounded memory).
  swept_vertex_bounds<3>(x_t0, x_t1, 0.5 * options_.min_separation, bounds_.vertices);
  bounds_.derive(topology_, /*with_edges=*/false);
  bvh_.refit(bounds_.triangles);
  const Interval interval{&x_t0, &x_t1, true};
  if (cull_enabled_) {
    cones_.refit(bvh_, topology_, x_t0, x_t1);
    refit_extra(interval);
  }
  const auto t1 = Clock::now();
  // Cone-culled self traversal → triangle pairs → de-duplicated feature pairs → tests, in blocks
  // of block_pairs pairs (bounded memory). A culled node's triangle pairs produce only feature
  // pairs inside a surface proven free of contact.
  blocks_.start_ccd(topology_, bounds_, x_t0, x_t1, tests_, options_.accuracy, ccd_options_, out);
  traverse(interval, out.counters.bv_tests);
  blocks_.finish();
  const auto t2 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
  out.times.elementary_us += blocks_.test_us();
}

bool ConeMethodBase::normal_test(std::int32_t n, Eigen::Vector3d& axis) {
  const DirectionCone snc = cones_.node_cone(bvh_, n);
  if (snc.in_open_half_space()) {
    axis = snc.axis;
    return true;
  }
  // Cones merged level by level grow looser than the normals they bound; a node that fails by
  // its cone may still pass triangle by triangle (early exit on the first normal that fails).
  axis = cones_.mean_normal(bvh_, n);
  if (!cones_.normals_in_half_space(bvh_, n, axis)) return false;
  ++stats_.normal_direct_passes;
  return true;
}

void ConeMethodBase::traverse(const Interval& interval, std::int64_t& bv_tests) {
  if (bvh_.empty()) return;
  const auto nodes = bvh_.nodes();
  self_stack_.clear();
  self_stack_.push_back(0);
  while (!self_stack_.empty() && !counted_enough()) {
    const std::int32_t n = self_stack_.back();
    self_stack_.pop_back();
    const BvhNode& node = nodes[sz(n)];
    if (node.is_leaf()) {
      leaf_self(n, bv_tests);
      continue;
    }
    const std::int32_t l = n + 1;
    const std::int32_t r = node.right;
    const bool leaf_children = nodes[sz(l)].is_leaf() && nodes[sz(r)].is_leaf();
    // SelfCollide(N): the method's cone test first; a culled node's whole subtree is done.
    if (cull_enabled_ && (without_contours_ ? node_culled_without_contours(n, interval)
                                            : node_culled(n, interval))) {
      ++stats_.nodes_culled;
      continue;
    }
    if (descent_ == Descent::grandchildren && !leaf_children) {
      // Algorithm 3: the sub-surfaces' self-tests and the six pairs between them (every one of
      // the ten: skipping those whose test passed is not sound, docs/dual-cone.md).
      std::array<std::int32_t, 4> parts{};
      const int k = sub_surfaces(bvh_, n, parts);
      for (int p = k; p-- > 0;) self_stack_.push_back(parts[static_cast<std::size_t>(p)]);
      for (int p = 0; p < k; ++p) {
        for (int q = p + 1; q < k; ++q) {
          collide(parts[static_cast<std::size_t>(p)], parts[static_cast<std::size_t>(q)], bv_tests);
        }
      }
    } else {
      self_stack_.push_back(r);
      self_stack_.push_back(l);
      collide(l, r, bv_tests);
    }
  }
}

void ConeMethodBase::collide(std::int32_t a, std::int32_t b, std::int64_t& bv_tests) {
  ++stats_.subtree_pairs;
  const auto nodes = bvh_.nodes();
  const auto volumes = bvh_.float_node_bounds();
  const auto order = bvh_.triangle_order();
  const auto& tri = bounds_.triangles;
  const bool single = bvh_.leaf_size() == 1;
  pair_stack_.clear();
  pair_stack_.emplace_back(a, b);
  while (!pair_stack_.empty() && !counted_enough()) {
    const auto [x, y] = pair_stack_.back();
    pair_stack_.pop_back();
    ++bv_tests;
    if (!volumes[sz(x)].overlaps(volumes[sz(y)])) continue;
    const BvhNode& nx = nodes[sz(x)];
    const BvhNode& ny = nodes[sz(y)];
    if (nx.is_leaf() && ny.is_leaf()) {
      if (single) {  // one-triangle leaves: the float node test only pruned; now the exact one
        const std::int32_t ta = order[sz(nx.begin)];
        const std::int32_t tb = order[sz(ny.begin)];
        if (tri[sz(ta)].overlaps(tri[sz(tb)])) {
          blocks_.pairs().push_back({std::min(ta, tb), std::max(ta, tb)});
          pair_added();
        }
        continue;
      }
      for (std::int32_t i = nx.begin; i < nx.end; ++i) {
        const std::int32_t ta = order[sz(i)];
        for (std::int32_t j = ny.begin; j < ny.end; ++j) {
          const std::int32_t tb = order[sz(j)];
          ++bv_tests;
          if (tri[sz(ta)].overlaps(tri[sz(tb)])) {
            blocks_.pairs().push_back({std::min(ta, tb), std::max(ta, tb)});
          }
        }
      }
      pair_added();
      continue;
    }
    // Split the node with more triangles (a leaf never).
    assert(pair_stack_.size() + 2 <= pair_stack_.capacity());
    if (ny.is_leaf() || (!nx.is_leaf() && nx.size() >= ny.size())) {
      pair_stack_.emplace_back(nx.right, y);
      pair_stack_.emplace_back(x + 1, y);
    } else {
      pair_stack_.emplace_back(x, ny.right);
      pair_stack_.emplace_back(x, y + 1);
    }
  }
}

void ConeMethodBase::leaf_self(std::int32_t leaf, std::int64_t& bv_tests) {
  const BvhNode& node = bvh_.nodes()[sz(leaf)];
  const auto order = bvh_.triangle_order();
  const auto& tri = bounds_.triangles;
  for (std::int32_t i = node.begin; i < node.end; ++i) {
    const std::int32_t ta = order[sz(i)];
    for (std::int32_t j = i + 1; j < node.end; ++j) {
      const std::int32_t tb = order[sz(j)];
      ++bv_tests;
      if (tri[sz(ta)].overlaps(tri[sz(tb)]))
        blocks_.pairs().push_back({std::min(ta, tb), std::max(ta, tb)});
    }
  }
  pair_added();
}

}  // namespace skelcd::culling::detail
