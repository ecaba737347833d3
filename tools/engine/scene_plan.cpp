// The plan of a scene: which stages run for which object, and why the others do not.
#include "tools/engine/scene_plan.hpp"

#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"
#include "tools/engine/radial_view_setup.hpp"

namespace skelcd::tools {
namespace {

bool is_cone_method(const std::string& method) {
  return method == "normal-cone" || method == "dual-cone" || method == "enhanced-dual-cone";
}

QuerySet query_set(bool dcd, bool ccd) {
  if (dcd && ccd) return QuerySet::both;
  return dcd ? QuerySet::dcd : QuerySet::ccd;
}

/// Decides the stages of one object from its checks and what loading found.
void decide_stages(ObjectPlan& o) {
  const bool self = o.self_dcd || o.self_ccd;
  const bool pair = o.pair_dcd || o.pair_ccd;
  o.checked = self || pair;
  o.skin = o.checked;
  o.topology = o.checked;
  o.bvh = pair || (self && o.method != "brute");
  o.swept_bounds = o.self_ccd || o.pair_ccd;
  const bool radial = culling::method_needs(o.method).segmentation;
  if (self && is_cone_method(o.method)) {
    o.cones = true;
  } else if (self && o.method == "auto") {
    o.cones = o.facts.auto_open_group > 0;
  }
  // Radial view culls intervals only: a DCD-only object answers with `bvh` and is not segmented.
  if (o.self_ccd && radial) {
    o.segmentation = true;
  } else if (o.self_ccd && o.method == "auto") {
    o.segmentation =
        o.facts.auto_closed_group > 0 && o.facts.rig_motion && !o.facts.auto_whole_to_bvh;
  }
  if (!o.load) return;
  auto& s = o.skipped;
  if (!o.checked) {
    s.push_back("skin, topology, bvh: no check names it (loaded only for what is attached to it)");
    return;
  }
  if (!o.bvh) s.push_back("bvh: method brute tests every pair");
  if (!o.swept_bounds) s.push_back("swept bounds: no CCD check names it (DCD only)");
  if (!o.cones) {
    if (!self) {
      s.push_back("cones: pair checks only (pairs use the hierarchies)");
    } else if (o.method == "auto") {
      s.push_back(
          o.facts.open_components == 0
              ? std::string("cones: no open part (auto uses cones only for parts with a boundary)")
          : o.facts.auto_whole_to_bvh
              ? "cones: every part closed, small or capped and " + auto_whole_mesh_size() +
                    " (auto sends the whole mesh to bvh)"
              : "cones: every open part under " + auto_open_size() +
                    " or capped (auto sends them with the closed parts)");
    } else {
      s.push_back("cones: method " + o.method + " uses none");
    }
  }
  if (!o.segmentation) {
    if (!self) {
      s.push_back("segmentation: pair checks only");
    } else if (!o.self_ccd && (radial || o.method == "auto")) {
      s.push_back(
          "segmentation: DCD only (" + o.method +
          " answers instants with bvh; radial view culls intervals)");
    } else if (o.method == "auto") {
      s.push_back(
          o.facts.auto_closed_group == 0
              ? "segmentation: no closed part, and no open one under " + auto_open_size() +
                    " or capped (auto segments only the parts it sends to dynamic)"
          : o.facts.auto_whole_to_bvh
              ? "segmentation: every part closed, small or capped and " + auto_whole_mesh_size() +
                    " (auto sends the whole mesh to bvh)"
              : std::string(
                    "segmentation: not moved by its own skeleton (closed parts go to bvh)"));
    } else {
      s.push_back("segmentation: method " + o.method + " uses none (only rvbc, dynamic)");
    }
  }
}

}  // namespace

std::string CheckPlan::name(const std::vector<ObjectPlan>& objects) const {
  const auto& a = objects[static_cast<std::size_t>(object_a)].name;
  if (kind == CheckKind::self) return "self " + a;
  return "pair " + a + " " + objects[static_cast<std::size_t>(object_b)].name;
}

std::vector<bool> objects_to_load(const Scene& scene) {
  std::vector<bool> load(scene.objects.size(), false);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const auto& o = scene.objects[i];
    if (!scene.is_checked(o.name)) continue;
    load[i] = true;
    if (!o.attach_to.empty()) {
      for (std::size_t j = 0; j < scene.objects.size(); ++j) {
        if (scene.objects[j].name == o.attach_to) load[j] = true;
      }
    }
  }
  return load;
}

