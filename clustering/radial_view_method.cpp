#include "clustering/radial_view_method.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <utility>

#include "ccd/orientation.hpp"
#include "culling/cluster_checks.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"

namespace skelcd::clustering {
namespace {

using Clock = std::chrono::steady_clock;
using culling::MaskedPairs;

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

double micros(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

bool same_positions(const skinning::Positions& a, const skinning::Positions& b) {
  return a.rows() == b.rows() && std::equal(a.data(), a.data() + a.size(), b.data());
}

/// True when triangles a and b, which share one vertex or one edge (shared: corner i of a is
/// corner shared[i] of b, else −1), are proven to meet nowhere beyond it by exact orientations:
/// - an edge: b's third corner off a's plane (b minus the edge lies strictly on one side);
/// - a vertex: b's other two corners strictly on one side of a's plane, or a's of b's plane.
/// False means "not proven": the full test decides.
bool apart_beyond_shared(
    const std::array<Eigen::Vector3d, 3>& a,
    const std::array<Eigen::Vector3d, 3>& b,
    const ccd::SharedCorners& shared) {
  std::array<bool, 3> b_shared{false, false, false};
  int count = 0;
  for (const auto j : shared) {
    if (j >= 0 && !b_shared[static_cast<std::size_t>(j)]) {
      b_shared[static_cast<std::size_t>(j)] = true;
      ++count;
    }
  }
  const auto side = [](const std::array<Eigen::Vector3d, 3>& t, const Eigen::Vector3d& p) {
    return ccd::orient3d(t[0], t[1], t[2], p);
  };
  if (count == 2) {
    for (std::size_t j = 0; j < 3; ++j) {
      if (!b_shared[j]) return side(a, b[j]) != 0;
    }
    return false;
  }
  if (count != 1) return false;
  // The two corners of b that are not shared, and the two of a.
  std::array<std::size_t, 2> bo{}, ao{};
  std::size_t nb = 0, na = 0;
  for (std::size_t j = 0; j < 3; ++j) {
    if (!b_shared[j] && nb < 2) bo[nb++] = j;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    if (shared[i] < 0 && na < 2) ao[na++] = i;
  }
  if (nb == 2) {
    const int s0 = side(a, b[bo[0]]);
    if (s0 != 0 && s0 == side(a, b[bo[1]])) return true;
  }
  if (na == 2) {
    const int s0 = side(b, a[ao[0]]);
    if (s0 != 0 && s0 == side(b, a[ao[1]])) return true;
  }
  return false;
}

}  // namespace

RadialViewMethod::RadialViewMethod(
    std::string name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    std::shared_ptr<const segmentation::Segmentation> segmentation,
    std::shared_ptr<const BonePoses> poses,
    std::int32_t num_bones,
    const culling::MethodOptions& method_options,
    const RadialViewOptions& options)
    : name_(std::move(name)),
      segmentation_(std::move(segmentation)),
      poses_(std::move(poses)),
      topology_(mesh, topology),
      clusters_(mesh, topology, *segmentation_, num_bones, method_options.bvh),
      method_options_(method_options),
      options_(options),
      tests_(culling::with_ccd_defaults(method_options.elementary)),
      // The bvh method checks the method options (min_separation, accuracy) as every method does.
      bvh_(culling::make_method("bvh", mesh, topology, method_options_)),
      builder_(clusters_, options.clusters),
      edge_face_offsets_(topology.edge_face_offsets),
      edge_faces_(topology.edge_faces),
      blocks_(
          method_options.block_pairs,
          culling::block_reserve(
              method_options.block_pairs,
              method_options.bvh.leaf_size,
              topology_.num_triangles())) {
  num_bones_ = num_bones;
  ccd_options_.min_separation = method_options.min_separation;
  const auto num_faces = at(topology_.num_triangles());
  const auto num_atomic = at(clusters_.num_atomic());
  const auto num_components = at(clusters_.num_components());
  // Everything an interval touches is sized here (the candidates' blocks by blocks_).
  bounds_.vertices.reserve(at(topology_.num_vertices()));
  bounds_.edges.reserve(at(topology_.num_edges()));
  bounds_.triangles.reserve(num_faces);
  cluster_bounds_.resize(num_atomic);
  triangle_mask_.assign(num_faces, culling::kMaskOther);
  node_masks_.resize(num_atomic);
  std::size_t deepest = 0;
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    node_masks_[at(a)].resize(clusters_.local_bvh(a).nodes().size());
    deepest = std::max(deepest, static_cast<std::size_t>(clusters_.local_bvh(a).depth()));
  }
  scratch_.reserve(std::max(
      4 * deepest + 4,
      4 * static_cast<std::size_t>(clusters_.global_bvh().depth()) + 4));
  vertex_label_.resize(at(topology_.num_vertices()));
  edge_label_.resize(at(topology_.num_edges()));
  status_.assign(num_components, Status::unknown);
  culled_.assign(num_components, 0);
  escalate_.assign(num_components, 0);
  carry_clean_.assign(num_components, 0);
  carry_contact_.assign(num_components, 0);
  dcd_clean_.assign(num_components, 0);
  dcd_pairs_.reserve(culling::block_reserve(
      method_options.block_pairs, method_options.bvh.leaf_size, topology_.num_triangles()));
}

void RadialViewMethod::check_positions(
    const skinning::Positions& x,
    const char* call,
    const char* which) const {
  if (x.rows() != topology_.num_vertices()) {
    throw InvalidInput(
        "clustering::" + name_ + "::" + call + ": " + which + " has " + std::to_string(x.rows()) +
        " rows, expected one per welded vertex (" + std::to_string(topology_.num_vertices()) +
        ")");
  }
}

void RadialViewMethod::record_dcd(
    const skinning::Positions& x,
    const culling::FrameResult& result) {
  dcd_x_ = x;
  std::fill(dcd_clean_.begin(), dcd_clean_.end(), 1);
  for (const auto& p : result.dcd_pairs) {
    const std::int32_t k = clusters_.component_of_triangle(p.a);
    if (k == clusters_.component_of_triangle(p.b)) dcd_clean_[at(k)] = 0;
  }
  has_dcd_ = true;
}

void RadialViewMethod::dcd(const culling::Instant& at, culling::FrameResult& out) {
  const skinning::Positions& x = at.x;
  check_positions(x, "detect_dcd", "x");
  bvh_->detect_dcd(x, out);
  record_dcd(x, out);
}

// --- preconditions at the interval's start ------------------------------------------------------

void RadialViewMethod::start_status(const skinning::Positions& x_t0, culling::FrameResult& out) {
  const std::int32_t num_components = clusters_.num_components();
  std::fill(status_.begin(), status_.end(), Status::unknown);
  const bool culling_possible = method_options_.min_separation == 0.0;
  if (!culling_possible) return;  // nothing is skipped: the start state does not matter
  if (!options_.guard) {
    for (std::int32_t k = 0; k < num_components; ++k) {
      if (clusters_.component_ok(k)) status_[at(k)] = Status::clean;
    }
    return;
  }
  // Known from the previous interval (its end is this start) or from a DCD at these positions.
  const bool carried = has_carry_ && same_positions(x_t0, carry_x_);
  const bool dcd_known = has_dcd_ && same_positions(x_t0, dcd_x_);
  bool any_unknown = false;
  for (std::int32_t k = 0; k < num_components; ++k) {
    if (!clusters_.component_ok(k)) continue;
    if (carried && carry_clean_[at(k)] != 0) {
      status_[at(k)] = Status::clean;
    } else if (dcd_known) {
      status_[at(k)] = dcd_clean_[at(k)] != 0 ? Status::clean : Status::dirty;
    } else if (carried && carry_contact_[at(k)] != 0) {
      // A self-contact in the previous interval: most likely still intersecting. Taking it as
      // dirty without a DCD pass is safe (nothing is skipped there); the first interval without
      // a self-contact runs the pass and may find it clean again.
      status_[at(k)] = Status::dirty;
      ++stats_.components_assumed_dirty;
    } else {
      any_unknown = true;
    }
  }
  if (!any_unknown) return;

  // A DCD pass over the unknown components: every pair of their triangles within one component
  // whose static boxes overlap, through the cluster hierarchies, then the exact triangle test.
  const auto start = Clock::now();
  const auto unknown = [&](std::int32_t k) { return status_[at(k)] == Status::unknown; };
  culling::static_vertex_bounds<3>(x_t0, static_bounds_.vertices);
  static_bounds_.derive(topology_, /*with_edges=*/false);
  const std::int32_t num_atomic = clusters_.num_atomic();
  for (std::int32_t a = 0; a < num_atomic; ++a) {
    auto& local = clusters_.local_bvh(a);
    const std::int32_t k = clusters_.component_of_atomic(a);
    if (local.empty() || k < 0 || !clusters_.component_ok(k) || !unknown(k)) {
      cluster_bounds_[at(a)] = culling::Aabb::empty();
      continue;
    }
    local.refit(static_bounds_.triangles);
    cluster_bounds_[at(a)] = local.node_bounds()[0];
  }
  auto& global = clusters_.global_bvh();
  global.refit(cluster_bounds_);
  std::int64_t bv_tests = 0;
  cluster_pairs_.clear();
  culling::self_traverse<3>(global, cluster_bounds_, scratch_, cluster_pairs_, bv_tests);
  for (std::int32_t k = 0; k < num_components; ++k) {
    if (unknown(k)) {
      status_[at(k)] = Status::clean;
      ++stats_.components_dcd;
    }
  }
  const auto dirty = [&](std::int32_t k) { return status_[at(k)] == Status::dirty; };

  // The exact triangle test, pair by pair: pairs without a shared vertex first (an intersecting one
  // settles its component at once), then adjacent pairs, most of which an exact orientation
  // proves apart beyond the shared vertex or edge without the full test.
  std::int64_t tt_tests = 0;
  double test_us = 0.0;
  const auto test_pairs = [&](bool adjacent) {
    const auto t0 = Clock::now();
    for (const auto& p : dcd_pairs_) {
      const std::int32_t k = clusters_.component_of_triangle(p.a);
      if (dirty(k) || topology_.triangles_excluded(p.a, p.b)) continue;
      int shared_count = 0;
      const ccd::SharedCorners shared = topology_.shared_corners(p.a, p.b, shared_count);
      if ((shared_count > 0) != adjacent || shared_count >= 3) continue;  // 3: duplicate face
      const auto& ta = topology_.triangle(p.a);
      const auto& tb = topology_.triangle(p.b);
      const auto row = [&](std::int32_t v) -> Eigen::Vector3d {
        return x_t0.row(static_cast<Eigen::Index>(v)).transpose();
      };
      const std::array<Eigen::Vector3d, 3> a{row(ta[0]), row(ta[1]), row(ta[2])};
      const std::array<Eigen::Vector3d, 3> b{row(tb[0]), row(tb[1]), row(tb[2])};
      if (adjacent && apart_beyond_shared(a, b, shared)) continue;
      ++tt_tests;
      if (tests_.triangles({a[0], a[1], a[2], b[0], b[1], b[2]}, shared)) {
        status_[at(k)] = Status::dirty;
      }
    }
    test_us += micros(t0, Clock::now());
  };
  // Bounded memory: the pairs come from the traversals in installments of block_pairs and are
  // tested as they come, so one pass over them never holds them whole. Non-adjacent pairs all
  // come before adjacent ones, so the traversals run twice: the second time only over components
  // not yet found dirty, and without counting its volume tests again. The tests made (tt_tests),
  // the volume tests counted and the outcome are those of testing all pairs in one piece (the
  // first pass traverses everything, as the one-piece pass did, whatever it has found).
  const std::size_t block = method_options_.block_pairs;
  const std::span<const culling::Aabb> tri_bounds(static_bounds_.triangles);
  const auto pass = [&](bool adjacent, std::int64_t& volume_tests) {
    const auto stream = [&](auto&& some) {
      for (bool done = false; !done;) {
        dcd_pairs_.clear();
        done = some(dcd_pairs_, block);
        if (!adjacent) stats_.dcd_pass_pairs += static_cast<std::int64_t>(dcd_pairs_.size());
        for (auto& p : dcd_pairs_) {
          if (p.b < p.a) std::swap(p.a, p.b);  // across two hierarchies: (a of one, b of other)
        }
        test_pairs(adjacent);
      }
    };
    for (std::int32_t a = 0; a < num_atomic; ++a) {
      if (cluster_bounds_[at(a)].lo[0] > cluster_bounds_[at(a)].hi[0]) continue;  // empty
      if (adjacent && dirty(clusters_.component_of_atomic(a))) continue;          // nothing to test
      const auto& local = clusters_.local_bvh(a);
      culling::start_self_traversal<3>(local, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::self_traverse_some<3>(
            local, tri_bounds, scratch_, pairs, volume_tests, max_pairs);
      });
    }
    for (const auto& cp : cluster_pairs_) {
      const std::int32_t k = clusters_.component_of_atomic(cp.a);
      if (k != clusters_.component_of_atomic(cp.b) || (adjacent && dirty(k))) continue;
      const auto& local_a = clusters_.local_bvh(cp.a);
      const auto& local_b = clusters_.local_bvh(cp.b);
      culling::start_pair_traversal<3>(local_a, local_b, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::pair_traverse_some<3>(
            local_a, tri_bounds, local_b, tri_bounds, scratch_, pairs, volume_tests, max_pairs);
      });
    }
  };
  pass(/*adjacent=*/false, bv_tests);
  std::int64_t counted_once = 0;
  pass(/*adjacent=*/true, counted_once);
  dcd_pairs_.clear();
  out.counters.bv_tests += bv_tests;
  out.counters.tt_tests += tt_tests;
  const auto end = Clock::now();
  out.times.traverse_us += micros(start, end) - test_us;
  out.times.elementary_us += test_us;
}

