#include "clustering/radial_view_method.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>
#include <utility>

#include "ccd/orientation.hpp"
#include "clustering/side_winding.hpp"
#include "culling/candidates.hpp"
#include "culling/cluster_checks.hpp"
#include "culling/hierarchy_cache.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/sieved_dcd.hpp"
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

/// Lane i's box in wide node w: the float volume of its triangles, rounded outwards (it contains
/// their exact volume: a test on it only prunes less).
culling::Aabb lane_box(const culling::WideBvhNode<3>& w, int i) {
  culling::Aabb box;
  for (std::size_t k = 0; k < 3; ++k) {
    box.lo[k] = w.lo[k][static_cast<std::size_t>(i)];
    box.hi[k] = w.hi[k][static_cast<std::size_t>(i)];
  }
  return box;
}

/// The order in which the triangles take their features (culling::FeatureTopology): the rims
/// first, one side of each. A triangle's rest label is its atomic cluster and its class at rest,
/// seen from the cluster's observer (positive or not); a rim is a side between two labels. A
/// feature on a rim is impure whenever the two sides end up with different labels in an interval
/// (other mega clusters, other signs), and its owner is then tested as Hᵘ (compute_masks). Taken
/// in triangle order, the rim features are spread over the triangles on both sides of every rim.
/// Taken first by the triangles on the side of the higher label, they are all owned by one strip,
/// and the other side is left to be skipped. Ghosts come last, so they never own a real feature
/// (traverse). Empty (triangle order) when the segmentation does not fit: ClusterSet reports that.
std::vector<std::int32_t> rim_first_order(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation& segmentation,
    std::int32_t real_triangles) {
  const auto num_faces = static_cast<std::size_t>(topology.welded_triangles.rows());
  const auto& cluster = segmentation.triangle_cluster;
  if (cluster.size() != num_faces ||
      topology.edge_face_offsets.size() != static_cast<std::size_t>(topology.edges.rows()) + 1) {
    return {};
  }
  for (const std::int32_t c : cluster) {
    if (c < 0 || static_cast<std::size_t>(c) >= segmentation.clusters.size()) return {};
  }
  const auto rest = [&](std::int32_t w) -> Eigen::Vector3d {
    return mesh.rest_positions.row(topology.representative_vertex[at(w)]).transpose();
  };
  std::vector<std::int64_t> label(num_faces);
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto r = static_cast<Eigen::Index>(f);
    const Eigen::Vector3d a = rest(topology.welded_triangles(r, 0));
    const Eigen::Vector3d b = rest(topology.welded_triangles(r, 1));
    const Eigen::Vector3d c = rest(topology.welded_triangles(r, 2));
    const MovingTriangle t{a, b, c, a, b, c};
    const segmentation::Observer& o = segmentation.clusters[at(cluster[f])].observer;
    OrientationClass k = OrientationClass::uncertain;
    if (o.kind == segmentation::ObserverKind::point) {
      const Eigen::Vector3d q = o.segment.midpoint();
      k = classify(t, MovingPoint{q, q});
    } else {
      k = classify(
          t, MovingSegment{o.segment.head, o.segment.tail, o.segment.head, o.segment.tail});
    }
    label[f] =
        2 * static_cast<std::int64_t>(cluster[f]) + (k == OrientationClass::positive ? 0 : 1);
  }
  // Rank 0: a side on a rim with a lower label across it; 1: any other corner or side on a rim;
  // 2: inside one label; 3: ghosts.
  std::vector<std::uint8_t> rank(num_faces, 2);
  constexpr std::int64_t kUnset = -2;
  constexpr std::int64_t kMixed = -3;
  std::vector<std::int64_t> vertex_label(
      static_cast<std::size_t>(topology.num_welded_vertices()), kUnset);
  for (std::size_t f = 0; f < num_faces; ++f) {
    if (static_cast<std::int32_t>(f) >= real_triangles) continue;
    for (Eigen::Index k = 0; k < 3; ++k) {
      auto& l = vertex_label[at(topology.welded_triangles(static_cast<Eigen::Index>(f), k))];
      l = (l == kUnset || l == label[f]) ? label[f] : kMixed;
    }
  }
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto r = static_cast<Eigen::Index>(f);
    if (static_cast<std::int32_t>(f) >= real_triangles) {
      rank[f] = 3;
      continue;
    }
    for (Eigen::Index k = 0; k < 3 && rank[f] != 0; ++k) {
      if (vertex_label[at(topology.welded_triangles(r, k))] == kMixed) rank[f] = 1;
      const std::int32_t e = topology.face_edges(r, k);
      if (e < 0) continue;
      for (auto i = topology.edge_face_offsets[at(e)]; i < topology.edge_face_offsets[at(e) + 1];
           ++i) {
        const std::int32_t g = topology.edge_faces[at(i)];
        if (g < real_triangles && label[at(g)] < label[f]) rank[f] = 0;
      }
    }
  }
  std::vector<std::int32_t> order(num_faces);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return rank[at(a)] < rank[at(b)];
  });
  return order;
}

bool same_positions(const skinning::Positions& a, const skinning::Positions& b) {
  return a.rows() == b.rows() && std::equal(a.data(), a.data() + a.size(), b.data());
}

/// The mesh and topology the method works on: the capped ones when there are ghost caps.
const skinning::Mesh& used_mesh(
    const std::unique_ptr<GhostCaps>& ghosts, const skinning::Mesh& real) {
  return ghosts ? ghosts->mesh : real;
}
const skinning::Topology& used_topology(
    const std::unique_ptr<GhostCaps>& ghosts, const skinning::Topology& real) {
  return ghosts ? ghosts->topology : real;
}

skinning::Positions welded_rest(const skinning::Mesh& mesh, const skinning::Topology& topology) {
  skinning::Positions rest;
  skinning::gather_welded(topology, mesh.rest_positions, rest);
  return rest;
}

/// The method's FeatureTopology, rims first when a segmentation ranks them (rim_first_order). The
/// workers of a parallel run build their methods at the same time from the runner's mesh, weld
/// and segmentation: through the runner's cache (`cache`, null: built here) the first builds it
/// and the others share it — it is never written — where each built its own (about 8 ms and
/// 3 MB a worker on CesiumMan-dense). Not with ghost caps: each method caps a mesh of its own.
std::shared_ptr<const culling::FeatureTopology> method_features(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation* segmentation,
    bool rims_first,
    std::int32_t real_triangles,
    culling::HierarchyCache* cache) {
  const auto build = [&] {
    return std::make_shared<const culling::FeatureTopology>(
        mesh,
        topology,
        segmentation != nullptr && rims_first
            ? rim_first_order(mesh, topology, *segmentation, real_triangles)
            : std::vector<std::int32_t>{});
  };
  if (cache == nullptr) return build();
  std::ostringstream key;
  key << "RadialViewMethod features " << &mesh << ' ' << &topology << ' ' << segmentation << ' '
      << rims_first << ' ' << real_triangles;
  return cache->shared<culling::FeatureTopology>(key.str(), build);
}

