#include "tools/cli/model_options.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"

namespace skelcd::tools {

void add_model_options(CLI::App& command, skinning::LoadOptions& options) {
  command.add_option(
      "--trajectory", options.trajectory, "robots: joint trajectory CSV (time,<joint names…>)");
  command.add_option(
      "--srdf", options.srdf, "robots: SRDF whose disabled collision pairs are skipped");
  command.add_option(
      "--package-path",
      options.package_path,
      "robots: folder searched for package:// meshes (repeatable)");
  // Memory that importing one model file may take, MiB; the import runs in a child process,
  // so a file that asks for more costs one line (docs/cli.md, "Broken files").
  command
      .add_option_function<double>(
          "--import-memory",
          [&options](double mib) {
            if (!(std::isfinite(mib) && mib >= 64 && mib <= 1024.0 * 1024.0)) {
              char text[64];
              std::snprintf(text, sizeof text, "%g", mib);
              throw InvalidInput(
                  std::string("--import-memory ") + text + ": expected MiB between 64 and 1048576");
            }
            options.import.memory_limit_bytes = static_cast<std::size_t>(mib * 1024.0 * 1024.0);
          },
          "model files: memory one import may use, MiB (default " +
              std::to_string(skinning::kDefaultImportMemoryLimit >> 20) + ")")
      ->type_name("MIB");
}

void add_mesh_order_option(CLI::App& command, skinning::LoadOptions& options) {
  command
      .add_option_function<std::string>(
          "--mesh-order",
          [&options](const std::string& order) {
            options.mesh_order =
                order == "file" ? skinning::MeshOrder::file : skinning::MeshOrder::spatial;
          },
          "frame sequences: hold vertices and triangles in a spatial order (faster when the "
          "files store them in none) or in the files' order; findings name the files' indices "
          "either way (default spatial)")
      ->check(CLI::IsMember({"spatial", "file"}));
}

std::string method_option_help(const std::string& lead) {
  std::string help = lead;
  for (const culling::MethodInfo* m : culling::registered_methods()) {
    help += "\n  " + m->name + ": " + m->description;
    if (m->needs.bone_poses || m->needs.segmentation) help += " (needs a rig's clip)";
    if (m->may_miss) help += " (may miss contacts)";
  }
  return help;
}

void add_radial_view_options(CLI::App& command, RadialViewArguments& args) {
  command.add_option("--gamma", args.gamma, "dynamic: merge threshold γ on (|H-| + |Hu|) / |C|")
      ->capture_default_str();
  command.add_option("--seed", args.seed, "dynamic: seed of the seed-cluster draws")
      ->capture_default_str();
  command.add_option(
      "--segmentation",
      args.segmentation,
      "rvbc/dynamic: SEG.h5 from `skelcd preprocess`, used when made from this model "
      "(else, and by default, segment here with the rig's weights)");
}

}  // namespace skelcd::tools
