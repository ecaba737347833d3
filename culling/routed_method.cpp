// `auto`: per-component routing. Open components → a cone method over their triangles; closed
// components → the best registered closed-part method (`dynamic`) or the `bvh` fallback; the pairs
// between the two groups → a BVH pair traversal; one feature and elementary stage for what this
// class traverses itself, and the groups' contacts merged, de-duplicated and sorted.
#include "culling/routed_method.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/cones_method_base.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/dual_cone.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/method_registry.hpp"
#include "culling/normal_cone.hpp"
#include "culling/pair_blocks.hpp"
#include "culling/pair_sort.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/sieved_dcd.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace {

inline std::size_t sz(std::int32_t i) { return static_cast<std::size_t>(i); }

bool is_cone_method(std::string_view name) {
  return name == "enhanced-dual-cone" || name == "normal-cone" || name == "dual-cone";
}

/// A whole-mesh method of the registry for the closed group (built on the mesh with its open
/// triangles excluded), as opposed to the cone methods, which take a triangle subset, and `bvh`,
/// which this class traverses itself.
bool whole_mesh_method(std::string_view name) {
  return !is_cone_method(name) && name != "bvh" && name != "auto" && find_method(name) != nullptr;
}

/// The method of the closed group: as asked, else the best registered closed-part method whose
/// needs the options meet, else the fallback.
std::string closed_method_name(const MethodOptions& options, const RoutingOptions& routing) {
  if (!routing.closed_method.empty()) return routing.closed_method;
  const MethodInfo* best = nullptr;
  for (const MethodInfo* m : registered_methods()) {
    if (m->route != RouteKind::closed || !needs_met(m->needs, options)) continue;
    if (best == nullptr || m->route_priority > best->route_priority) best = m;
  }
  return best != nullptr ? best->name : std::string(kClosedFallbackMethod);
}

void check_group_method(const std::string& name, bool open) {
  if (is_cone_method(name) || name == "bvh") return;
  if (!open && whole_mesh_method(name)) return;
  throw InvalidInput(
      "culling::make_method(auto): '" + name + "' cannot take the " + (open ? "open" : "closed") +
      " components (use enhanced-dual-cone, normal-cone, dual-cone or bvh" +
      (open ? ")" : ", or a registered method)"));
}

/// Edge-connected components and whether each is closed (every edge has exactly two triangles):
/// Topology::components when filled, else computed from the edge → face incidence.
std::vector<skinning::Component> components_of(const skinning::Topology& topology) {
  if (!topology.components.empty()) return topology.components;
  const auto nf = static_cast<std::size_t>(topology.welded_triangles.rows());
  std::vector<std::int32_t> root(nf);
  std::iota(root.begin(), root.end(), 0);
  auto find = [&root](std::int32_t f) {
    while (root[sz(f)] != f) f = root[sz(f)] = root[sz(root[sz(f)])];
    return f;
  };
  const std::size_t ne =
      topology.edge_face_offsets.empty() ? 0 : topology.edge_face_offsets.size() - 1;
  std::vector<std::uint8_t> open_face(nf, 0);
  for (std::size_t e = 0; e < ne; ++e) {
    const auto b = topology.edge_face_offsets[e];
    const auto c = topology.edge_face_offsets[e + 1];
    for (auto k = b + 1; k < c; ++k) {
      const std::int32_t r0 = find(topology.edge_faces[sz(b)]);
      const std::int32_t r1 = find(topology.edge_faces[sz(k)]);
      if (r0 != r1) root[sz(r1)] = r0;
    }
    if (c - b != 2) {
      for (auto k = b; k < c; ++k) open_face[sz(topology.edge_faces[sz(k)])] = 1;
    }
  }
  std::vector<skinning::Component> out;
  std::vector<std::int32_t> index(nf, -1);
  for (std::size_t f = 0; f < nf; ++f) {
    const auto r = sz(find(static_cast<std::int32_t>(f)));
    if (index[r] < 0) {
      index[r] = static_cast<std::int32_t>(out.size());
      out.emplace_back();
      out.back().closed = true;
    }
    auto& c = out[sz(index[r])];
    c.faces.push_back(static_cast<std::int32_t>(f));
    if (open_face[f] != 0) c.closed = false;
  }
  return out;
}

/// Whether a route goes with the closed group: closed, every hole one the closed method caps
/// itself (ComponentRoute::capped), or a small open part (ComponentRoute::small).
bool in_closed_group(const ComponentRoute& r) { return r.closed || r.capped || r.small; }

/// Component c (of topology.components) has every hole capped by `info`'s method: a 1 per
/// component of closing_loops (none when the method caps no holes or the topology has no
/// components of its own).
std::vector<std::uint8_t> capped_components(
    const skinning::Topology& topology, std::size_t num_components, const MethodInfo* info) {
  std::vector<std::uint8_t> capped(num_components, 0);
  if (info == nullptr || info->closes_holes_up_to <= 0 || topology.components.empty() ||
      topology.face_component.empty()) {
    return capped;
  }
  for (const auto& loop : skinning::closing_loops(
           topology, info->closes_holes_up_to, info->closes_holes_triangles_per_side)) {
    capped[sz(topology.face_component[sz(loop.front().face)])] = 1;
  }
  return capped;
}