/// Patches smaller than this are not classified (their triangles are tested as Hᵘ): a ray costs
/// a pass over the component, and a few triangles skipped save less than that.
constexpr std::int32_t kMinPatch = 8;
/// Triangles of a patch tried before it is given up (each with its own ray tilt).
constexpr int kPatchAttempts = 6;

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
    : RadialViewMethod(
          std::move(name),
          mesh,
          topology,
          // Loops up to kMaxGhostLoop edges; none when the segmentation does not fit (reported
          // below by ClusterSet).
          segmentation ? cap_small_loops(mesh, topology, *segmentation, kMaxGhostLoop) : nullptr,
          segmentation,  // copied: the argument above reads it (evaluation order is unspecified)
          std::move(poses),
          num_bones,
          method_options,
          options) {}

RadialViewMethod::RadialViewMethod(
    std::string name,
    const skinning::Mesh& real_mesh,
    const skinning::Topology& real_topology,
    std::unique_ptr<GhostCaps> ghosts,
    std::shared_ptr<const segmentation::Segmentation> segmentation,
    std::shared_ptr<const BonePoses> poses,
    std::int32_t num_bones,
    const culling::MethodOptions& method_options,
    const RadialViewOptions& options)
    : name_(std::move(name)),
      ghosts_(std::move(ghosts)),
      real_vertices_(real_topology.num_welded_vertices()),
      real_triangles_(static_cast<std::int32_t>(real_topology.welded_triangles.rows())),
      segmentation_(ghosts_ ? ghosts_->segmentation : std::move(segmentation)),
      poses_(std::move(poses)),
      features_(method_features(
          used_mesh(ghosts_, real_mesh),
          used_topology(ghosts_, real_topology),
          segmentation_.get(),
          options.rims_first,
          real_triangles_,
          ghosts_ ? nullptr : method_options.hierarchies.get())),
      topology_(*features_),
      clusters_(
          used_mesh(ghosts_, real_mesh),
          used_topology(ghosts_, real_topology),
          *segmentation_,
          num_bones,
          method_options.bvh),
      method_options_(method_options),
      options_(options),
      tests_(culling::with_ccd_defaults(method_options.elementary)),
      updater_(used_mesh(ghosts_, real_mesh), used_topology(ghosts_, real_topology), features_),
      dcd_rest_(welded_rest(used_mesh(ghosts_, real_mesh), used_topology(ghosts_, real_topology))),
      builder_(clusters_, options.clusters),
      blocks_(
          method_options.block_pairs,
          culling::block_reserve(
              method_options.block_pairs,
              method_options.bvh.leaf_size,
              topology_.num_triangles())) {
  // What every method refuses at once (the DCD, which checks them too, is built when needed).
  culling::check_method_options(method_options);
  // Not held: the method works on features_ (its own owner order), and a caller's features kept
  // here would outlive the caller's need for them (ClipRunner::adopt_method_features).
  method_options_.features.reset();
  num_bones_ = num_bones;
  ccd_options_.min_separation = method_options.min_separation;
  ccd_options_.relative_boxes = true;  // docs/ccd.md, "Relative boxes"
  const auto num_faces = at(topology_.num_triangles());
  const auto num_atomic = at(clusters_.num_atomic());
  const auto num_components = at(clusters_.num_components());
  // Everything an interval touches is sized here (the candidates' blocks by blocks_).
  // No edge volumes, and vertex volumes only with a contact distance (bounded memory; ccd).
  if (!culling::feature_stage_tests_ends(method_options.min_separation)) {
    bounds_.vertices.reserve(at(topology_.num_vertices()));
  }
  bounds_.triangles.reserve(num_faces);
  cluster_bounds_.resize(num_atomic);
  triangle_mask_.assign(num_faces, culling::kMaskOther);
  // Rigid rows given for the real triangles (the runner's welded numbering: the capped mesh's
  // ghosts come after them and have none).
  if (method_options.rigid_rows != nullptr &&
      method_options.rigid_rows->triangle_row.size() == at(real_triangles_)) {
    rigid_rows_ = method_options.rigid_rows;
    row_of_.assign(num_faces, -1);
    cluster_row_.assign(num_atomic, -1);
    cluster_live_row_.assign(num_atomic, -1);
    for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
      const auto faces = clusters_.triangles(a);
      std::int32_t row = faces.empty() || faces.front() >= real_triangles_
                             ? -1
                             : rigid_rows_->triangle_row[at(faces.front())];
      for (const std::int32_t f : faces) {
        if (row < 0) break;
        if (f >= real_triangles_ || rigid_rows_->triangle_row[at(f)] != row) row = -1;
      }
      cluster_row_[at(a)] = row;
    }
    row_certified_.reserve(at(rigid_rows_->num_rows()));
    rest_pairs_.reserve(rigid_rows_->rest_pairs.size());
  }
  node_masks_.resize(num_atomic);
  std::size_t deepest = 0;
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    node_masks_[at(a)].nodes.resize(clusters_.local_bvh(a).nodes().size());
    node_masks_[at(a)].slots.resize(clusters_.local_bvh(a).slot_stride());
    deepest = std::max(deepest, static_cast<std::size_t>(clusters_.local_bvh(a).depth()));
  }
  scratch_.reserve(std::max(
      4 * deepest + 4,
      4 * static_cast<std::size_t>(clusters_.global_bvh().depth()) + 4));
  node_stack_.reserve(2 * deepest + 2);
  triangle_label_.resize(at(topology_.num_triangles()));
  status_.assign(num_components, Status::unknown);
  culled_.assign(num_components, 0);
  component_escalated_.assign(num_components, 0);
  cut_.assign(num_faces, 0);
  skippable_.assign(num_faces, 0);
  taken_.assign(num_faces, 0);
  escalated_.assign(num_faces, 0);
  patch_order_.reserve(num_faces);
  // Component → triangles (CSR, from Topology::components), for the rays of the patches.
  const auto& components = used_topology(ghosts_, real_topology).components;
  component_offsets_.assign(1, 0);
  component_triangles_.reserve(num_faces);
  for (const auto& c : components) {
    component_triangles_.insert(component_triangles_.end(), c.faces.begin(), c.faces.end());
    component_offsets_.push_back(static_cast<std::int32_t>(component_triangles_.size()));
  }
  if (ghosts_) {
    // Pairs of two ghosts are never tested (traverse): sound only because ghosts own no real
    // feature — they come after the real triangles and features go to their first triangle.
    for (std::int32_t g = real_triangles_; g < topology_.num_triangles(); ++g) {
      const auto& owned = topology_.owned_features(g);
      for (std::size_t i = 0; i < owned.num_vertices; ++i) {
        if (owned.vertices[i] < real_vertices_) ghosts_own_real_features_ = true;
      }
      for (std::size_t i = 0; i < owned.num_edges; ++i) {
        if (ghosts_->real_edge[at(owned.edges[i])] >= 0) ghosts_own_real_features_ = true;
      }
    }
  }
  // Each triangle's neighbour across each side, for build_patches' walk: the edge's other face
  // when it has two, kNoNeighbour for a boundary edge, kNeighboursListed when it has more (the
  // walk then reads the edge's faces). A collapsed side (two corners welded into one: no edge,
  // face_edge −1) has no neighbour.
  face_neighbours_.assign(3 * num_faces, kNoNeighbour);
  for (std::int32_t f = 0; f < topology_.num_triangles(); ++f) {
    for (int side = 0; side < 3; ++side) {
      const std::int32_t e = topology_.face_edge(f, side);
      if (e < 0) continue;
      const auto faces = updater_.edge_triangles(e);
      std::int32_t& n = face_neighbours_[3 * at(f) + at(side)];
      if (faces.size() > 2) {
        n = kNeighboursListed;
      } else if (faces.size() == 2) {
        n = faces[0] != f ? faces[0] : faces[1];
      }
    }
  }
  if (ghosts_) {  // everything is built: keep only the loops and the edge map
    ghosts_->mesh = skinning::Mesh{};
    ghosts_->topology = skinning::Topology{};
    ghosts_->segmentation.reset();
  }
  // A parallel run's workers (the cache) with DCD queries: each worker's first block starts
  // with a full DCD, so its DCD tree is built now, a copy of the tree the baseline's `bvh` built
  // (the same key: the welded triangles at rest, no node volumes), with one slot adjacency for
  // all the workers — where each worker built both at its first block (docs/radial-view.md,
  // "Memory"). A serial run's (a hand-over cache): the baseline's tree itself, lent once its
  // `bvh` is gone. Not with ghost caps: the tree is over the capped mesh, each method's own.
  if (method_options.dcd_queries && method_options.hierarchies != nullptr && !ghosts_) {
    (void)dcd_tree(method_options.hierarchies.get());
  }
}