// --- class masks: which pairs of a mega cluster may be skipped -----------------------------------

void RadialViewMethod::compute_masks() {
  // A triangle's label: (mega cluster, sign) when the argument applies to it and it is H⁺ or H⁻;
  // −1 otherwise. A feature (vertex, edge) is pure when all its triangles carry the same label.
  // A triangle may be skipped against another of the same label only if every feature it owns
  // (representative triangles, culling/feature_topology.hpp) is pure with that label: then every
  // feature pair the triangle pair produces joins two pure features of one sign, which is what
  // the argument rules out (docs/radial-view.md, "Why features, not triangles").
  const auto label = [&](std::int32_t f) -> std::int64_t {
    const std::int32_t k = clusters_.component_of_triangle(f);
    if (culled_[at(k)] == 0) return -1;
    const OrientationClass c = classes_.triangle_class[at(f)];
    if (c == OrientationClass::uncertain) return -1;
    const std::int32_t mega = classes_.atomic_mega[at(clusters_.atomic_of(f))];
    return 2 * static_cast<std::int64_t>(mega) + (c == OrientationClass::negative ? 1 : 0);
  };
  const std::int32_t num_vertices = topology_.num_vertices();
  for (std::int32_t w = 0; w < num_vertices; ++w) {
    std::int64_t l = -2;
    for (const std::int32_t f : clusters_.vertex_triangles(w)) {
      const std::int64_t lf = label(f);
      l = (l == -2 || l == lf) ? lf : -1;
      if (l == -1) break;
    }
    vertex_label_[at(w)] = l < 0 ? -1 : l;
  }
  const std::int32_t num_edges = topology_.num_edges();
  for (std::int32_t e = 0; e < num_edges; ++e) {
    std::int64_t l = -2;
    for (auto i = edge_face_offsets_[at(e)]; i < edge_face_offsets_[at(e) + 1]; ++i) {
      const std::int64_t lf = label(edge_faces_[at(i)]);
      l = (l == -2 || l == lf) ? lf : -1;
      if (l == -1) break;
    }
    edge_label_[at(e)] = l < 0 ? -1 : l;
  }
  const std::int32_t num_faces = topology_.num_triangles();
  for (std::int32_t f = 0; f < num_faces; ++f) {
    const std::int64_t l = label(f);
    std::uint8_t mask = culling::kMaskOther;
    if (l >= 0) {
      const std::uint8_t owned = topology_.owned(f);
      const auto& corners = topology_.triangle(f);
      bool pure = true;
      for (int k = 0; k < 3 && pure; ++k) {
        if ((owned & (1u << k)) != 0 && vertex_label_[at(corners[at(k)])] != l) pure = false;
        if ((owned & (1u << (3 + k))) != 0 && edge_label_[at(topology_.face_edge(f, k))] != l) {
          pure = false;
        }
      }
      if (pure) mask = (l & 1) != 0 ? culling::kMaskNegative : culling::kMaskPositive;
    }
    triangle_mask_[at(f)] = mask;
  }
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    culling::node_class_masks<3>(clusters_.local_bvh(a), triangle_mask_, node_masks_[at(a)]);
  }
}

