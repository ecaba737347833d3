#include "culling/method_registry.hpp"

#include <algorithm>
#include <mutex>

#include "culling/detail/method_base.hpp"
#include "culling/dual_cone.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/normal_cone.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::unique_ptr<MethodInfo>> methods;
};

void add(Registry& r, MethodInfo info) {
  if (info.name.empty()) throw InvalidInput("culling::register_method: a method needs a name");
  if (!info.make)
    throw InvalidInput("culling::register_method: method '" + info.name + "' has no factory");
  const std::lock_guard lock(r.mutex);
  for (const auto& m : r.methods) {
    if (m->name == info.name)
      throw InvalidInput(
          "culling::register_method: method '" + info.name + "' is registered twice");
  }
  r.methods.push_back(std::make_unique<MethodInfo>(std::move(info)));
}

// culling/'s own methods. Those of modules above register themselves from their own files.
void add_culling_methods(Registry& r) {
  add(r,
      {.name = "brute",
       .description = "every feature pair (volume-filtered), the reference on small meshes",
       .order = 10,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return detail::make_brute_method(mesh, topology, options);
       }});
  add(r,
      {.name = "bvh",
       .description = "AABB hierarchy (the papers' 'AABB only')",
       .order = 20,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return detail::make_bvh_method<3>("bvh", mesh, topology, options);
       }});
  add(r,
      {.name = "kdop",
       .description =
           "16-DOP hierarchy; CCD pairs through relative AABBs when that pays, and skipped "
           "where skinning moves both triangles by one matrix",
       .takes_rigid_rows = true,
       .order = 30,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return detail::make_bvh_method<8>(
             "kdop", mesh, topology, options, /*relative_pairs=*/true, /*rigid_rows=*/true);
       }});
  add(r,
      {.name = "normal-cone",
       .description = "continuous normal cones and contour tests (ICCD/CBC; NCT for DCD)",
       .order = 40,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return make_normal_cone_method(mesh, topology, options);
       }});
  add(r,
      {.name = "dual-cone",
       .description = "the original dual-cone method (FASTCD), kept to show what it misses",
       .may_miss = true,
       .order = 50,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return make_dual_cone_method(mesh, topology, options);
       }});
  add(r,
      {.name = "enhanced-dual-cone",
       .description = "enhanced dual cones for meshes with open boundaries (paper 000)",
       .route = RouteKind::open,
       .route_priority = 10,
       .order = 60,
       .make = [](const skinning::Mesh& mesh,
                  const skinning::Topology& topology,
                  const MethodOptions& options) {
         return make_enhanced_dual_cone_method(mesh, topology, options);
       }});
  add(r,
      {.name = "auto",
       .description =
           "bvh (skipping the CCD pairs skinning moves by one matrix) for a mesh whose every "
           "part is closed, under 256 triangles or open only at holes dynamic caps; otherwise "
           "per "
           "connected part: closed parts to the best closed-part method whose needs are met "
           "(dynamic on a rig, else bvh), and with them open parts it caps or under 256 "
           "triangles; other open parts to enhanced-dual-cone",
       // Its `bvh` for a whole mesh skips the pairs skinning moves as one (docs/culling.md).
       .takes_rigid_rows = true,
       // `auto` carries what the methods it routes to carry.
       .serial_reason =
           [](const MethodOptions& options, bool dcd_before_each_ccd) {
             for (const auto& route : auto_group_methods(options)) {
               const MethodInfo* m = find_method(route);
               if (m != nullptr && m->serial_reason) {
                 auto why = m->serial_reason(options, dcd_before_each_ccd);
                 if (!why.empty()) return why;
               }
             }
             return std::string();
           },
       // … and what they carry follows from the pose when it does for each of them.
       .carried_state_follows_pose =
           [](const MethodOptions& options) {
             for (const auto& route : auto_group_methods(options)) {
               const MethodInfo* m = find_method(route);
               if (m != nullptr && m->serial_reason &&
                   !(m->carried_state_follows_pose && m->carried_state_follows_pose(options))) {
                 return false;
               }
             }
             return true;
           },
       .order = 65,
       .make =
           [](const skinning::Mesh& mesh,
              const skinning::Topology& topology,
              const MethodOptions& options) {
             return make_routed_method(mesh, topology, options);
           }});
}

Registry& registry() {
  // Built on first use (static registrations of other modules may come first), never destroyed:
  // registrations from static objects of other files may run in any order.
  static Registry* r = [] {
    auto* made = new Registry;
    add_culling_methods(*made);
    return made;
  }();
  return *r;
}

}  // namespace

bool register_method(MethodInfo info) {
  add(registry(), std::move(info));
  return true;
}

const MethodInfo* find_method(std::string_view name) {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  for (const auto& m : r.methods) {
    if (m->name == name) return m.get();
  }
  return nullptr;
}

MethodNeeds method_needs(std::string_view name) {
  const MethodInfo* m = find_method(name);
  return m != nullptr ? m->needs : MethodNeeds{};
}

std::vector<const MethodInfo*> registered_methods() {
  Registry& r = registry();
  std::vector<const MethodInfo*> out;
  {
    const std::lock_guard lock(r.mutex);
    for (const auto& m : r.methods) out.push_back(m.get());
  }
  std::stable_sort(out.begin(), out.end(), [](const MethodInfo* a, const MethodInfo* b) {
    return a->order != b->order ? a->order < b->order : a->name < b->name;
  });
  return out;
}

bool needs_met(const MethodNeeds& needs, const MethodOptions& options) {
  return (!needs.segmentation || options.segmentation != nullptr) &&
         (!needs.bone_poses || options.num_bones > 0);
}

}  // namespace skelcd::culling