/// The registered closed-part method of highest priority, whatever its needs: the one whose hole
/// capping the all_closed_method rule asks about (it is the closed method whenever its needs are
/// met, and the rule is decided before a segmentation exists).
const MethodInfo* first_closed_method() {
  const MethodInfo* best = nullptr;
  for (const MethodInfo* m : registered_methods()) {
    if (m->route != RouteKind::closed) continue;
    if (best == nullptr || m->route_priority > best->route_priority) best = m;
  }
  return best;
}

/// Whether RoutingOptions::all_closed_method's rule is asked at all: it is set, `closed_method`
/// is not named, and there are components.
bool all_closed_rule_asked(
    const std::vector<skinning::Component>& components, const RoutingOptions& routing) {
  return !routing.all_closed_method.empty() && routing.closed_method.empty() && !components.empty();
}

/// RoutingOptions::all_closed_method's rule: it is asked (all_closed_rule_asked), the mesh has
/// fewer triangles than all_closed_below_triangles (when that is set), and every component is
/// closed, under min_open_triangles, or open only at holes the highest-priority closed-part
/// method caps (first_closed_method) — whether that method's needs are met or not.
/// `capped_by_first`: capped_components for first_closed_method().
bool whole_to_all_closed_method(
    const std::vector<skinning::Component>& components,
    const RoutingOptions& routing,
    const std::vector<std::uint8_t>& capped_by_first) {
  if (!all_closed_rule_asked(components, routing)) return false;
  if (routing.all_closed_below_triangles > 0) {
    std::int64_t triangles = 0;
    for (const auto& component : components) {
      triangles += static_cast<std::int64_t>(component.faces.size());
    }
    if (triangles >= routing.all_closed_below_triangles) return false;
  }
  for (std::size_t c = 0; c < components.size(); ++c) {
    if (!components[c].closed && capped_by_first[c] == 0 &&
        static_cast<std::int32_t>(components[c].faces.size()) >= routing.min_open_triangles) {
      return false;
    }
  }
  return true;
}

/// route_components' routes with what they were made from: the components, and whether the
/// all_closed_method rule sends the whole mesh to one method (whole_to_all_closed_method).
struct RoutePlan {
  std::vector<skinning::Component> components;
  std::vector<ComponentRoute> routes;
  bool whole = false;
};

/// route_components, keeping the components and the rule's decision (each hole-capping search,
/// skinning::closing_loops, made once: `auto`'s constructor needs all three).
RoutePlan plan_routes(
    const skinning::Topology& topology,
    const MethodOptions& options,
    const RoutingOptions& routing);

/// A copy of `mesh` whose parts are split into (part, open) and (part, closed), with every pair
/// that involves an open triangle excluded on top of the mesh's own exclusions: what a whole-mesh
/// method (an extension's `dynamic`) is given so that it tests only closed-closed pairs.
skinning::Mesh closed_only_mesh(
    const skinning::Mesh& mesh, const std::vector<std::uint8_t>& open_face) {
  skinning::Mesh m = mesh;
  const std::int32_t parts = std::max<std::int32_t>(1, mesh.num_parts());
  auto refined = [](std::int32_t p, bool open) { return 2 * p + (open ? 1 : 0); };
  m.part_names.clear();
  for (std::int32_t p = 0; p < parts; ++p) {
    const std::string base = p < mesh.num_parts() ? mesh.part_names[sz(p)] : "mesh";
    m.part_names.push_back(base + "/closed");
    m.part_names.push_back(base + "/open");
  }
  const auto nf = static_cast<std::size_t>(mesh.num_triangles());
  m.face_part.resize(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::int32_t p = mesh.face_part.empty() ? 0 : mesh.face_part[f];
    m.face_part[f] = refined(p, open_face[f] != 0);
  }
  m.vertex_part.assign(static_cast<std::size_t>(mesh.num_vertices()), 0);
  for (std::size_t f = 0; f < nf; ++f) {
    for (Eigen::Index k = 0; k < 3; ++k) {
      m.vertex_part[sz(mesh.triangles(static_cast<Eigen::Index>(f), k))] = m.face_part[f];
    }
  }
  m.excluded_part_pairs.clear();
  for (const auto& [a, b] : mesh.excluded_part_pairs) {
    for (const bool oa : {false, true}) {
      for (const bool ob : {false, true}) {
        const std::int32_t x = refined(a, oa);
        const std::int32_t y = refined(b, ob);
        m.excluded_part_pairs.emplace_back(std::min(x, y), std::max(x, y));
      }
    }
  }
  for (std::int32_t p = 0; p < parts; ++p) {
    for (std::int32_t q = 0; q < 2 * parts; ++q) {
      const std::int32_t o = refined(p, true);
      m.excluded_part_pairs.emplace_back(std::min(o, q), std::max(o, q));
    }
  }
  return m;
}

