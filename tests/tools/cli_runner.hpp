#pragma once
// Runs the real `skelcd` binary from a test and captures its exit status, stdout and stderr.

#include <string>
#include <vector>

namespace skelcd::test {

struct CommandResult {
  int exit_code = -1;  ///< process exit status; 128 + signal number when killed by a signal
  std::string out;
  std::string err;
};

/// Runs SKELCD_EXE with `args` (no shell: arguments are passed as they are).
/// @param stdin_text written to the child's standard input, then closed.
[[nodiscard]] CommandResult run_skelcd(const std::vector<std::string>& args,
                                       const std::string& stdin_text = {});

}  // namespace skelcd::test
