// libFuzzer harness: CCD query files (tools/io/ccd_query_file.hpp, parse_ccd_queries), with the
// exact rationals kept (the slower path, which also parses every p/q into GMP).
// A thrown std::exception is the parser refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>

#include "fuzz/fuzz_input.hpp"
#include "tools/io/ccd_query_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in{std::string(skelcd::fuzz::as_text(data, size))};
  try {
    const auto queries = skelcd::tools::parse_ccd_queries(in, "fuzz.queries", /*keep_exact=*/true);
    for (const auto& q : queries) {
      if (q.exact.size() != q.coordinates.size()) __builtin_trap();
    }
  } catch (const std::exception&) {
  }
  return 0;
}