const skinning::Positions& RadialViewMethod::with_ghosts(
    const skinning::Positions& x, skinning::Positions& capped) const {
  if (!ghosts_) return x;
  place_ghost_centres(*ghosts_, x, capped);
  return capped;
}

void RadialViewMethod::drop_ghosts(culling::FrameResult& out) {
  if (!ghosts_) return;
  const auto ghost_pair = [&](const culling::TrianglePair& p) {
    return p.a >= real_triangles_ || p.b >= real_triangles_;
  };
  std::erase_if(out.dcd_pairs, ghost_pair);
  const std::size_t before = out.contacts.size();
  std::erase_if(out.contacts, [&](culling::CcdContact& c) {
    if (c.kind == culling::CcdContact::Kind::vf) {
      return c.a >= real_vertices_ || c.b >= real_triangles_;
    }
    const std::int32_t a = ghosts_->real_edge[at(c.a)];
    const std::int32_t b = ghosts_->real_edge[at(c.b)];
    if (a < 0 || b < 0) return true;
    c.a = a;
    c.b = b;
    return false;
  });
  stats_.ghost_contacts += static_cast<std::int64_t>(before - out.contacts.size());
  // Renumbered edges: the canonical order again.
  std::sort(
      out.contacts.begin(),
      out.contacts.end(),
      [](const culling::CcdContact& a, const culling::CcdContact& b) { return a.before(b); });
}

void RadialViewMethod::check_positions(
    const skinning::Positions& x,
    const char* call,
    const char* which) const {
  if (x.rows() != real_vertices_) {
    throw InvalidInput(
        "clustering::" + name_ + "::" + call + ": " + which + " has " + std::to_string(x.rows()) +
        " rows, expected one per welded vertex (" + std::to_string(real_vertices_) + ")");
  }
}

void RadialViewMethod::record_dcd(
    const skinning::Positions& x,
    const culling::FrameResult& result) {
  if (!options_.guard) return;
  dcd_x_ = x;
  dcd_pairs_.assign(result.dcd_pairs.begin(), result.dcd_pairs.end());
  has_dcd_ = true;
}

void RadialViewMethod::dcd(const culling::Instant& at, culling::FrameResult& out) {
  check_positions(at.x, "detect_dcd", "x");
  const skinning::Positions& x = with_ghosts(at.x, capped_x0_);
  DcdTree& tree = dcd_tree();
  // `bvh`'s DCD (the same tree, refit over the static volumes at x, the same sieved traversal
  // and tests) through this method's volumes and blocks, which the CCD refills.
  culling::sieved_dcd_at<3>(
      x,
      tree.bvh,
      bounds_,
      topology_,
      *tree.slots,
      tree.full_slots,
      scratch_,
      blocks_,
      tests_,
      out);
  blocks_.release_dcd_planes();  // not held between queries: the CCD's blocks need none

  record_dcd(x, out);  // with the ghosts' pairs: the next interval's cuts need them
  drop_ghosts(out);
}

void RadialViewMethod::start_dcd(const skinning::Positions& x, culling::FrameResult& out) {
  // The triangles' static volumes, the local hierarchies and the global one over their roots
  // (step 2 of the interval refits them over the swept volumes afterwards).
  const auto t0 = Clock::now();
  bounds_.static_triangles(topology_, x);
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    auto& local = clusters_.local_bvh(a);
    if (local.empty()) {
      cluster_bounds_[at(a)] = culling::Aabb::empty();
      continue;
    }
    local.refit(bounds_.triangles);  // drops the last interval's end boxes
    cluster_bounds_[at(a)] = local.root_bounds();
  }
  clusters_.global_bvh().refit(cluster_bounds_);
  const auto t1 = Clock::now();
  // Every pair of triangles whose boxes meet: each atomic cluster with itself, then the cluster
  // pairs whose boxes meet — what `bvh`'s self traversal finds, through this method's trees — in
  // blocks through the DCD rules and tests.
  const std::span<const culling::Aabb> tri(bounds_.triangles);
  std::int64_t& bv_tests = out.counters.bv_tests;
  cluster_pairs_.clear();
  culling::self_traverse<3>(
      clusters_.global_bvh(), cluster_bounds_, scratch_, cluster_pairs_, bv_tests);
  blocks_.start_dcd(topology_, x, tests_, out);
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    const auto& local = clusters_.local_bvh(a);
    if (local.empty()) continue;
    culling::start_self_traversal<3>(local, scratch_);
    blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      return culling::self_traverse_some<3>(local, tri, scratch_, pairs, bv_tests, max_pairs);
    });
  }
  for (const auto& cp : cluster_pairs_) {
    const auto& local_a = clusters_.local_bvh(cp.a);
    const auto& local_b = clusters_.local_bvh(cp.b);
    culling::start_pair_traversal<3>(local_a, local_b, scratch_);
    blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      return culling::pair_traverse_some<3>(
          local_a, tri, local_b, tri, scratch_, pairs, bv_tests, max_pairs);
    });
  }
  blocks_.finish();
  blocks_.release_dcd_planes();  // rare here: not held for the run
  const auto t2 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
  out.times.elementary_us += blocks_.test_us();
}