class AutoMethod final : public detail::MethodBase {
 public:
  /// `plan`: plan_routes(topology, options, routing), made by make_routed_method.
  AutoMethod(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      const RoutingOptions& routing,
      RoutePlan plan)
      : MethodBase("auto", mesh, topology, options),
        blocks_(
            options.block_pairs,
            block_reserve(options.block_pairs, options.bvh.leaf_size, topology_.num_triangles())) {
    routes_ = std::move(plan.routes);
    const auto& components = plan.components;
    // The whole mesh to all_closed_method: one group, whatever each part would have been (an
    // open part capped only by a closed method whose needs are not met would otherwise be built
    // a cone group of its own, only to be dropped).
    const bool whole = plan.whole;
    const auto nf = static_cast<std::size_t>(topology_.num_triangles());
    std::vector<std::uint8_t> open_face(nf, 0);
    for (std::size_t c = 0; c < components.size(); ++c) {
      const auto& r = routes_[c];
      const bool closed = whole || in_closed_group(r);
      for (const std::int32_t f : components[c].faces) {
        (closed ? closed_triangles_ : open_triangles_).push_back(f);
        open_face[sz(f)] = closed ? 0 : 1;
      }
    }
    std::sort(open_triangles_.begin(), open_triangles_.end());
    std::sort(closed_triangles_.begin(), closed_triangles_.end());

    // Welded rest positions for the groups' hierarchies.
    skinning::Positions rest(topology.num_welded_vertices(), 3);
    for (std::int32_t w = 0; w < topology.num_welded_vertices(); ++w) {
      rest.row(w) = mesh.rest_positions.row(topology.representative_vertex[sz(w)]);
    }
    const std::string open_name = routing.open_method;
    // The closed group's method: the routes' (RoutingOptions::all_closed_method when every
    // component goes with the closed ones), else the one asked for or the best registered.
    const auto closed_route = std::find_if(routes_.begin(), routes_.end(), in_closed_group);
    const std::string closed_name =
        closed_route != routes_.end() ? closed_route->method : closed_method_name(options, routing);
    if (!open_triangles_.empty()) {
      open_method_ = make_group_method(open_name, mesh, topology, options, open_triangles_);
    }
    if (!closed_triangles_.empty()) {
      if (whole_mesh_method(closed_name)) {
        // A whole-mesh method (`dynamic`): the open triangles are excluded — when there are any
        // (the exclusions would otherwise cost it the culling of clusters that span parts).
        closed_method_ = make_method(
            closed_name,
            open_triangles_.empty() ? mesh : closed_only_mesh(mesh, open_face),
            topology,
            options);
      } else {
        closed_method_ = make_group_method(closed_name, mesh, topology, options, closed_triangles_);
      }
    }
    // A group's hierarchy is traversed here when `bvh` tests its pairs (no method of its own), for
    // the pairs between the two groups, or for a cone group's query that its cones do not answer
    // (choose_traversals). A cone method's group already has one, over the same triangles, split
    // at the same rest pose, refit by that method's own query just before ours or by its
    // refit_static / refit_swept, and the volumes of every feature of the mesh: those are read, not
    // copied (bounded memory, docs/culling.md). Hierarchies built here are traversed on their wide
    // copy only (culling/traversal.hpp): no binary node volumes.
    const bool both = !open_triangles_.empty() && !closed_triangles_.empty();
    open_cone_ = dynamic_cast<detail::ConeMethodBase*>(open_method_.get());
    closed_cone_ = dynamic_cast<detail::ConeMethodBase*>(closed_method_.get());
    choose_traversals(rest, routing);
    drop_idle_cones();
    if (to_whole_bvh(mesh, topology, options)) return;  // nothing traversed here
    const detail::ConeMethodBase* open_cone = open_cone_;
    const detail::ConeMethodBase* closed_cone = closed_cone_;
    BvhOptions own_bvh = options.bvh;
    own_bvh.node_volumes = false;
    if (!open_triangles_.empty() && (open_method_ == nullptr || both)) {
      if (open_cone != nullptr) {
        open_hierarchy_ = &open_cone->hierarchy();
      } else {
        open_bvh_ = AabbBvh(topology_.welded_triangles(), rest, open_triangles_, own_bvh);
        open_hierarchy_ = &open_bvh_;
      }
    }
    if (!closed_triangles_.empty() && (closed_method_ == nullptr || both)) {
      if (closed_cone != nullptr) {
        closed_hierarchy_ = &closed_cone->hierarchy();
      } else {
        closed_bvh_ = AabbBvh(topology_.welded_triangles(), rest, closed_triangles_, own_bvh);
        closed_hierarchy_ = &closed_bvh_;
      }
    }
    // The volumes every traversal here reads: a cone group's, refit by its query or by
    // refit_static / refit_swept (a cone group traversed here without its cones), else our own.
    const detail::ConeMethodBase* cone = open_cone != nullptr ? open_cone : closed_cone;
    if (cone != nullptr) bounds_ = &cone->feature_bounds();
    if (open_hierarchy_ == nullptr && closed_hierarchy_ == nullptr)
      return;  // nothing traversed here but maybe a cone group without its cones
    if (cone == nullptr) {
      if (!feature_stage_tests_ends(options_.min_separation))
        own_bounds_.vertices.reserve(static_cast<std::size_t>(topology_.num_vertices()));
      own_bounds_.triangles.reserve(nf);
      bounds_ = &own_bounds_;
    }
    const int depth = std::max(
        open_hierarchy_ != nullptr ? open_hierarchy_->depth() : 0,
        closed_hierarchy_ != nullptr ? closed_hierarchy_->depth() : 0);
    scratch_.reserve(static_cast<std::size_t>(4 * depth + 8));
  }

