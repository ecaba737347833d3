#pragma once
// Typed exceptions thrown at the boundaries (import, rig validation, options, files).
// Messages name the file or function and the offending index; the CLI prints what() on one line.

#include <stdexcept>
#include <string>

namespace skelcd {

/// The input is well-formed as a file but wrong as data (NaN, index out of range, cycle, ...).
class InvalidInput : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A file could not be found, opened, read, parsed or written.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace skelcd