RadialViewMethod::DcdTree::DcdTree(
    culling::HierarchyCache* cache,
    const std::shared_ptr<const culling::FeatureTopology>& features,
    const skinning::Positions& rest,
    const culling::BvhOptions& options)
    : tree(culling::lend_hierarchy<3>(cache, features->welded_triangles(), rest, options)),
      slots(culling::shared_slot_adjacency(cache, features, bvh.triangle_order())) {
  full_slots.reserve(at(features->num_triangles()));
}

RadialViewMethod::DcdTree& RadialViewMethod::dcd_tree(culling::HierarchyCache* cache) {
  if (!dcd_) {
    // Traversed through the wide copy only, as `bvh`'s: no binary node volumes (the key of the
    // baseline's `bvh` tree, which `cache` may hold).
    culling::BvhOptions options = method_options_.bvh;
    options.node_volumes = false;
    dcd_ = std::make_unique<DcdTree>(cache, features_, dcd_rest_, options);
    dcd_rest_ = skinning::Positions();  // built: dcd_ is kept (see dcd_)
    scratch_.reserve_self(dcd_->bvh);
  }
  return *dcd_;
}

// --- preconditions at the interval's start ------------------------------------------------------

void RadialViewMethod::start_status(const skinning::Positions& x_t0, culling::FrameResult& out) {
  const std::int32_t num_components = clusters_.num_components();
  std::fill(status_.begin(), status_.end(), Status::unknown);
  std::fill(cut_.begin(), cut_.end(), 0);
  start_by_own_dcd_ = false;
  const bool culling_possible = method_options_.min_separation == 0.0;
  if (!culling_possible) return;  // nothing is skipped: the start state does not matter
  if (!options_.guard) {
    for (std::int32_t k = 0; k < num_components; ++k) {
      if (clusters_.component_ok(k)) status_[at(k)] = Status::clean;
    }
    return;
  }
  // The intersecting pairs at x_t0: from a DCD at these positions, from the previous interval
  // (its end is this start), else a DCD here.
  if (has_dcd_ && same_positions(x_t0, dcd_x_)) {
    start_pairs_.assign(dcd_pairs_.begin(), dcd_pairs_.end());
  } else if (has_carry_ && same_positions(x_t0, carry_x_)) {
    start_pairs_.swap(carry_pairs_);
  } else {
    scratch_result_.clear();
    start_by_own_dcd_ = true;
    start_dcd(x_t0, scratch_result_);
    start_pairs_.assign(scratch_result_.dcd_pairs.begin(), scratch_result_.dcd_pairs.end());
    out.counters.bv_tests += scratch_result_.counters.bv_tests;
    out.counters.tt_tests += scratch_result_.counters.tt_tests;
    out.times.traverse_us += scratch_result_.times.traverse_us;
    out.times.elementary_us += scratch_result_.times.elementary_us;
    stats_.dcd_pass_pairs = scratch_result_.counters.candidate_pairs;
    for (std::int32_t k = 0; k < num_components; ++k) {
      stats_.components_dcd += clusters_.component_ok(k) ? 1 : 0;
    }
  }
  has_carry_ = false;
  for (std::int32_t k = 0; k < num_components; ++k) {
    if (clusters_.component_ok(k)) status_[at(k)] = Status::clean;
  }
  for (const auto& p : start_pairs_) {
    const std::int32_t k = clusters_.component_of_triangle(p.a);
    if (k != clusters_.component_of_triangle(p.b) || !clusters_.component_ok(k)) continue;
    // Two ghosts: their contacts are not tested (traverse), so the carried set does not know
    // these pairs; every ghost is cut below instead.
    if (p.a >= real_triangles_ && p.b >= real_triangles_) continue;
    status_[at(k)] = Status::dirty;
    cut_[at(p.a)] = 1;
    cut_[at(p.b)] = 1;
  }
  // Ghosts are always cut (docs/radial-view.md, "Open parts with ghost triangles"): patches hold
  // real triangles only, and whether two ghosts intersect never matters.
  const auto num_triangles = static_cast<std::int32_t>(cut_.size());
  for (std::int32_t g = real_triangles_; g < num_triangles; ++g) {
    const std::int32_t k = clusters_.component_of_triangle(g);
    if (!clusters_.component_ok(k)) continue;
    status_[at(k)] = Status::dirty;
    cut_[at(g)] = 1;
  }
}

void RadialViewMethod::build_patches() {
  // Patches: uncut triangles of the dirty culled components joined across edges (the component is
  // closed and manifold, so each edge has two triangles), component by component.
  const std::int32_t num_components = clusters_.num_components();
  patch_order_.clear();
  patch_offsets_.assign(1, 0);
  component_patches_.assign(at(num_components) + 1, 0);
  // A triangle is taken (cut, or in a patch already) when its byte is set: one byte read per
  // neighbour met.
  std::copy(cut_.begin(), cut_.end(), taken_.begin());
  for (std::int32_t k = 0; k < num_components; ++k) {
    component_patches_[at(k)] = static_cast<std::int32_t>(patch_offsets_.size() - 1);
    if (culled_[at(k)] == 0 || status_[at(k)] != Status::dirty) continue;
    const auto first = static_cast<std::ptrdiff_t>(component_offsets_[at(k)]);
    const auto last = static_cast<std::ptrdiff_t>(component_offsets_[at(k) + 1]);
    for (std::ptrdiff_t i = first; i < last; ++i) {
      const std::int32_t seed = component_triangles_[static_cast<std::size_t>(i)];
      if (taken_[at(seed)] != 0) continue;
      std::size_t head = patch_order_.size();
      patch_order_.push_back(seed);
      taken_[at(seed)] = 1;
      const auto join = [&](std::int32_t g) {
        if (taken_[at(g)] != 0) return;
        taken_[at(g)] = 1;
        patch_order_.push_back(g);
      };
      while (head < patch_order_.size()) {
        const std::int32_t f = patch_order_[head++];
        for (int s = 0; s < 3; ++s) {
          // The faces of f's side s in the edge's order (f itself is in the patch already).
          const std::int32_t n = face_neighbours_[3 * at(f) + at(s)];
          if (n >= 0) {
            join(n);
          } else if (n == kNeighboursListed) {
            for (const std::int32_t g : updater_.edge_triangles(topology_.face_edge(f, s))) join(g);
          }
        }
      }
      patch_offsets_.push_back(static_cast<std::int32_t>(patch_order_.size()));
    }
  }
  component_patches_[at(num_components)] = static_cast<std::int32_t>(patch_offsets_.size() - 1);
}