  /// The traversals of each cone group, chosen at rest (RoutingOptions::dcd_cone_share,
  /// ccd_cone_share): the cones' for a query when their traversal produces fewer than 1/share of
  /// the pairs whose volumes overlap (what the plain traversal of `bvh` produces; for DCD emitted
  /// or settled). At rest, not at a query: the choice, and so every counter, is then the same
  /// whichever worker meets which instant first.
  void choose_traversals(const skinning::Positions& rest, const RoutingOptions& routing) {
    std::vector<TrianglePair> pairs;
    for (std::size_t g = 0; g < 2; ++g) {
      detail::ConeMethodBase* cone = g == 0 ? open_cone_ : closed_cone_;
      if (cone == nullptr || cone->hierarchy().empty()) continue;
      if (routing.dcd_cone_share == 0 && routing.ccd_cone_share == 0) continue;
      cone->refit_static(rest);
      const AabbBvh& h = cone->hierarchy();
      const std::span<const Aabb> tri(cone->feature_bounds().triangles);
      constexpr std::size_t kInstallment = 4096;
      const auto bucket = static_cast<std::size_t>(bucket_size(h.leaf_size()));
      pairs.reserve(kInstallment + bucket * bucket);  // an installment passes by a bucket pair's
      start_self_traversal<3>(h, scratch_);
      std::int64_t overlapping = 0;
      std::int64_t bv_tests = 0;
      for (bool done = false; !done;) {
        pairs.clear();
        done = self_traverse_some<3>(h, tri, scratch_, pairs, bv_tests, kInstallment);
        overlapping += static_cast<std::int64_t>(pairs.size());
      }
      // cones < overlapping / share  <=>  cones < ceil(overlapping / share) (integers); 0 for a
      // share of 0 (never).
      const auto cap_of = [overlapping](std::int64_t share) -> std::int64_t {
        return share == 0 ? 0 : overlapping / share + (overlapping % share != 0 ? 1 : 0);
      };
      const std::int64_t dcd_cap = cap_of(routing.dcd_cone_share);
      const std::int64_t ccd_cap = cap_of(routing.ccd_cone_share);
      const std::int64_t cap = std::max(dcd_cap, ccd_cap);
      // A lower bound first, without the contours: when even it reaches the larger cap, the cones
      // pay for neither query (drop_idle_cones frees the method before it builds its contours:
      // about 100 ms of `auto`'s set-up on the cloth-ball step). Else the count proper.
      const std::int64_t cones =
          cone->count_dcd_pairs_at_least(rest, cap) >= cap ? cap : cone->count_dcd_pairs(rest, cap);
      dcd_by_cones_[g] = cones < dcd_cap;
      ccd_by_cones_[g] = cones < ccd_cap;
    }
  }

  /// A cone group whose cones pay for neither query (choose_traversals) would only lend this
  /// method its hierarchy, split at the median as the cone tests assume: the group becomes a `bvh`
  /// group instead (surface-area splits; its routes say `bvh`), and the cone method is freed. On
  /// the cloth steps, whose sheets' cones cull half of the overlapping pairs at rest, `auto` cost
  /// 1.07-1.12x `bvh` per interval before (docs/dual-cone.md "`auto`: routing").
  void drop_idle_cones() {
    for (std::size_t g = 0; g < 2; ++g) {
      detail::ConeMethodBase*& cone = g == 0 ? open_cone_ : closed_cone_;
      if (cone == nullptr || dcd_by_cones_[g] || ccd_by_cones_[g]) continue;
      cone = nullptr;
      dropped_cones_ = true;
      (g == 0 ? open_method_ : closed_method_).reset();
      for (auto& r : routes_) {
        if (in_closed_group(r) == (g == 1)) r.method = "bvh";
      }
    }
  }

  /// When no group has a method of its own (every group `bvh`) and one group holds the mesh, or
  /// the other became `bvh` by drop_idle_cones, the `bvh` method answers for the whole mesh (its
  /// DCD sieve and CCD fans, no traversal between groups), on this method's FeatureTopology, and
  /// this returns true. Two groups named `bvh` by the routing options stay traversed here.
  bool to_whole_bvh(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options) {
    const bool one_group = open_triangles_.empty() || closed_triangles_.empty();
    if (open_method_ != nullptr || closed_method_ != nullptr || !(one_group || dropped_cones_)) {
      return false;
    }
    for (auto& r : routes_) r.method = "bvh";
    MethodOptions shared = options;
    shared.features = features_;
    // `bvh` with the rigid rows, when the runner gave them (docs/culling.md "Rigid rows").
    closed_method_ = detail::make_bvh_method<3>(
        "bvh", mesh, topology, shared, /*relative_pairs=*/false, /*rigid_rows=*/true);
    return true;
  }

  /// What this method holds for its own traversal (routed_structures).
  [[nodiscard]] RoutedStructures structures() const {
    RoutedStructures r;
    for (const AabbBvh* h : {open_hierarchy_, closed_hierarchy_}) {
      if (h == nullptr) continue;
      ++(h == &open_bvh_ || h == &closed_bvh_ ? r.own_hierarchies : r.shared_hierarchies);
    }
    r.own_feature_bounds = !traverses_nothing() && bounds_ == &own_bounds_;
    // Feature topologies held by this method and its culling-module group methods.
    std::vector<const FeatureTopology*> held{features_.get()};
    for (const CullingMethod* m : {open_method_.get(), closed_method_.get()}) {
      const auto* base = dynamic_cast<const detail::MethodBase*>(m);
      if (base != nullptr &&
          std::find(held.begin(), held.end(), base->shared_features().get()) == held.end()) {
        held.push_back(base->shared_features().get());
      }
    }
    r.feature_topologies = static_cast<std::int32_t>(held.size());
    return r;
  }

