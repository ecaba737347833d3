#include "tools/report/progress.hpp"

#include <unistd.h>

#include <cstdio>
#include <utility>

namespace skelcd::tools {

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

Progress::Progress(
    std::string label, std::int64_t total, const std::atomic<std::int64_t>* tests_done)
    : label_(std::move(label)),
      total_(total),
      enabled_(stderr_is_terminal()),
      tests_done_(tests_done) {
  if (!enabled_ || tests_done_ == nullptr) return;
  ticker_ = std::thread([this] {
    std::unique_lock lock(mutex_);
    while (!finished_) {
      wake_.wait_for(lock, std::chrono::milliseconds(250));
      if (!finished_) draw(done_);
    }
  });
}

Progress::~Progress() { finish(); }

void Progress::update(std::int64_t done) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  if (finished_) return;
  done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  draw(done);
}

void Progress::draw(std::int64_t done) {
  const double percent =
      total_ > 0 ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0;
  std::fprintf(
      stderr,
      "\r%s %lld/%lld (%.0f%%)",
      label_.c_str(),
      static_cast<long long>(done),
      static_cast<long long>(total_),
      percent);
  if (tests_done_ != nullptr) {
    std::fprintf(
        stderr,
        ", %lld elementary tests",
        static_cast<long long>(tests_done_->load(std::memory_order_relaxed)));
  }
  std::fprintf(stderr, "\033[K");
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_) return;
  {
    std::lock_guard lock(mutex_);
    if (finished_) return;
    finished_ = true;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

}  // namespace skelcd::tools
