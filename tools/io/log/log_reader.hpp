#pragma once
// Reads a skelcd log (docs/log-format.md), complete or left behind by a run that was killed.

#include <filesystem>
#include <string>
#include <vector>

#include "tools/io/event_record.hpp"
#include "tools/io/frame_report.hpp"
#include "tools/io/log/log_header.hpp"

namespace skelcd::tools {

struct LogData {
  LogHeader header;
  std::vector<FrameRow> frames;       ///< /frames, in file order
  std::vector<ContactRow> contacts;   ///< /contacts (empty unless ReadLogOptions::findings)
  std::vector<DcdPairRow> dcd_pairs;  ///< /dcd_pairs (empty unless ReadLogOptions::findings)
  /// /frame_check of a scene log: the check (index into header.checks) of each /frames row, in
  /// file order (empty for other logs).
  std::vector<std::int32_t> frame_checks;
  /// /events with their parts and bones (docs/events.md), by id. Empty unless events_recorded.
  std::vector<EventRecord> events;
  /// True when the log holds its events: written at the end of a run by a skelcd that labels
  /// findings. False for a log written before events existed (header.baseline empty, findings
  /// labelled kLabelNone), for a run cut short before its end, and for a damaged log (its events
  /// come after the damage): `events` then says nothing, not "no events".
  bool events_recorded = false;
  /// True when the log carries /checksums (logs written since checksums were added) and every
  /// row it covers matched. Rows after the last checksum row (a run killed mid-flush) are read
  /// unverified either way.
  bool verified = false;
  /// What failed verification, one sentence each ("/dcd_pairs rows 1024 to 2047 fail their
  /// checksum"). Every table is then cut back to the last verified checksum row, so what is
  /// read is what was written before the damage.
  std::vector<std::string> damage;
};

struct ReadLogOptions {
  /// Also read /contacts and /dcd_pairs (a batch summary needs only the header and /frames).
  bool findings = true;
  /// Read the file in a child process, which sends the log back: HDF5 itself crashes, loops or
  /// allocates without bound on some malformed files (fuzz/crashes/hdf5/), which then costs one
  /// line, not the process, and this process never opens the file with HDF5. Off only for fuzzing
  /// the reader in-process.
  bool isolate = true;
};

/// Reads the log at `path`, verifying its rows against /checksums (see LogData::damage).
/// @throws IoError naming `path` and the fault when it is missing, not HDF5, not a skelcd log
/// (no `format` attribute equal to "skelcd-log"), of a newer format version, or so damaged that
/// HDF5 cannot read its structure.
[[nodiscard]] LogData read_log(
    const std::filesystem::path& path, const ReadLogOptions& options = {});

}  // namespace skelcd::tools