  [[nodiscard]] std::span<const ComponentRoute> component_routes() const override {
    return routes_;
  }
  /// Its rows are its groups' together with the pairs between them, which keep nothing.
  [[nodiscard]] bool last_ccd_row_reusable() const override {
    return (!open_method_ || open_method_->last_ccd_row_reusable()) &&
           (!closed_method_ || closed_method_->last_ccd_row_reusable());
  }

  void dcd(const Instant& at, FrameResult& out) override {
    const skinning::Positions& x = at.x;
    check_positions(x, "detect_dcd", "x");
    // The groups that answer themselves; a cone group that does not (its DCD traversal chosen at
    // rest: docs/dual-cone.md "`auto`'s DCD") refit to x for the sieved traversal of `bvh`.
    const std::array<const AabbBvh*, 2> groups = answer_groups(
        dcd_by_cones_,
        [&](CullingMethod& m, FrameResult& r) { m.detect_dcd(at, r); },
        [&](detail::ConeMethodBase& cone) { cone.refit_static(x); },
        out);
    const bool between = traverses_between();
    if (groups[0] == nullptr && groups[1] == nullptr && !between) return;
    const auto t0 = Clock::now();
    if (bounds_ == &own_bounds_) {
      own_bounds_.static_triangles(topology_, x);
    }
    refit_groups();
    const auto t1 = Clock::now();
    // Each group's own pairs (sieved), then the pairs between the groups, tested in blocks of
    // block_pairs (bounded memory).
    blocks_.start_dcd(topology_, x, tests_, out);
    // Every cone group's volumes equal bounds_' (the whole mesh's, refit to x).
    const std::span<const Aabb> tri(bounds_->triangles);
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const AabbBvh* h = groups[g];
      if (h == nullptr || h->empty()) continue;
      sieved_self_dcd<3>(*h, tri, topology_, slots_of(g, *h), full_slots_, scratch_, blocks_, out);
    }
    if (between)
      traverse_between(out.counters.bv_tests, [](std::vector<TrianglePair>&, std::size_t) {});
    blocks_.finish();
    const auto t2 = Clock::now();
    // Merge: sorted, each pair once.
    sort_pairs(out.dcd_pairs);
    out.dcd_pairs.erase(
        std::unique(out.dcd_pairs.begin(), out.dcd_pairs.end()), out.dcd_pairs.end());
    out.counters.dcd_pairs = static_cast<std::int64_t>(out.dcd_pairs.size());
    out.times.refit_us += micros(t0, t1);
    out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
    out.times.elementary_us += blocks_.test_us();
  }

  void ccd(const Interval& interval, FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    check_positions(x_t0, "detect_ccd", "x_t0");
    check_positions(x_t1, "detect_ccd", "x_t1");
    // The groups that answer themselves; a cone group that does not (its CCD traversal chosen at
    // rest: docs/dual-cone.md "`auto`'s CCD") refit to the interval's swept volumes for the plain
    // traversal of `bvh`.
    const std::array<const AabbBvh*, 2> groups = answer_groups(
        ccd_by_cones_,
        [&](CullingMethod& m, FrameResult& r) { m.detect_ccd(interval, r); },
        [&](detail::ConeMethodBase& cone) { cone.refit_swept(x_t0, x_t1); },
        out);
    const bool between = traverses_between();
    if (groups[0] == nullptr && groups[1] == nullptr && !between) return;
    const auto t0 = Clock::now();
    if (bounds_ == &own_bounds_) {
      if (feature_stage_tests_ends(options_.min_separation)) {
        own_bounds_.swept_triangles(topology_, x_t0, x_t1);  // as `bvh`: no vertex volumes held
      } else {
        swept_vertex_bounds<3>(x_t0, x_t1, 0.5 * options_.min_separation, own_bounds_.vertices);
        own_bounds_.derive(topology_, /*with_edges=*/false);
      }
    }
    refit_groups();
    const auto t1 = Clock::now();
    // Each group's own pairs, then the pairs between the groups, tested in blocks of block_pairs
    // (bounded memory).
    blocks_.start_ccd(
        topology_, *bounds_, x_t0, x_t1, tests_, options_.accuracy, ccd_options_, out);
    const std::span<const Aabb> tri(bounds_->triangles);
    // With a contact distance the pairs this method traverses go through the relative filter when
    // its trial says it pays, as `kdop`'s do (docs/culling.md "Relative boxes in `kdop`"): one
    // trial per query. Without one the feature stage makes that test (candidates.hpp).
    const bool filter_pairs = !feature_stage_tests_ends(options_.min_separation);
    if (filter_pairs) relative_.start(RelativePairTrial::trial_pairs(topology_.num_triangles()));
    const auto filter = [&](std::vector<TrianglePair>& pairs, std::size_t first) {
      if (filter_pairs) {
        relative_.filter(topology_, x_t0, x_t1, 0.5 * options_.min_separation, pairs, first);
      }
    };
    // Pairs that share a vertex whose fan is certified over the interval are settled where the
    // traversal meets them, as `bvh` does (not with part exclusions, whose CCD rule is per
    // feature): the fans are certified once per query, each group's slots built on first need.
    std::span<const std::uint8_t> certified;
    bool certify = !topology_.has_exclusions();
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const AabbBvh* h = groups[g];
      if (h == nullptr || h->empty()) continue;
      if (certify) {
        certified = blocks_.certify_interval_fans();
        certify = false;
      }
      FanSieve sieve = fan_sieve(slots_of(g, *h), certified, full_slots_, topology_);
      FanSieve* const sieving = sieve.certified.empty() ? nullptr : &sieve;
      start_self_traversal<3>(*h, scratch_);
      blocks_.drain_overlapped([&](std::vector<TrianglePair>& pairs, std::size_t max_pairs) {
        const std::size_t first = pairs.size();
        const bool done = self_traverse_some<3>(
            *h, tri, scratch_, pairs, out.counters.bv_tests, max_pairs, sieving);
        filter(pairs, first);
        return done;
      });
      out.counters.candidate_pairs += sieve.settled;
    }
    if (between) traverse_between(out.counters.bv_tests, filter);
    blocks_.finish();
    const auto t2 = Clock::now();
    // Merge: canonical order, each pair once (a vertex shared by an open and a closed component
    // can reach one feature pair from two groups), earliest time of impact kept.
    auto& c = out.contacts;
    std::sort(c.begin(), c.end(), [](const CcdContact& a, const CcdContact& b) {
      return a.before(b) || (a.same_pair(b) && a.toi_lower < b.toi_lower);
    });
    c.erase(
        std::unique(
            c.begin(),
            c.end(),
            [](const CcdContact& a, const CcdContact& b) { return a.same_pair(b); }),
        c.end());
    out.counters.vf_contacts = std::count_if(
        c.begin(), c.end(), [](const CcdContact& x) { return x.kind == CcdContact::Kind::vf; });
    out.counters.ee_contacts = static_cast<std::int64_t>(c.size()) - out.counters.vf_contacts;
    out.times.refit_us += micros(t0, t1);
    out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
    out.times.elementary_us += blocks_.test_us();
  }

 private:
  /// A cone group method over `triangles`, on this method's own FeatureTopology (the same mesh and
  /// topology: shared, not built again); null for `bvh`.
  [[nodiscard]] std::unique_ptr<CullingMethod> make_group_method(
      const std::string& name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      const std::vector<std::int32_t>& triangles) const {
    if (name == "enhanced-dual-cone") {
      // The simple top-down scheme: measured faster than Algorithm 3's descent on most scenes of
      // bench/culling/bm_cones (docs/benchmarks.md, "## dual-cone"); same contacts.
      return make_enhanced_dual_cone_method(
          mesh,
          topology,
          options,
          {.grandchildren_descent = false, .triangles = triangles, .features = features_});
    }
    if (name == "normal-cone") {
      return make_normal_cone_method(mesh, topology, options, triangles, features_);
    }
    if (name == "dual-cone") {
      return make_dual_cone_method(mesh, topology, options, triangles, features_);
    }
    return nullptr;  // `bvh`: traversed here
  }

  /// One group method's query, its findings and counters added to out.
  template <class Call>
  void run_group(CullingMethod& m, Call call, FrameResult& out) {
    sub_.clear();
    call(m, sub_);
    out.counters += sub_.counters;
    out.times += sub_.times;
    out.contacts.insert(out.contacts.end(), sub_.contacts.begin(), sub_.contacts.end());
    out.dcd_pairs.insert(out.dcd_pairs.end(), sub_.dcd_pairs.begin(), sub_.dcd_pairs.end());
  }

  /// Runs the query `call` of the groups that answer for themselves — a whole-mesh closed method
  /// (`dynamic`), a cone group whose cones were chosen for this query (`by_cones`) — adding their
  /// findings to out, and refits (`refit`) the other cone groups. Returns per group (open, closed)
  /// the hierarchy whose own pairs this method traverses: such a cone group's, or the one built
  /// here when `bvh` tests the group; null otherwise.
  template <class Call, class Refit>
  std::array<const AabbBvh*, 2> answer_groups(
      const std::array<bool, 2>& by_cones, Call call, Refit refit, FrameResult& out) {
    if (closed_method_ != nullptr && closed_cone_ == nullptr) run_group(*closed_method_, call, out);
    std::array<const AabbBvh*, 2> groups{};
    for (std::size_t g = 0; g < 2; ++g) {
      detail::ConeMethodBase* cone = g == 0 ? open_cone_ : closed_cone_;
      const bool own = (g == 0 ? open_method_ : closed_method_) == nullptr;
      if (cone != nullptr && by_cones[g]) {
        run_group(*cone, call, out);
      } else if (cone != nullptr) {
        refit(*cone);
        groups[g] = &cone->hierarchy();
      } else if (own) {
        groups[g] = g == 0 ? open_hierarchy_ : closed_hierarchy_;  // null for an empty group
      }
    }
    return groups;
  }

  /// The two groups are both here with triangles: their pairs are traversed here.
  [[nodiscard]] bool traverses_between() const {
    return open_hierarchy_ != nullptr && closed_hierarchy_ != nullptr &&
           !open_hierarchy_->empty() && !closed_hierarchy_->empty();
  }

  [[nodiscard]] bool traverses_nothing() const {
    return open_hierarchy_ == nullptr && closed_hierarchy_ == nullptr;
  }

  /// Refits the hierarchies built here (a cone method refits its own in its query).
  void refit_groups() {
    if (!open_bvh_.empty()) open_bvh_.refit(bounds_->triangles);
    if (!closed_bvh_.empty()) closed_bvh_.refit(bounds_->triangles);
  }

  /// The pairs between the two groups (both hierarchies refit), into blocks_ in installments,
  /// each installment from pairs[first] on passed to filter(pairs, first) (the CCD's relative
  /// filter; nothing for a DCD).
  template <typename Filter>
  void traverse_between(std::int64_t& bv_tests, Filter&& filter) {
    const std::span<const Aabb> tri(bounds_->triangles);
    start_pair_traversal<3>(*open_hierarchy_, *closed_hierarchy_, scratch_);
    blocks_.drain_overlapped([&](std::vector<TrianglePair>& pairs, std::size_t max_pairs) {
      const std::size_t first = pairs.size();
      const bool done = pair_traverse_some<3>(
          *open_hierarchy_, tri, *closed_hierarchy_, tri, scratch_, pairs, bv_tests, max_pairs);
      filter(pairs, first);
      return done;
    });
  }

  std::vector<ComponentRoute> routes_;
  std::vector<std::int32_t> open_triangles_;
  std::vector<std::int32_t> closed_triangles_;
  /// The CCD's relative filter over the pairs traversed here, decided per query by its trial.
  RelativePairTrial relative_;
  AabbBvh open_bvh_;  ///< built here when the open group has no cone method
  AabbBvh closed_bvh_;
  std::unique_ptr<CullingMethod> open_method_;
  std::unique_ptr<CullingMethod> closed_method_;
  /// The group methods that are cone methods (null otherwise): their hierarchies are traversed
  /// here for a DCD (dcd).
  detail::ConeMethodBase* open_cone_ = nullptr;
  detail::ConeMethodBase* closed_cone_ = nullptr;
  /// The slots' corners and windows of group g's hierarchy (open, closed), for the fan sieves of
  /// both queries: built by the first query that traverses the group here (#F x 24 bytes).
  SlotAdjacency& slots_of(std::size_t g, const AabbBvh& h) {
    SlotAdjacency& slots = group_slots_[g];
    if (slots.corners.size() != h.triangle_order().size()) {
      slots = SlotAdjacency(topology_, h.triangle_order());
    }
    return slots;
  }

  std::array<SlotAdjacency, 2> group_slots_;
  bool dropped_cones_ = false;            ///< drop_idle_cones made a cone group a `bvh` group
  std::vector<std::uint8_t> full_slots_;  ///< the sieves' per-slot buffer
  /// Per group (open, closed): a cone group's DCD, CCD takes its method's cone-culled traversal
  /// (choose_traversals).
  std::array<bool, 2> dcd_by_cones_{};
  std::array<bool, 2> ccd_by_cones_{};
  /// The groups' hierarchies this method traverses (null: not traversed here): its own, or a
  /// cone group method's.
  const AabbBvh* open_hierarchy_ = nullptr;
  const AabbBvh* closed_hierarchy_ = nullptr;
  FeatureBounds<3> own_bounds_;  ///< refit here only when no group method is a cone method
  const FeatureBounds<3>* bounds_ = &own_bounds_;
  TraversalScratch scratch_;
  PairBlocks<3> blocks_;
  FrameResult sub_;
};

}  // namespace