void RadialViewMethod::classify_patches(const skinning::Positions& x_t0) {
  // Clean culled components: every triangle is skippable (the surface is embedded, its front
  // winding number the same everywhere). Dirty ones: the triangles of uncut patches whose front
  // winding number is that of the component's largest classified patch.
  const std::int32_t num_components = clusters_.num_components();
  const auto& triangles = topology_.welded_triangles();
  build_patches();
  for (std::int32_t k = 0; k < num_components; ++k) {
    const auto first = static_cast<std::ptrdiff_t>(component_offsets_[at(k)]);
    const auto last = static_cast<std::ptrdiff_t>(component_offsets_[at(k) + 1]);
    const std::span<const std::int32_t> surface(
        component_triangles_.data() + first, static_cast<std::size_t>(last - first));
    const bool dirty = status_[at(k)] == Status::dirty;
    for (const std::int32_t f : surface) skippable_[at(f)] = culled_[at(k)] != 0 && !dirty ? 1 : 0;
    if (culled_[at(k)] == 0 || !dirty) continue;
    // One ray per patch, largest patch first: its value is the component's.
    patch_sizes_.clear();
    for (std::int32_t p = component_patches_[at(k)]; p < component_patches_[at(k) + 1]; ++p) {
      const std::int32_t size = patch_offsets_[at(p) + 1] - patch_offsets_[at(p)];
      ++stats_.patches;
      if (size >= kMinPatch) patch_sizes_.emplace_back(-size, p);
    }
    std::sort(patch_sizes_.begin(), patch_sizes_.end());
    const auto make_skippable = [&](std::int32_t p) {
      for (std::int32_t i = patch_offsets_[at(p)]; i < patch_offsets_[at(p) + 1]; ++i) {
        skippable_[at(patch_order_[at(i)])] = 1;
      }
    };
    if (patch_sizes_.size() == 1) {
      // The only patch to classify: its value is the component's whatever it is, no ray needed
      // (its triangles all see one front value, which is all the argument asks of a skipped pair).
      ++stats_.patches_classified;
      make_skippable(patch_sizes_.front().second);
    } else if (!patch_sizes_.empty()) {
      // The rays end beyond the component's box at x_t0; the union of its clusters' swept boxes
      // contains it (no pass over the surface).
      culling::Aabb box = culling::Aabb::empty();
      for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
        if (clusters_.component_of_atomic(a) == k) box.merge(cluster_bounds_[at(a)]);
      }
      std::optional<int> value;
      for (const auto& [minus_size, p] : patch_sizes_) {
        const std::int32_t begin = patch_offsets_[at(p)];
        const std::int32_t size = -minus_size;
        std::optional<int> w;
        for (int attempt = 0; attempt < kPatchAttempts && !w; ++attempt) {
          // Spread the tries over the patch (BFS order: the seed's neighbourhood first). The
          // count runs over the triangles the hierarchies say may meet the ray: the same as over
          // the whole surface (count_winding).
          const std::int32_t f = patch_order_[at(begin + (attempt * size) / kPatchAttempts)];
          const std::optional<WindingRay> ray = winding_ray(box, triangles, x_t0, f, attempt);
          if (!ray) continue;
          gather_ray_candidates(k, *ray);
          w = count_winding(*ray, ray_candidates_, triangles, x_t0, f);
          ++stats_.rays;
        }
        if (!w) continue;
        ++stats_.patches_classified;
        if (!value) value = w;
        if (*w == *value) make_skippable(p);
      }
    }
    for (const std::int32_t f : surface) {
      stats_.triangles_kept_out += skippable_[at(f)] == 0 ? 1 : 0;
    }
  }
}

void RadialViewMethod::gather_ray_candidates(std::int32_t k, const WindingRay& ray) {
  // Both segments against the swept boxes, which contain the triangles at x_t0: the global
  // hierarchy over the atomic clusters, then the local ones of k's clusters.
  const auto may_meet = [&](const culling::Aabb& b) {
    return segment_meets_box(ray.front, ray.far, b) || segment_meets_box(ray.back, ray.front, b);
  };
  // The atomic clusters whose boxes may meet a segment: the global hierarchy's leaves (one
  // cluster each, whose exact box is then the one just tested).
  ray_candidates_.clear();
  const auto& global = clusters_.global_bvh();
  if (global.empty()) return;
  ray_stack_.assign(1, 0);
  while (!ray_stack_.empty()) {
    const std::int32_t n = ray_stack_.back();
    ray_stack_.pop_back();
    if (!may_meet(global.node_bounds()[at(n)])) continue;
    const auto& node = global.nodes()[at(n)];
    if (!node.is_leaf()) {
      ray_stack_.push_back(node.right);
      ray_stack_.push_back(n + 1);
      continue;
    }
    for (std::int32_t i = node.begin; i < node.end; ++i) {
      const std::int32_t a = global.triangle_order()[at(i)];
      if (clusters_.component_of_atomic(a) == k) gather_ray_cluster(a, may_meet);
    }
  }
}

template <class MayMeet>
void RadialViewMethod::gather_ray_cluster(std::int32_t a, const MayMeet& may_meet) {
  // Down the cluster's wide copy (its lanes' float boxes), then each triangle's exact box.
  const auto& local = clusters_.local_bvh(a);
  if (local.empty()) return;
  const auto wide = local.wide_nodes();
  const auto order = local.triangle_order();
  ray_local_stack_.assign(1, 0);
  while (!ray_local_stack_.empty()) {
    const auto& w = wide[at(ray_local_stack_.back())];
    ray_local_stack_.pop_back();
    for (int i = 0; i < w.num_children; ++i) {
      if (!may_meet(lane_box(w, i))) continue;
      if (w.child[i] >= 0) {
        ray_local_stack_.push_back(w.child[i]);
        continue;
      }
      for (std::int32_t s = ~w.child[i]; s < ~w.child[i] + w.count[i]; ++s) {
        const std::int32_t t = order[at(s)];
        if (may_meet(bounds_.triangles[at(t)])) ray_candidates_.push_back(t);
      }
    }
  }
}

// --- class masks: which pairs of a mega cluster may be skipped -----------------------------------

