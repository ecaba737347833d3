// skelcd info MODEL [--json]: what a model holds — mesh, skeleton, clips, parts (open/closed),
// topology and the problems found on the way.

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/model_options.hpp"
#include "tools/report/model_report.hpp"

namespace skelcd::tools {
namespace {

struct InfoArgs {
  std::string model;
  bool json = false;
  skinning::LoadOptions load;
};

void run_info(const InfoArgs& args) {
  const auto model = skinning::load_model(args.model, args.load);
  const auto topology = skinning::build_topology(*model.mesh);
  const auto report = model_report(model, topology);
  if (args.json) {
    print_json(report);
  } else {
    std::cout << format_model_report(report);
  }
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  auto* cmd = app.add_subcommand(
      "info",
      "meshes, triangles, vertices, bones, clips (and the rate a check samples each at), "
      "open/closed parts, problems found");
  cmd->add_option(
         "model",
         args->model,
         "model file (glTF, FBX, Collada, .X, OBJ, PLY, …), URDF, or frames (folder or glob)")
      ->required();
  cmd->add_flag("--json", args->json, "print one JSON object instead of the summary");
  add_model_options(*cmd, args->load);
  cmd->callback([args] { run_info(*args); });
}

}  // namespace skelcd::tools