namespace {

RoutePlan plan_routes(
    const skinning::Topology& topology,
    const MethodOptions& options,
    const RoutingOptions& routing) {
  RoutePlan plan;
  const std::string closed_name = closed_method_name(options, routing);
  check_group_method(routing.open_method, /*open=*/true);
  check_group_method(closed_name, /*open=*/false);
  plan.components = components_of(topology);
  const auto& components = plan.components;
  // Open components whose every hole the closed method closes itself go with the closed ones.
  const MethodInfo* closed_info = find_method(closed_name);
  const std::vector<std::uint8_t> capped =
      capped_components(topology, components.size(), closed_info);
  auto& routes = plan.routes;
  routes.reserve(components.size());
  for (std::size_t c = 0; c < components.size(); ++c) {
    ComponentRoute r;
    r.component = static_cast<std::int32_t>(c);
    r.part = components[c].part;
    r.closed = components[c].closed;
    r.capped = capped[c] != 0;
    r.num_triangles = static_cast<std::int32_t>(components[c].faces.size());
    r.small = !r.closed && !r.capped && r.num_triangles < routing.min_open_triangles;
    r.method = r.closed || r.capped || r.small ? closed_name : routing.open_method;
    routes.push_back(std::move(r));
  }
  if (all_closed_rule_asked(components, routing)) {
    // The rule's capping: the same loops when its method is the closed one.
    const MethodInfo* first = first_closed_method();
    plan.whole = whole_to_all_closed_method(
        components,
        routing,
        first == closed_info ? capped : capped_components(topology, components.size(), first));
  }
  if (plan.whole) {
    check_group_method(routing.all_closed_method, /*open=*/false);
    const MethodNeeds needs = method_needs(routing.all_closed_method);
    if (needs.bone_poses || needs.segmentation) {
      throw InvalidInput(
          "culling::make_method(auto): all_closed_method '" + routing.all_closed_method +
          "' needs more than the mesh (bones or a segmentation)");
    }
    for (auto& r : routes) r.method = routing.all_closed_method;
  }
  return plan;
}

}  // namespace