void RadialViewMethod::compute_masks() {
  // A triangle's label: (mega cluster, sign) when the argument applies to it and it is H⁺ or H⁻;
  // −1 otherwise. A feature (vertex, edge) is pure when all its triangles carry the same label.
  // A triangle may be skipped against another of the same label only if every feature it owns
  // (representative triangles, culling/feature_topology.hpp) is pure with that label: then every
  // feature pair the triangle pair produces joins two pure features of one sign, which is what
  // the argument rules out (docs/radial-view.md, "Why features, not triangles").
  const auto label = [&](std::int32_t f) -> std::int32_t {
    const std::int32_t k = clusters_.component_of_triangle(f);
    // Ghost triangles are Hᵘ: tested against everything, never skipped.
    if (culled_[at(k)] == 0 || skippable_[at(f)] == 0 || f >= real_triangles_) return -1;
    const OrientationClass c = classes_.triangle_class[at(f)];
    if (c == OrientationClass::uncertain) return -1;
    const std::int32_t mega = classes_.atomic_mega[at(clusters_.atomic_of(f))];
    return 2 * mega + (c == OrientationClass::negative ? 1 : 0);
  };
  // A feature is pure with label l when every triangle at it has label l. Only the features a
  // labelled triangle owns are asked about, each by its one owner: decided there. An edge's
  // triangles are its owner and the neighbour across it (face_neighbours_), the edge's list only
  // where it has more than two; the labels are 4 bytes (on a 28k-triangle mesh the edges' lists
  // and 8-byte labels it read before no longer fitted the second-level cache).
  const std::int32_t num_faces = topology_.num_triangles();
  for (std::int32_t f = 0; f < num_faces; ++f) triangle_label_[at(f)] = label(f);
  const auto vertex_pure = [&](std::int32_t w, std::int32_t l) {
    for (const std::int32_t f : updater_.vertex_triangles(w)) {
      if (triangle_label_[at(f)] != l) return false;
    }
    return true;
  };
  const auto edge_pure = [&](std::int32_t f, int side, std::int32_t l) {
    const std::int32_t n = face_neighbours_[3 * at(f) + at(side)];
    if (n >= 0) return triangle_label_[at(n)] == l;
    if (n == kNoNeighbour) return true;  // a boundary edge: f is its only triangle
    for (const std::int32_t g : updater_.edge_triangles(topology_.face_edge(f, side))) {
      if (triangle_label_[at(g)] != l) return false;
    }
    return true;
  };
  for (std::int32_t f = 0; f < num_faces; ++f) {
    const std::int32_t l = triangle_label_[at(f)];
    std::uint8_t mask = culling::kMaskOther;
    if (l >= 0) {
      const std::uint8_t owned = topology_.owned(f);
      const auto& corners = topology_.triangle(f);
      bool pure = true;
      for (int k = 0; k < 3 && pure; ++k) {
        if ((owned & (1u << k)) != 0 && !vertex_pure(corners[at(k)], l)) pure = false;
        if (pure && (owned & (1u << (3 + k))) != 0 && !edge_pure(f, k, l)) pure = false;
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

void RadialViewMethod::certify_rows(const culling::Interval& interval) {
  rest_pairs_.clear();
  rows_live_ = false;
  if (!rigid_rows_ || interval.bones_t0.empty() || interval.bones_t1.empty()) return;
  const culling::RigidRows& rows = *rigid_rows_;
  culling::certify_rigid_rows(
      rows, interval.bones_t0, interval.bones_t1, method_options_.min_separation, row_certified_);
  for (const std::uint8_t c : row_certified_) stats_.rows_certified += c;
  if (stats_.rows_certified == 0) return;
  for (std::int32_t f = 0; f < real_triangles_; ++f) {
    const std::int32_t r = rows.triangle_row[at(f)];
    row_of_[at(f)] = r >= 0 && row_certified_[at(r)] != 0 ? r : -1;
  }
  for (std::size_t a = 0; a < cluster_row_.size(); ++a) {
    const std::int32_t r = cluster_row_[a];
    cluster_live_row_[a] = r >= 0 && row_certified_[at(r)] != 0 ? r : -1;
  }
  for (const culling::TrianglePair& p : rows.rest_pairs) {
    if (row_of_[at(p.a)] >= 0) rest_pairs_.push_back(p);
  }
  stats_.rest_pairs = static_cast<std::int64_t>(rest_pairs_.size());
  rows_live_ = true;
}

std::int64_t RadialViewMethod::drop_row_pairs(
    std::vector<culling::TrianglePair>& pairs, std::size_t first) const {
  const auto kept = std::remove_if(
      pairs.begin() + static_cast<std::ptrdiff_t>(first),
      pairs.end(),
      [&](const culling::TrianglePair& p) {
        const std::int32_t r = row_of_[at(p.a)];
        return r >= 0 && r == row_of_[at(p.b)];
      });
  const auto dropped = static_cast<std::int64_t>(pairs.end() - kept);
  pairs.erase(kept, pairs.end());
  return dropped;
}

void RadialViewMethod::stream_rest_pairs(double half_width) {
  if (rest_pairs_.empty()) return;
  std::size_t next = 0;
  blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
    // At most an installment's worth at a time, so that a block stays bounded.
    const std::size_t first = pairs.size();
    const std::size_t take =
        std::min(rest_pairs_.size() - next, max_pairs > first ? max_pairs - first : std::size_t{1});
    pairs.insert(
        pairs.end(),
        rest_pairs_.begin() + static_cast<std::ptrdiff_t>(next),
        rest_pairs_.begin() + static_cast<std::ptrdiff_t>(next + take));
    next += take;
    if (filters_pairs()) {
      stats_.relative_aabb_culled += relative_filter_.filter(topology_, half_width, pairs, first);
    }
    return next == rest_pairs_.size();
  });
}

std::int64_t RadialViewMethod::traverse(double half_width, culling::FrameResult& out) {
  const std::span<const culling::Aabb> tri_bounds(bounds_.triangles);
  std::int64_t& bv_tests = out.counters.bv_tests;
  // Rigid rows (docs/radial-view.md "Rigid rows"): the certified rows' rest pairs are tested
  // first; the walks' pairs of two triangles of one such row are dropped below.
  if (rows_live_) stream_rest_pairs(half_width);
  // Each traversal runs in installments; the pairs of an installment go through the relative AABB
  // filter (§6) as they come, and every full block is tested before the traversal goes on.
  std::int64_t found = 0;
  const auto stream = [&](auto&& some) {
    blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      const std::size_t first = pairs.size();
      const bool done = some(pairs, max_pairs);
      found += static_cast<std::int64_t>(pairs.size() - first);
      if (rows_live_) stats_.rigid_pairs_skipped += drop_row_pairs(pairs, first);
      if (filters_pairs()) {
        stats_.relative_aabb_culled += relative_filter_.filter(topology_, half_width, pairs, first);
      }
      if (ghosts_ && !ghosts_own_real_features_) {
        // Two ghosts own only ghost features (centres, spokes, ghost faces: real features are
        // owned by real triangles, which come first): no contact between those is reported or
        // needed (docs/radial-view.md, "Open parts with ghost triangles").
        const auto kept = std::remove_if(
            pairs.begin() + static_cast<std::ptrdiff_t>(first),
            pairs.end(),
            [&](const culling::TrianglePair& p) {
              return p.a >= real_triangles_ && p.b >= real_triangles_;
            });
        stats_.ghost_pairs_skipped += static_cast<std::int64_t>(pairs.end() - kept);
        pairs.erase(kept, pairs.end());
      }
      return done;
    });
  };
  // Intra-cluster: each atomic cluster against itself, with the masks of its mega cluster.
  // A cluster (or two) whose triangles all have one certified row holds no pair to test.
  const auto one_row = [&](std::int32_t a, std::int32_t b) {
    if (!rows_live_) return false;
    const std::int32_t r = cluster_live_row_[at(a)];
    if (r < 0 || r != cluster_live_row_[at(b)]) return false;
    ++stats_.rigid_walks_skipped;
    return true;
  };
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    if (one_row(a, a)) continue;
    const auto& local = clusters_.local_bvh(a);
    culling::start_masked_self_traversal<3>(local, scratch_);
    stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
      return culling::masked_self_traverse_some<3>(
          local,
          tri_bounds,
          node_masks_[at(a)],
          MaskedPairs::tested,
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
    if (one_row(cp.a, cp.b)) continue;
    const bool same_mega = classes_.atomic_mega[at(cp.a)] == classes_.atomic_mega[at(cp.b)];
    const auto& local_a = clusters_.local_bvh(cp.a);
    const auto& local_b = clusters_.local_bvh(cp.b);
    if (same_mega) {
      culling::start_masked_pair_traversal<3>(local_a, local_b, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::masked_pair_traverse_some<3>(
            local_a,
            node_masks_[at(cp.a)],
            local_b,
            node_masks_[at(cp.b)],
            tri_bounds,
            MaskedPairs::tested,
            scratch_,
            pairs,
            bv_tests,
            max_pairs);
      });
    } else {
      culling::start_pair_traversal<3>(local_a, local_b, scratch_);
      stream([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
        return culling::pair_traverse_some<3>(
            local_a, tri_bounds, local_b, tri_bounds, scratch_, pairs, bv_tests, max_pairs);
      });
    }
  }
  return found;
}