ScenePlan plan_scene(
    const Scene& scene,
    const std::vector<ObjectFacts>& facts,
    const std::optional<FrameRange>& frames) {
  ScenePlan plan;
  plan.scene = scene.path.string();
  const auto load = objects_to_load(scene);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const auto& so = scene.objects[i];
    ObjectPlan o;
    o.name = so.name;
    o.line = so.line;
    o.self_dcd = so.self_dcd;
    o.self_ccd = so.self_ccd;
    o.method = so.method;
    o.accuracy = so.accuracy;
    o.load = load[i];
    if (i < facts.size()) o.facts = facts[i];
    for (const auto& p : scene.pairs) {
      if (p.a == so.name || p.b == so.name) {
        o.pair_dcd = o.pair_dcd || p.dcd;
        o.pair_ccd = o.pair_ccd || p.ccd;
      }
    }
    decide_stages(o);
    plan.objects.push_back(std::move(o));
  }
  const auto index_of = [&](const std::string& name) {
    for (std::size_t i = 0; i < plan.objects.size(); ++i) {
      if (plan.objects[i].name == name) return static_cast<std::int32_t>(i);
    }
    return std::int32_t{-1};
  };
  // Rows of a check over samples first..last: a DCD row per sample, a CCD row per interval.
  const auto fill_rows =
      [&](CheckPlan& c, std::int32_t samples, int line, const std::string& what) {
        const std::int32_t first = frames ? frames->first : 0;
        const std::int32_t last = frames && frames->last ? *frames->last : samples - 1;
        if (samples < 1 || first > last || last >= samples) {
          throw InvalidInput(scene.where(
              frames ? scene.frames_line : line,
              what + ": frames " + std::to_string(first) + ":" + std::to_string(last) +
                  " do not fit its " + std::to_string(samples) +
                  " samples (0:" + std::to_string(samples - 1) + ")"));
        }
        c.first_sample = first;
        c.last_sample = last;
        const bool dcd = c.query != QuerySet::ccd;
        const bool ccd = c.query != QuerySet::dcd;
        c.rows = (dcd ? last - first + 1 : 0) + (ccd ? last - first : 0);
        plan.rows += c.rows;
      };
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const auto& so = scene.objects[i];
    if (!so.has_self_check()) continue;
    CheckPlan c;
    c.kind = CheckKind::self;
    c.object_a = static_cast<std::int32_t>(i);
    c.query = query_set(so.self_dcd, so.self_ccd);
    c.method = so.method;
    c.accuracy = so.accuracy;
    c.line = so.checks_line != 0 ? so.checks_line : so.line;
    fill_rows(c, plan.objects[i].facts.samples, c.line, "object '" + so.name + "'");
    plan.checks.push_back(c);
  }
  for (const auto& p : scene.pairs) {
    CheckPlan c;
    c.kind = CheckKind::pair;
    c.object_a = index_of(p.a);
    c.object_b = index_of(p.b);
    c.query = query_set(p.dcd, p.ccd);
    c.method = "bvh";
    c.accuracy = p.accuracy;
    c.line = p.line;
    fill_rows(
        c,
        plan.objects[static_cast<std::size_t>(c.object_a)].facts.samples,
        p.line,
        "pair " + p.a + " × " + p.b);
    plan.checks.push_back(c);
  }
  return plan;
}

}  // namespace skelcd::tools
