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
    // Link names may come back empty (TinyXML reads `link2=/>` as an empty value): the parser
    // promises only that both attributes exist; load_urdf refuses '' as an unknown link.
    (void)skelcd::skinning::parse_srdf_disabled_collisions(
        std::string(skelcd::fuzz::as_text(data, size)), "fuzz.srdf");
  } catch (const std::exception&) {
  }
  return 0;
}
