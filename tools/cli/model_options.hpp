#pragma once
// The options every command that reads a MODEL shares (how to load it), so that `info`,
// `export` and the others accept the same spellings.

#include <CLI/CLI.hpp>
#include <string>

#include "skinning/load.hpp"
#include "tools/engine/radial_view_setup.hpp"

namespace skelcd::tools {

/// Adds --trajectory, --srdf and --package-path (robots) and --import-memory (model files) to
/// `command`, filling `options`.
/// `options` must outlive the parse.
void add_model_options(CLI::App& command, skinning::LoadOptions& options);

/// Adds --mesh-order (frame sequences: spatial, LoadOptions' default, or file) to a command that
/// checks.
void add_mesh_order_option(CLI::App& command, skinning::LoadOptions& options);

/// The help text of a method option: every registered method (culling/method_registry.hpp) with
/// its one line, and what it needs.
[[nodiscard]] std::string method_option_help(const std::string& lead);

/// Adds --gamma, --seed and --segmentation (rvbc/dynamic/auto) to `command`, stored into `args`.
void add_radial_view_options(CLI::App& command, RadialViewArguments& args);

}  // namespace skelcd::tools