// --- intra- and inter-cluster checks (§6) ---------------------------------------------------------

std::int64_t RadialViewMethod::traverse(
    MaskedPairs which,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    culling::FrameResult& out) {
  const std::span<const culling::Aabb> tri_bounds(bounds_.triangles);
  std::int64_t& bv_tests = out.counters.bv_tests;
  const bool retest = which == MaskedPairs::skipped;
  const auto wanted = [&](std::int32_t a) {
    return !retest || escalate_[at(clusters_.component_of_atomic(a))] != 0;
  };
  // Each traversal runs in installments; the pairs of an installment go through the relative AABB
  // filter (§6) as they come, and every full block is tested before the traversal goes on.
  std::int64_t found = 0;
  const auto stream = [&](auto&& some) {
    blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      const std::size_t first = pairs.size();
      const bool done = some(pairs, max_pairs);
      found += static_cast<std::int64_t>(pairs.size() - first);
      if (options_.relative_aabb) {
        stats_.relative_aabb_culled +=
            culling::relative_aabb_filter(topology_, x_t0, x_t1, half_width, pairs, first);
      }
      return done;
    });
  };
  // Intra-cluster: each atomic cluster against itself, with the masks of its mega cluster.
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    if (!wanted(a)) continue;
    const auto& local = clusters_.local_bvh(a);
    culling::start_masked_self_traversal<3>(local, scratch_);
    stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      return culling::masked_self_traverse_some<3>(
          local,
          tri_bounds,
          node_masks_[at(a)],
          triangle_mask_,
          which,
          scratch_,
          pairs,
          bv_tests,
          max_pairs);
    });
  }
  // Atomic cluster pairs whose swept volumes meet (the global hierarchy's self traversal): within
  // one mega cluster with masks (intra-cluster check across atomic clusters), across mega
  // clusters without (inter-cluster check).
  for (const auto& cp : cluster_pairs_) {
    const bool same_mega = classes_.atomic_mega[at(cp.a)] == classes_.atomic_mega[at(cp.b)];
    const auto& local_a = clusters_.local_bvh(cp.a);
    const auto& local_b = clusters_.local_bvh(cp.b);
    if (same_mega) {
      if (!wanted(cp.a)) continue;
      culling::start_masked_pair_traversal<3>(local_a, local_b, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::masked_pair_traverse_some<3>(
            local_a,
            node_masks_[at(cp.a)],
            local_b,
            node_masks_[at(cp.b)],
            tri_bounds,
            triangle_mask_,
            which,
            scratch_,
            pairs,
            bv_tests,
            max_pairs);
      });
    } else if (!retest) {
      culling::start_pair_traversal<3>(local_a, local_b, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::pair_traverse_some<3>(
            local_a, tri_bounds, local_b, tri_bounds, scratch_, pairs, bv_tests, max_pairs);
      });
    }
  }
  return found;
}

