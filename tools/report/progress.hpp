#pragma once
// A progress line on stderr, shown only when stderr is a terminal: what `check`, a scene's checks,
// `bench`, `generate` and `ccd-queries` draw while they work.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace skelcd::tools {

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

}  // namespace skelcd::tools