// --- the local guard's re-tests --------------------------------------------------------------

void RadialViewMethod::escalate(const culling::FrameResult& out, std::int32_t round) {
  // The triangles at every vertex of a contact's two features: the contact's triangles and the
  // owners of their features (docs/radial-view.md, "The local guard": re-testing their skipped
  // pairs re-tests every skipped feature pair at those triangles).
  const auto mark_vertex = [&](std::int32_t w) {
    for (const std::int32_t f : updater_.vertex_triangles(w)) {
      const std::uint8_t m = triangle_mask_[at(f)];
      if (escalated_[at(f)] != 0 || (m != culling::kMaskPositive && m != culling::kMaskNegative)) {
        continue;
      }
      escalated_[at(f)] = round;
      frontier_.push_back(f);
      ++stats_.triangles_escalated;
      const std::int32_t k = clusters_.component_of_triangle(f);
      if (component_escalated_[at(k)] == 0) {
        component_escalated_[at(k)] = 1;
        ++stats_.components_escalated;
      }
    }
  };
  for (const auto& c : out.contacts) {
    if (c.kind == culling::CcdContact::Kind::vf) {
      mark_vertex(c.a);
      for (const std::int32_t w : topology_.triangle(c.b)) mark_vertex(w);
    } else {
      for (const std::int32_t w : topology_.edge(c.a)) mark_vertex(w);
      for (const std::int32_t w : topology_.edge(c.b)) mark_vertex(w);
    }
  }
}

std::int64_t RadialViewMethod::retest_frontier(
    std::int32_t round, double half_width, culling::FrameResult& out) {
  // The pairs the masked traversal skipped: both triangles of one mega cluster with the same
  // single-sign mask, their swept boxes overlapping. A pair with a triangle of an earlier round
  // was tested in that round; two of this round are taken once, from the smaller id.
  const std::span<const culling::Aabb> tri_bounds(bounds_.triangles);
  std::int64_t& bv_tests = out.counters.bv_tests;
  std::int64_t found = 0;
  std::size_t next = 0;
  blocks_.drain([&](std::vector<culling::TrianglePair>& pairs, std::size_t max_pairs) {
    const std::size_t first = pairs.size();
    while (next < frontier_.size() && pairs.size() - first < max_pairs) {
      const std::int32_t t = frontier_[next++];
      const std::uint8_t mask = triangle_mask_[at(t)];
      const culling::Aabb& box = tri_bounds[at(t)];
      const std::int32_t mega = classes_.atomic_mega[at(clusters_.atomic_of(t))];
      const std::int32_t row = rows_live_ ? row_of_[at(t)] : -1;
      for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
        if (classes_.atomic_mega[at(a)] != mega) continue;
        // Every triangle of `a` in t's certified row: no pair of t's there to re-test.
        if (row >= 0 && cluster_live_row_[at(a)] == row) continue;
        ++bv_tests;
        if (!cluster_bounds_[at(a)].overlaps(box)) continue;
        // Down the cluster's wide copy: a lane whose node holds no triangle of t's mask, or
        // whose float box misses t's, holds no pair to re-test.
        const auto& local = clusters_.local_bvh(a);
        const auto wide = local.wide_nodes();
        const auto order = local.triangle_order();
        const auto& masks = node_masks_[at(a)].nodes;
        node_stack_.clear();
        node_stack_.push_back(0);
        while (!node_stack_.empty()) {
          const auto& w = wide[at(node_stack_.back())];
          node_stack_.pop_back();
          for (int i = 0; i < w.num_children; ++i) {
            if ((masks[at(w.node[i])] & mask) == 0) continue;
            ++bv_tests;
            if (!lane_box(w, i).overlaps(box)) continue;
            if (w.child[i] >= 0) {
              node_stack_.push_back(w.child[i]);
              continue;
            }
            for (std::int32_t s = ~w.child[i]; s < ~w.child[i] + w.count[i]; ++s) {
              const std::int32_t u = order[at(s)];
              if (u == t || triangle_mask_[at(u)] != mask) continue;
              const std::int32_t r = escalated_[at(u)];
              if ((r != 0 && r < round) || (r == round && u < t)) continue;
              if (!tri_bounds[at(u)].overlaps(box)) continue;
              pairs.push_back(culling::TrianglePair{std::min(t, u), std::max(t, u)});
            }
          }
        }
      }
    }
    // A rest pair was tested at the start (stream_rest_pairs); the row's other pairs need none.
    if (rows_live_) stats_.rigid_pairs_skipped += drop_row_pairs(pairs, first);
    found += static_cast<std::int64_t>(pairs.size() - first);
    if (filters_pairs()) {
      stats_.relative_aabb_culled += relative_filter_.filter(topology_, half_width, pairs, first);
    }
    return next == frontier_.size();
  });
  return found;
}

