// libFuzzer harness: scene TOML (tools/engine/scene.hpp, parse_scene_text). The scene is named
// assets/scenes/fuzz.toml so that relative model paths in the seeds (../characters/...) resolve
// to the bundled files; parsing only checks that they exist, nothing is loaded.
// A thrown std::exception is the parser refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_input.hpp"
#include "tools/engine/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path scene_path =
      std::filesystem::path(SKELCD_SOURCE_DIR) / "assets" / "scenes" / "fuzz.toml";
  try {
    const auto scene =
        skelcd::tools::parse_scene_text(skelcd::fuzz::as_text(data, size), scene_path);
    // Touch what a caller reads next, so a half-built scene would show up here.
    for (const auto& o : scene.objects) (void)scene.is_checked(o.name);
    for (const auto& p : scene.pairs) (void)scene.find(p.a);
  } catch (const std::exception&) {
  }
  return 0;
}
