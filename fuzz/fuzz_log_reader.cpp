// libFuzzer harness: the HDF5 log reader (tools/io/log/log_reader.hpp, read_log with findings), the
// bytes written to input.h5. Seeds are small real logs; mutations mostly damage HDF5 metadata, so
// a crash here may be inside libhdf5 (docs/fuzzing.md says how those are reported).
// A thrown std::exception is the reader refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_input.hpp"
#include "tools/io/log/log_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = skelcd::fuzz::write_input(data, size, ".h5");
  try {
    (void)skelcd::tools::read_log(path, {.findings = true, .isolate = false});
  } catch (const std::exception&) {
  }
  return 0;
}
