#include "tools/model_options.hpp"

namespace skelcd::tools {

void add_model_options(CLI::App& command, skinning::LoadOptions& options) {
  command.add_option("--trajectory", options.trajectory, "robots: joint trajectory CSV (time,<joint names…>)");
  command.add_option("--srdf", options.srdf, "robots: SRDF whose disabled collision pairs are skipped");
  command.add_option("--package-path", options.package_path, "robots: folder searched for package:// meshes (repeatable)");
}

}  // namespace skelcd::tools
