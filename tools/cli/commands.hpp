#pragma once
// The `skelcd` subcommands. Each lives in its own tools/cli/cmd_<name>.cpp and registers itself on
// the app with add_<name>_command; main.cpp calls them in the order `skelcd --help` lists them.

#include <CLI/CLI.hpp>

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

}  // namespace skelcd::tools
