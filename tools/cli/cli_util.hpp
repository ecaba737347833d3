#pragma once
// Small pieces every command uses: JSON output, a progress line on a terminal, path checks.

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <thread>

namespace skelcd::tools {

/// Prints `object` to stdout as one JSON document followed by a newline.
void print_json(const nlohmann::json& object);

/// True when stderr is a terminal (progress lines are shown only then).
[[nodiscard]] bool stderr_is_terminal();

/// A one-line progress indicator on stderr, redrawn at most ~10 times a second, shown only when
/// stderr is a terminal; erased by finish() or the destructor.
class Progress {
 public:
  /// @param tests_done when set, also shown (and redrawn every 0.25 s by a thread of its own
  ///   while the line is up), so that one long row still shows work going on.
  Progress(
      std::string label, std::int64_t total, const std::atomic<std::int64_t>* tests_done = nullptr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void update(std::int64_t done);
  void finish();

 private:
  void draw(std::int64_t done);  // with mutex_ held

  std::string label_;
  std::int64_t total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_{};
  const std::atomic<std::int64_t>* tests_done_;
  std::int64_t done_ = 0;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread ticker_;
};

/// Adds a sampling-rate option (`names`, e.g. "--fps" or "--rate,--fps") that stores a rate in
/// samples/s into `rate`. Leaving it out keeps `rate` as it is (0: the model's default); giving a
/// value that is not finite and > 0 (0 included) is refused: InvalidInput "--fps 0: expected a
/// rate > 0 (samples/s)".
CLI::Option* add_rate_option(
    CLI::App& command, const std::string& names, double& rate, const std::string& help);

/// The help of a rate option that samples a clip, saying its default: the clip's frame rate
/// (skinning::ClipSummary::rate_hz), else 30.
inline constexpr const char* kClipRateHelp =
    "samples per second (default: the clip's frame rate, else 30; `skelcd info` shows it)";

/// Throws IoError "<path>: no such file" unless `path` exists.
void require_exists(const std::filesystem::path& path);

}  // namespace skelcd::tools
