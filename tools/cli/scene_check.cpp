// `skelcd check SCENE.toml`: the scene's plan, progress and results on the terminal.
#include "tools/cli/scene_check.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>

#include "skinning/errors.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/engine/scene.hpp"
#include "tools/engine/scene_runner.hpp"
#include "tools/report/scene_plan_report.hpp"
#include "tools/report/summary_json.hpp"

namespace skelcd::tools {
namespace {

std::string own_command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (char& ch : raw) {
    if (ch == '\0') ch = ' ';
  }
  while (!raw.empty() && raw.back() == ' ') raw.pop_back();
  return raw;
}

}  // namespace

void run_scene_check(const std::filesystem::path& scene_path, const SceneCheckArguments& args) {
  const Scene scene = parse_scene(scene_path);
  SceneRunOptions options;
  options.log = args.output.empty() ? scene.output : std::filesystem::path(args.output);
  if (!args.frames.empty()) options.frames = parse_frame_range(args.frames);
  if (args.threads < 0) {
    throw InvalidInput(
        "--threads " + std::to_string(args.threads) +
        ": expected a worker count >= 1 (0: all cores)");
  }
  options.threads = args.threads;
  options.command_line = own_command_line();
  options.on_loaded = args.on_loaded;
  options.on_check = [](const std::string& label, std::int64_t rows) {
    auto progress = std::make_shared<Progress>(label, rows);
    return std::function<void(std::int64_t)>(
        [progress](std::int64_t done) { progress->update(done); });
  };
  if (!args.json) {
    options.on_plan = [](const ScenePlan& plan) {
      print_plan(std::cout, plan);
      std::cout << std::flush;
    };
  }
  const auto result = run_scene(scene, options);

  if (args.json) {
    auto checks = nlohmann::json::array();
    for (const auto& c : result.checks) {
      const auto& s = c.summary;
      checks.push_back(
          {{"name", c.name},
           {"rows", s.rows},
           {"samples", s.samples},
           {"intervals", s.intervals},
           {"dcd_pairs", s.dcd_pairs},
           {"ccd_vf", s.ccd_vf},
           {"ccd_ee", s.ccd_ee},
           {"frames_with_interpenetration", s.frames_with_interpenetration},
           {"intervals_with_contacts", s.intervals_with_contacts},
           {"bv_tests", s.bv_tests},
           {"candidate_pairs", s.candidate_pairs},
           {"ms_per_interval", s.ms_per_interval},
           {"total_ms", s.total_ms},
           {"stages_ms", stages_json(s)},
           {"baseline", c.baseline.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.baseline)},
           {"events",
            c.baseline.empty() ? nlohmann::json(nullptr)
                               : events_json(c.events, result.part_names)},
           {"new_dcd_pairs", s.new_dcd_pairs},
           {"new_ccd_contacts", s.new_ccd_contacts},
           {"baseline_dcd_pairs", s.baseline_dcd_pairs},
           {"baseline_ccd_contacts", s.baseline_ccd_contacts},
           {"allowed_dcd_pairs", s.allowed_dcd_pairs},
           {"allowed_ccd_contacts", s.allowed_ccd_contacts}});
    }
    print_json(
        {{"scene", scene_path.string()},
         {"plan", plan_json(result.plan)},
         {"checks", checks},
         {"total_ms", result.total_ms},
         {"log",
          options.log.empty() ? nlohmann::json(nullptr) : nlohmann::json(options.log.string())}});
    return;
  }
  std::size_t width = 0;
  for (const auto& c : result.checks) width = std::max(width, c.name.size());
  char line[320];
  for (std::size_t k = 0; k < result.checks.size(); ++k) {
    const auto& c = result.checks[k];
    const auto& s = c.summary;
    const auto& p = result.plan.checks[k];
    std::cout << "result    " << c.name << std::string(width - c.name.size(), ' ') << "  ";
    if (!c.baseline.empty()) {
      std::cout << root_events(c.events).size() << " events against " << c.baseline << " ("
                << s.baseline_dcd_pairs + s.baseline_ccd_contacts << " baseline, "
                << s.allowed_dcd_pairs + s.allowed_ccd_contacts << " allowed findings); ";
    }
    if (p.query != QuerySet::ccd) {
      std::cout << "DCD " << s.frames_with_interpenetration << "/" << s.samples
                << " samples with new intersections (" << s.dcd_pairs << " pairs)";
      if (p.query == QuerySet::both) std::cout << "; ";
    }
    if (p.query != QuerySet::dcd) {
      std::cout << "CCD " << s.intervals_with_contacts << "/" << s.intervals
                << " intervals with new contacts (" << s.ccd_vf << " VF + " << s.ccd_ee << " EE)";
    }
    std::snprintf(
        line,
        sizeof line,
        "; %.3f ms per %s (refit %.3f, classify %.3f, merge %.3f, traverse %.3f, "
        "elementary %.3f)\n",
        s.ms_per_interval,
        s.intervals > 0 ? "interval" : "sample",
        s.refit_ms,
        s.classify_ms,
        s.merge_ms,
        s.traverse_ms,
        s.elementary_ms);
    std::cout << line;
  }
  std::snprintf(line, sizeof line, "time      %.1f ms in all\n", result.total_ms);
  std::cout << line;
  if (!options.log.empty()) std::cout << "log       " << options.log.string() << '\n';
}

}  // namespace skelcd::tools