void RadialViewMethod::ccd(const culling::Interval& interval, culling::FrameResult& out) {
  const skinning::Positions& x_t0 = interval.x_t0;
  const skinning::Positions& x_t1 = interval.x_t1;
  check_positions(x_t0, "detect_ccd", "x_t0");
  check_positions(x_t1, "detect_ccd", "x_t1");
  // The observers ride their bones: the interval's own transforms, else (a driver that selects
  // them itself) the BonePoses given at construction.
  std::span<const skinning::BoneTransform> bones_t0 = interval.bones_t0;
  std::span<const skinning::BoneTransform> bones_t1 = interval.bones_t1;
  if (static_cast<std::int32_t>(bones_t0.size()) < num_bones_ ||
      static_cast<std::int32_t>(bones_t1.size()) < num_bones_) {
    if (!poses_ || !poses_->ready()) {
      throw InvalidInput(
          "clustering::" + name_ + "::detect_ccd: the interval carries no bone transforms (" +
          std::to_string(bones_t0.size()) + " for " + std::to_string(num_bones_) +
          " bones) and no bone poses were selected");
    }
    bones_t0 = poses_->t0();
    bones_t1 = poses_->t1();
  }
  stats_ = RadialViewStats{};
  const std::int32_t num_components = clusters_.num_components();
  stats_.components = num_components;

  // 1. Which components the radial-view argument may be applied to in this interval.
  start_status(x_t0, out);
  const bool culling_possible = method_options_.min_separation == 0.0;
  for (std::int32_t k = 0; k < num_components; ++k) {
    culled_[at(k)] = culling_possible && clusters_.component_ok(k) &&
                     status_[at(k)] == Status::clean;
    stats_.components_culled += culled_[at(k)];
    stats_.components_open += clusters_.component_ok(k) ? 0 : 1;
    stats_.components_dirty += status_[at(k)] == Status::dirty ? 1 : 0;
  }

  // 2. Swept volumes of the interval, local hierarchies, then the global one over their roots.
  const auto t_refit = Clock::now();
  const double half_width = 0.5 * method_options_.min_separation;
  culling::swept_vertex_bounds<3>(x_t0, x_t1, half_width, bounds_.vertices);
  bounds_.derive(topology_);
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    auto& local = clusters_.local_bvh(a);
    if (local.empty()) {
      cluster_bounds_[at(a)] = culling::Aabb::empty();
      continue;
    }
    local.refit(bounds_.triangles);
    cluster_bounds_[at(a)] = local.node_bounds()[0];
  }
  clusters_.global_bvh().refit(cluster_bounds_);
  const auto t_classify = Clock::now();

  // 3. RV update: observers ride their bones; classes and mega clusters (§3.1, §5).
  pose_observers(clusters_, bones_t0, bones_t1, observers_);
  builder_.build(topology_.welded_triangles(), x_t0, x_t1, observers_, classes_);
  const auto t_masks = Clock::now();
  compute_masks();
  const auto t_traverse = Clock::now();

  // 4. Intra- and inter-cluster checks, relative AABBs, feature pairs and (5.) the elementary
  //    tests, a block of triangle pairs at a time.
  cluster_pairs_.clear();
  culling::self_traverse<3>(clusters_.global_bvh(), cluster_bounds_, scratch_, cluster_pairs_,
                            out.counters.bv_tests);
  blocks_.start_ccd(
      topology_, bounds_, x_t0, x_t1, tests_, method_options_.accuracy, ccd_options_, out);
  (void)traverse(MaskedPairs::tested, x_t0, x_t1, half_width, out);
  blocks_.finish();
  stats_.blocks += blocks_.blocks();
  const double test_us = blocks_.test_us();
  const auto t_escalate = Clock::now();

  // 6. The argument guarantees the first contact of a component, not the ones after it: where a
  //    component that had pairs skipped has a self-contact, test the skipped pairs too.
  const auto component_of_contact = [&](const culling::CcdContact& c) -> std::int32_t {
    std::int32_t ka = -1;
    std::int32_t kb = -1;
    if (c.kind == culling::CcdContact::Kind::vf) {
      ka = clusters_.component_of_vertex(c.a);
      kb = clusters_.component_of_triangle(c.b);
    } else {
      ka = clusters_.component_of_vertex(topology_.edge(c.a)[0]);
      kb = clusters_.component_of_vertex(topology_.edge(c.b)[0]);
    }
    return ka == kb ? ka : -1;
  };
  double escalate_traverse_us = 0.0;
  double escalate_elementary_us = 0.0;
  if (options_.guard) {
    std::fill(escalate_.begin(), escalate_.end(), 0);
    bool any = false;
    for (const auto& c : out.contacts) {
      const std::int32_t k = component_of_contact(c);
      if (k >= 0 && culled_[at(k)] != 0 && escalate_[at(k)] == 0) {
        escalate_[at(k)] = 1;
        ++stats_.components_escalated;
        any = true;
      }
    }
    if (any) {
      const auto e0 = Clock::now();
      const std::size_t before = out.contacts.size();
      blocks_.start_ccd(
          topology_, bounds_, x_t0, x_t1, tests_, method_options_.accuracy, ccd_options_, out);
      stats_.skipped_pairs_retested += traverse(MaskedPairs::skipped, x_t0, x_t1, half_width, out);
      blocks_.finish();
      stats_.blocks += blocks_.blocks();
      stats_.escalation_contacts += static_cast<std::int64_t>(out.contacts.size() - before);
      // Both runs are sorted; one canonical order for the whole interval (in place).
      std::inplace_merge(
          out.contacts.begin(), out.contacts.begin() + static_cast<std::ptrdiff_t>(before),
          out.contacts.end(),
          [](const culling::CcdContact& a, const culling::CcdContact& b) { return a.before(b); });
      const auto e1 = Clock::now();
      escalate_elementary_us = blocks_.test_us();
      escalate_traverse_us = micros(e0, e1) - escalate_elementary_us;
    }
  }
  const auto t_end = Clock::now();

  // 7. What the next interval may assume at its start (these positions' end): components that
  //    were free of self-intersection here and had no self-contact stay free of it.
  if (options_.guard && culling_possible) {
    for (std::int32_t k = 0; k < num_components; ++k) {
      carry_clean_[at(k)] = status_[at(k)] == Status::clean ? 1 : 0;
      carry_contact_[at(k)] = 0;
    }
    for (const auto& c : out.contacts) {
      const std::int32_t k = component_of_contact(c);
      if (k < 0) continue;
      carry_clean_[at(k)] = 0;
      carry_contact_[at(k)] = 1;
    }
    carry_x_ = x_t1;
    has_carry_ = true;
  }

  // Counters and stage times (paper Table 3: RV-update = classify + merge).
  out.counters.atomic_clusters += clusters_.num_atomic();
  out.counters.mega_clusters += classes_.num_mega();
  out.counters.h_minus += classes_.h_minus;
  out.counters.h_uncertain += classes_.h_uncertain;
  out.times.refit_us += micros(t_refit, t_classify);
  out.times.classify_us += classes_.classify_us + micros(t_masks, t_traverse);
  out.times.merge_us += classes_.merge_us;
  out.times.traverse_us += micros(t_traverse, t_escalate) - test_us + escalate_traverse_us;
  out.times.elementary_us += test_us + escalate_elementary_us;
  (void)t_end;
}

}  // namespace skelcd::clustering
