// A scene's plan as text and as JSON.
#include "tools/report/scene_plan_report.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace skelcd::tools {
namespace {

std::string queries(bool dcd, bool ccd) {
  if (dcd && ccd) return "dcd+ccd";
  return dcd ? "dcd" : (ccd ? "ccd" : "none");
}

std::string stage_list(const ObjectPlan& o) {
  std::string out;
  const auto add = [&](bool on, const char* name) {
    if (on) out += (out.empty() ? "" : ", ") + std::string(name);
  };
  add(o.load, "load");
  add(o.skin, "skin");
  add(o.topology, "topology");
  add(o.bvh, "bvh");
  add(o.swept_bounds, "swept-bounds");
  add(o.cones, "cones");
  add(o.segmentation, "segmentation");
  return out.empty() ? "none" : out;
}

}  // namespace

void print_plan(std::ostream& out, const ScenePlan& plan) {
  std::size_t width = 4;
  for (const auto& o : plan.objects) width = std::max(width, o.name.size());
  const auto pad = [&](const std::string& s) { return s + std::string(width - s.size(), ' '); };
  out << "plan      " << plan.scene << ": " << plan.objects.size() << " objects, "
      << plan.checks.size() << " checks, " << plan.rows << " rows\n";
  char line[256];
  for (const auto& o : plan.objects) {
    if (!o.load) {
      out << "  object " << pad(o.name) << "  not checked: validated only, never loaded or posed\n";
      continue;
    }
    const auto& f = o.facts;
    std::snprintf(line, sizeof line, "%.6g", f.rate_hz);
    out << "  object " << pad(o.name) << "  " << f.source << ": " << f.triangles << " triangles, "
        << f.closed_components << " closed + " << f.open_components << " open components; "
        << f.motion << ", " << f.samples << " samples at " << line << " Hz\n";
    out << "    " << std::string(width, ' ') << "   self " << queries(o.self_dcd, o.self_ccd);
    if (o.self_dcd || o.self_ccd) {
      out << " (" << o.method << ", " << ccd::to_string(o.accuracy) << ")";
    }
    out << ", pairs " << queries(o.pair_dcd, o.pair_ccd) << "\n";
    out << "    " << std::string(width, ' ') << "   runs  " << stage_list(o) << "\n";
    for (const auto& s : o.skipped) {
      out << "    " << std::string(width, ' ') << "   skips " << s << "\n";
    }
  }
  for (std::size_t k = 0; k < plan.checks.size(); ++k) {
    const auto& c = plan.checks[k];
    out << "  check " << k << "  " << c.name(plan.objects) << ": " << to_string(c.query) << ", "
        << c.method << (c.kind == CheckKind::pair ? " pair traversal" : "") << ", "
        << ccd::to_string(c.accuracy) << ", samples " << c.first_sample << ".." << c.last_sample
        << ", " << c.rows << " rows\n";
  }
}

nlohmann::json plan_json(const ScenePlan& plan) {
  auto objects = nlohmann::json::array();
  for (const auto& o : plan.objects) {
    objects.push_back({
        {"name", o.name},
        {"checked", o.checked},
        {"self", queries(o.self_dcd, o.self_ccd)},
        {"pairs", queries(o.pair_dcd, o.pair_ccd)},
        {"method", o.method},
        {"accuracy", std::string(ccd::to_string(o.accuracy))},
        {"stages",
         {{"load", o.load},
          {"skin", o.skin},
          {"topology", o.topology},
          {"bvh", o.bvh},
          {"swept_bounds", o.swept_bounds},
          {"cones", o.cones},
          {"segmentation", o.segmentation}}},
        {"skipped", o.skipped},
        {"source", o.facts.source},
        {"motion", o.facts.motion},
        {"samples", o.facts.samples},
        {"rate_hz", o.facts.rate_hz},
        {"triangles", o.facts.triangles},
        {"open_components", o.facts.open_components},
        {"closed_components", o.facts.closed_components},
    });
  }
  auto checks = nlohmann::json::array();
  for (const auto& c : plan.checks) {
    checks.push_back({
        {"name", c.name(plan.objects)},
        {"kind", c.kind == CheckKind::self ? "self" : "pair"},
        {"query", std::string(to_string(c.query))},
        {"method", c.method},
        {"accuracy", std::string(ccd::to_string(c.accuracy))},
        {"first_sample", c.first_sample},
        {"last_sample", c.last_sample},
        {"rows", c.rows},
    });
  }
  return {{"scene", plan.scene}, {"objects", objects}, {"checks", checks}, {"rows", plan.rows}};
}

}  // namespace skelcd::tools
