#pragma once
// Reading CCD query files (format: docs/ccd-queries.md). One query per line: `vf` or `ee`, 24
// coordinates (decimal or exact rational p/q), an optional expected result 0/1; `#` comments and
// blank lines ignored.

#include <gmpxx.h>

#include <array>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace skelcd::tools {

struct CcdQueryRecord {
  bool vertex_face = true;
  /// The 8 points x, y, z in file order (vf: vertex, corners 0..2; ee: a0, a1, b0, b1; t = 0 then
  /// t = 1), each coordinate the double nearest to the written number.
  std::array<double, 24> coordinates{};
  /// The written numbers exactly (0.1 is 1/10), in the same order; empty unless asked for.
  std::vector<mpq_class> exact;
  std::optional<bool> expected;
  int line = 0;  ///< 1-based line number in the file
  /// Largest |double - written number| over the 24 coordinates, bounded from above (0 when every
  /// coordinate is exactly a double, e.g. p/q with q a power of two, or 0.5).
  double rounding = 0.0;
};

/// Parses every query of `in`. Throws InvalidInput "<name>:<line>: <fault>" on the first malformed
/// line (wrong keyword, wrong count, a number that is not one, a value beyond the double range, an
/// expected result other than 0 or 1).
/// @param keep_exact also fill CcdQueryRecord::exact (slower).
[[nodiscard]] std::vector<CcdQueryRecord> parse_ccd_queries(
    std::istream& in, const std::string& name, bool keep_exact);

/// Reads `path` ("-" for standard input). Throws IoError if it cannot be opened, InvalidInput as
/// parse_ccd_queries.
[[nodiscard]] std::vector<CcdQueryRecord> read_ccd_queries(
    const std::string& path, bool keep_exact);

/// One number token: the double nearest to it, and (when `exact` is not null) its exact value.
/// `rounding` receives an upper bound on |value - written number|: 0 when the double is exactly
/// the number, otherwise half an ulp of the value. Returns false with `fault` set when the token is
/// not a finite number of the format.
[[nodiscard]] bool parse_ccd_number(
    std::string_view token, double& value, mpq_class* exact, double& rounding, std::string& fault);

}  // namespace skelcd::tools
