// skelcd: self-collision detection for skeleton-driven animation. Every error reaches the user as
// one line on stderr and a non-zero exit status.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>

#include "skelcd_version.hpp"
#include "tools/cli/commands.hpp"
#if defined(SKELCD_LARGE_PAGES)
#include "tools/cli/large_pages.hpp"
#endif

int main(int argc, char** argv) {
  CLI::App app{"skelcd — finds self-collisions in skeleton-driven animation", "skelcd"};
  app.set_version_flag("--version", skelcd::kVersion);
  app.require_subcommand(1);
  app.fallthrough(false);

  // Commands, in the order of DESIGN.md's table (one line each):
  skelcd::tools::add_info_command(app);
  skelcd::tools::add_preprocess_command(app);
  skelcd::tools::add_check_command(app);
  skelcd::tools::add_inspect_command(app);
  skelcd::tools::add_export_command(app);
  skelcd::tools::add_generate_command(app);
  skelcd::tools::add_ccd_queries_command(app);
  skelcd::tools::add_bench_command(app);
#if defined(SKELCD_LARGE_PAGES)
  // A large mesh's check puts its small blocks on huge pages too (docs/cli.md, "Large
  // allocations"), once its model is loaded and its size known; the other commands keep malloc as
  // it is.
  app.get_subcommand("check")->preparse_callback([](std::size_t) {
    if (!skelcd::tools::large_pages_wanted(std::getenv("SKELCD_LARGE_PAGES"))) return;
    skelcd::tools::on_check_model_loaded([advised = false](std::int64_t triangles) mutable {
      if (advised || !skelcd::tools::heap_on_huge_pages_pays(triangles)) return;
      skelcd::tools::heap_on_huge_pages(skelcd::tools::kHeapOnHugePages);
      advised = true;  // the first large model of a batch: the heap's top stays advised
    });
  });
#endif

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "skelcd: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
