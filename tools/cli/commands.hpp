#pragma once
// The `skelcd` subcommands. Each lives in its own tools/cli/cmd_<name>.cpp and registers itself on
// the app with add_<name>_command; main.cpp calls them in the order `skelcd --help` lists them.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>

namespace skelcd::tools {

// One line per command; keep the order of DESIGN.md's command table.
void add_info_command(CLI::App& app);
void add_preprocess_command(CLI::App& app);
void add_check_command(CLI::App& app);
void add_inspect_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_generate_command(CLI::App& app);
void add_ccd_queries_command(CLI::App& app);
void add_bench_command(CLI::App& app);

/// What the executable does with a check's heap once it knows the size of the mesh (tools/cli/
/// main.cpp: the heap's top on huge pages for large meshes, docs/cli.md "Large allocations"):
/// `check` calls `hook` with the triangles of each model it loads (of a scene: of the objects it
/// checks, once they are all loaded), before it sets up its check.
/// None by default (the CLI's library alone, as the tests link it).
void on_check_model_loaded(std::function<void(std::int64_t triangles)> hook);

}  // namespace skelcd::tools
