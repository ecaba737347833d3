#pragma once
// Writes a skelcd log (HDF5, docs/log-format.md) row by row as a run produces it. Every append is
// flushed to disk, so a run that is killed leaves a readable log holding every completed frame.

#include <filesystem>
#include <memory>
#include <vector>

#include "tools/io/event_record.hpp"
#include "tools/io/frame_report.hpp"
#include "tools/io/log/log_header.hpp"

namespace skelcd::tools {

class LogWriter {
 public:
  /// Creates the log at `path` and writes the header (root attributes and /parts) and empty tables.
  /// An existing file is replaced only if it is a skelcd log or empty.
  /// @throws IoError naming `path` when it exists and is something else, or cannot be created.
  LogWriter(const std::filesystem::path& path, const LogHeader& header);
  /// Closes the file without marking it complete (as a run cut short would leave it).
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  /// Appends the report's contacts, DCD pairs and its /frames row, then flushes the file.
  /// @throws IoError naming the file when HDF5 fails.
  void append(const FrameReport& report);

  /// For a scene log (header.checks not empty): records the row's check (index into
  /// header.checks) in /frame_check, then appends as above.
  /// @throws IoError naming the file when HDF5 fails or the log has no checks.
  void append(const FrameReport& report, std::int32_t check);

  /// Writes the run's events (/events, /event_parts, /event_bones, and their /checksums row), once,
  /// after the last append and before finish(). A log without them (a run cut short, or written
  /// before events) reads with LogData::events_recorded false.
  /// @throws IoError naming the file when HDF5 fails, the log is finished or already has events.
  void write_events(const std::vector<EventRecord>& events);

  /// Sets the root attribute `complete` to 1 and closes the file. Further calls do nothing.
  void finish();

  [[nodiscard]] const std::filesystem::path& path() const;
  [[nodiscard]] std::int64_t rows_written() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// True when `path` is an HDF5 file whose root attribute `format` is kLogFormatName.
[[nodiscard]] bool is_skelcd_log(const std::filesystem::path& path);

}  // namespace skelcd::tools
