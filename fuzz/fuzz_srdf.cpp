// libFuzzer harness: SRDF disabled-collision pairs (skinning/urdf_srdf.hpp,
// parse_srdf_disabled_collisions; TinyXML underneath).
// A thrown std::exception is the parser refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz/fuzz_input.hpp"
#include "skinning/urdf_srdf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto pairs = skelcd::skinning::parse_srdf_disabled_collisions(
        std::string(skelcd::fuzz::as_text(data, size)), "fuzz.srdf");
    for (const auto& p : pairs) {
      if (p.link1.empty() || p.link2.empty()) __builtin_trap();  // documented: both present
    }
  } catch (const std::exception&) {
  }
  return 0;
}