std::vector<ComponentRoute> route_components(
    const skinning::Topology& topology,
    const MethodOptions& options,
    const RoutingOptions& routing) {
  return plan_routes(topology, options, routing).routes;
}

bool routes_whole_mesh_to_all_closed_method(
    const skinning::Topology& topology, const RoutingOptions& routing) {
  const auto components = components_of(topology);
  if (!all_closed_rule_asked(components, routing)) return false;
  return whole_to_all_closed_method(
      components, routing, capped_components(topology, components.size(), first_closed_method()));
}

AutoGroups auto_groups(
    const skinning::Topology& topology, bool rig, const RoutingOptions& routing) {
  AutoGroups out;
  const auto components = components_of(topology);
  const MethodInfo* first = first_closed_method();
  const std::vector<std::uint8_t> capped_by_first =
      capped_components(topology, components.size(), first);
  out.whole = whole_to_all_closed_method(components, routing, capped_by_first);
  // route_components' closed method: a named one, else the first when a rig meets its needs.
  const MethodInfo* closed_info = !routing.closed_method.empty()
                                      ? find_method(routing.closed_method)
                                  : rig ? first
                                        : find_method(kClosedFallbackMethod);
  const std::vector<std::uint8_t> capped =
      closed_info == first ? capped_by_first
                           : capped_components(topology, components.size(), closed_info);
  for (std::size_t c = 0; c < components.size(); ++c) {
    const bool to_open =
        !out.whole && !components[c].closed && capped[c] == 0 &&
        static_cast<std::int32_t>(components[c].faces.size()) >= routing.min_open_triangles;
    (to_open ? out.open_components : out.closed_components)++;
  }
  return out;
}

