#pragma once
// Helpers shared by the harnesses: the parsers that take a path get the fuzzer's bytes through a
// file in a private temporary folder (one per process, so -fork/-jobs workers do not collide).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace skelcd::fuzz {

/// Writes `size` bytes to `<tmp>/skelcd-fuzz-<pid>/input<extension>` and returns that path.
inline std::filesystem::path write_input(
    const std::uint8_t* data, std::size_t size, std::string_view extension) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("skelcd-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto path = dir / ("input" + std::string(extension));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

/// The bytes as text (the parsers that take text see exactly the fuzzer's bytes, NULs included).
inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace skelcd::fuzz