void RadialViewMethod::ccd(const culling::Interval& interval, culling::FrameResult& out) {
  check_positions(interval.x_t0, "detect_ccd", "x_t0");
  check_positions(interval.x_t1, "detect_ccd", "x_t1");
  // The capped mesh's positions (ghost centres placed); the findings of ghost features are used
  // by the guard, then dropped (drop_ghosts, at the end).
  const skinning::Positions& x_t0 = with_ghosts(interval.x_t0, capped_x0_);
  const skinning::Positions& x_t1 = with_ghosts(interval.x_t1, capped_x1_);
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
  certify_rows(interval);

  // 1. Which components the radial-view argument may be applied to in this interval, and where
  //    in them: the intersecting pairs at the start, the uncut patches and their winding numbers.
  start_status(x_t0, out);
  const bool culling_possible = method_options_.min_separation == 0.0;
  for (std::int32_t k = 0; k < num_components; ++k) {
    culled_[at(k)] =
        culling_possible && clusters_.component_ok(k) && status_[at(k)] != Status::unknown;
    stats_.components_culled += culled_[at(k)];
    stats_.components_open += clusters_.component_ok(k) ? 0 : 1;
    stats_.components_dirty += status_[at(k)] == Status::dirty ? 1 : 0;
  }
  for (const std::uint8_t c : cut_) stats_.triangles_cut += c;

  // 2. Swept volumes of the interval, local hierarchies, then the global one over their roots.
  const auto t_refit = Clock::now();
  const double half_width = 0.5 * method_options_.min_separation;
  // No edge volumes: the feature stage forms them from the vertices'. Without a contact distance
  // it reads the positions at both ends instead, and no vertex volumes are held: the triangles'
  // come from their corners directly (as in `bvh`).
  if (culling::feature_stage_tests_ends(method_options_.min_separation)) {
    bounds_.swept_triangles(topology_, x_t0, x_t1);
  } else {
    culling::swept_vertex_bounds<3>(x_t0, x_t1, half_width, bounds_.vertices);
    bounds_.derive(topology_, /*with_edges=*/false);
  }
  // The unmasked pair traversals test node pairs in the relative motion too when the interval
  // moves enough for it to prune (docs/culling.md "Relative boxes at the nodes").
  const bool node_relative =
      options_.relative_aabb &&
      culling::motion_scale(topology_, x_t0, x_t1) >= culling::kNodeRelativeMotion;
  for (std::int32_t a = 0; a < clusters_.num_atomic(); ++a) {
    auto& local = clusters_.local_bvh(a);
    if (local.empty()) {
      cluster_bounds_[at(a)] = culling::Aabb::empty();
      continue;
    }
    const bool ends_tested = culling::feature_stage_tests_ends(method_options_.min_separation);
    if (node_relative && ends_tested) {
      // The swept volumes, the nodes' end boxes and the slots' (docs/culling.md "Apart at both
      // ends in the leaves"): on an interval that moves this much, many pairs the swept volumes
      // pass lie apart at both ends. All from one gather of the corners' positions (no
      // per-vertex end boxes held: 64 bytes a vertex), the swept ones as the union of the ends'.
      local.refit_swept_and_ends(topology_.welded_triangles(), x_t0, x_t1, true);
    } else {
      local.refit(bounds_.triangles);
      if (node_relative) {
        local.refit_end_boxes(topology_.welded_triangles(), x_t0, x_t1, half_width, ends_tested);
      }
    }
    cluster_bounds_[at(a)] = local.root_bounds();
  }
  clusters_.global_bvh().refit(cluster_bounds_);
  if (filters_pairs()) relative_filter_.prepare(topology_, x_t0, x_t1);
  const auto t_patches = Clock::now();
  // 1'. The patches' winding numbers: their rays gather triangles through the refit hierarchies.
  classify_patches(x_t0);
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
  (void)traverse(half_width, out);
  blocks_.finish();
  stats_.blocks += blocks_.blocks();
  const double test_us = blocks_.test_us();
  const auto t_escalate = Clock::now();

  // 6. The argument guarantees the first contact at a pair of skippable triangles, not the ones
  //    after it: wherever a contact touches a skippable triangle, test its skipped pairs too,
  //    round after round, until no new contact touches one (docs/radial-view.md, "The local
  //    guard").
  double escalate_traverse_us = 0.0;
  double escalate_elementary_us = 0.0;
  if (options_.guard) {
    std::fill(escalated_.begin(), escalated_.end(), 0);
    std::fill(component_escalated_.begin(), component_escalated_.end(), 0);
    frontier_.clear();
    for (std::int32_t round = 1;; ++round) {
      // New contacts are merged into the sorted list wherever they sort: look at all of them
      // (marking is idempotent).
      escalate(out, round);
      if (frontier_.empty()) break;
      ++stats_.escalation_rounds;
      const auto e0 = Clock::now();
      const std::size_t before = out.contacts.size();
      blocks_.start_ccd(
          topology_, bounds_, x_t0, x_t1, tests_, method_options_.accuracy, ccd_options_, out);
      stats_.skipped_pairs_retested += retest_frontier(round, half_width, out);
      blocks_.finish();
      stats_.blocks += blocks_.blocks();
      stats_.escalation_contacts += static_cast<std::int64_t>(out.contacts.size() - before);
      // The new contacts are sorted; one canonical order for the whole interval (in place).
      std::inplace_merge(
          out.contacts.begin(), out.contacts.begin() + static_cast<std::ptrdiff_t>(before),
          out.contacts.end(),
          [](const culling::CcdContact& a, const culling::CcdContact& b) { return a.before(b); });
      const auto e1 = Clock::now();
      escalate_elementary_us += blocks_.test_us();
      escalate_traverse_us += micros(e0, e1) - blocks_.test_us();
      frontier_.clear();
      if (before == out.contacts.size()) break;
    }
  }

  // 7. The intersecting pairs at the interval's end, for the next interval's start: this one's
  //    start pairs updated from its contacts (exact when nothing is missed: conservative and
  //    exact accuracy; `fast` guarantees nothing, and a contact it misses may leave a pair out
  //    here too — a full DCD per interval would cost more than the fast kernels save).
  if (options_.guard && culling_possible) {
    scratch_result_.clear();
    updater_.update(start_pairs_, out.contacts, x_t1, tests_, scratch_result_);
    carry_pairs_.assign(scratch_result_.dcd_pairs.begin(), scratch_result_.dcd_pairs.end());
    carry_x_ = x_t1;
    has_carry_ = true;
    out.counters.tt_tests += scratch_result_.counters.tt_tests;
    escalate_elementary_us += scratch_result_.times.elementary_us;
  }
  stats_.ghost_loops = ghosts_ ? ghosts_->num_loops() : 0;
  drop_ghosts(out);
  const auto t_end = Clock::now();

  // Counters and stage times (paper Table 3: RV-update = classify + merge).
  out.counters.atomic_clusters += clusters_.num_atomic();
  out.counters.mega_clusters += classes_.num_mega();
  out.counters.h_minus += classes_.h_minus;
  out.counters.h_uncertain += classes_.h_uncertain;
  out.times.refit_us += micros(t_refit, t_patches);
  out.times.classify_us +=
      classes_.classify_us + micros(t_masks, t_traverse) + micros(t_patches, t_classify);
  out.times.merge_us += classes_.merge_us;
  out.times.traverse_us += micros(t_traverse, t_escalate) - test_us + escalate_traverse_us;
  out.times.elementary_us += test_us + escalate_elementary_us;
  (void)t_end;
}

}  // namespace skelcd::clustering
