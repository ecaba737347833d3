#pragma once
// Small pieces every command uses: JSON output, a progress line on a terminal, path checks.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace skelcd::tools {

/// Prints `object` to stdout as one JSON document followed by a newline.
void print_json(const nlohmann::json& object);

/// True when stderr is a terminal (progress lines are shown only then).
[[nodiscard]] bool stderr_is_terminal();

/// A one-line progress indicator on stderr, redrawn at most ~10 times a second, shown only when
/// stderr is a terminal; erased by finish() or the destructor.
class Progress {
 public:
  Progress(std::string label, std::int64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void update(std::int64_t done);
  void finish();

 private:
  std::string label_;
  std::int64_t total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_{};
};

/// Throws IoError "<path>: no such file" unless `path` exists.
void require_exists(const std::filesystem::path& path);

}  // namespace skelcd::tools