std::vector<std::string> auto_group_methods(
    const MethodOptions& options, const RoutingOptions& routing) {
  return {routing.open_method, closed_method_name(options, routing)};
}

/// `auto` when every component goes to the closed group and its method is a whole-mesh method
/// (`dynamic` on a large rig closed throughout: RoutingOptions::all_closed_below_triangles): that
/// method on the whole mesh, answering for `auto` under its name with its routes. Nothing is
/// traversed between groups, so AutoMethod would only add its own feature topology, blocks and a
/// copy of each row (0.15 KiB per triangle more than `dynamic` on CesiumMan-dense).
class WholeMeshAuto final : public CullingMethod {
 public:
  WholeMeshAuto(std::unique_ptr<CullingMethod> method, std::vector<ComponentRoute> routes)
      : method_(std::move(method)), routes_(std::move(routes)) {}
  [[nodiscard]] std::string_view name() const override { return "auto"; }
  [[nodiscard]] std::span<const ComponentRoute> component_routes() const override {
    return routes_;
  }
  [[nodiscard]] const ConeStatistics* cone_statistics() const override {
    return method_->cone_statistics();
  }
  [[nodiscard]] std::shared_ptr<const FeatureTopology> shared_features() const override {
    return method_->shared_features();
  }
  [[nodiscard]] bool last_ccd_row_reusable() const override {
    return method_->last_ccd_row_reusable();
  }
  [[nodiscard]] const CullingMethod& method() const { return *method_; }

 protected:
  void dcd(const Instant& at, FrameResult& out) override { method_->detect_dcd(at, out); }
  void ccd(const Interval& interval, FrameResult& out) override {
    method_->detect_ccd(interval, out);
  }

 private:
  std::unique_ptr<CullingMethod> method_;
  std::vector<ComponentRoute> routes_;
};

std::unique_ptr<CullingMethod> make_routed_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const RoutingOptions& routing) {
  if (routing.dcd_cone_share < 0 || routing.ccd_cone_share < 0) {
    throw InvalidInput(
        "culling::make_method(auto): dcd_cone_share and ccd_cone_share must be 0 (never the "
        "cones) or more (got " +
        std::to_string(routing.dcd_cone_share) + " and " + std::to_string(routing.ccd_cone_share) +
        ")");
  }
  // The plan, with each component's part taken from the mesh.
  RoutePlan plan = plan_routes(topology, options, routing);
  for (auto& r : plan.routes) {
    const auto& faces = plan.components[sz(r.component)].faces;
    if (r.part < 0 && !faces.empty()) {
      r.part = mesh.face_part.empty() ? 0 : mesh.face_part[sz(faces.front())];
    }
  }
  const bool all_closed =
      !plan.routes.empty() && std::all_of(plan.routes.begin(), plan.routes.end(), in_closed_group);
  if (!plan.whole && all_closed && whole_mesh_method(plan.routes.front().method)) {
    std::unique_ptr<CullingMethod> method =
        make_method(plan.routes.front().method, mesh, topology, options);
    return std::make_unique<WholeMeshAuto>(std::move(method), std::move(plan.routes));
  }
  return std::make_unique<AutoMethod>(mesh, topology, options, routing, std::move(plan));
}

std::span<const ComponentRoute> routes_of(const CullingMethod& method) {
  return method.component_routes();
}

RoutedStructures routed_structures(const CullingMethod& method) {
  if (const auto* whole = dynamic_cast<const WholeMeshAuto*>(&method); whole != nullptr) {
    // Nothing of its own: the one method's feature topology, when it is one of culling/'s.
    RoutedStructures r;
    const auto* base = dynamic_cast<const detail::MethodBase*>(&whole->method());
    r.feature_topologies = base != nullptr ? 1 : 0;
    return r;
  }
  const auto* routed = dynamic_cast<const AutoMethod*>(&method);
  if (routed == nullptr) {
    throw InvalidInput(
        "culling::routed_structures: method '" + std::string(method.name()) + "' is not auto");
  }
  return routed->structures();
}

}  // namespace skelcd::culling
