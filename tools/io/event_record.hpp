#pragma once
// One collision event as the log's /events table stores it (docs/events.md, docs/log-format.md);
// engine/events.hpp makes them, the log writes and reads them.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace skelcd::tools {

/// One collision event: a connected region of new intersecting triangles (and the CCD contacts
/// between them) tracked over consecutive samples. Stored as a row of the log's /events table.
struct EventRecord {
  std::int32_t id = 0;            ///< 0, 1, … in order of first appearance; the findings' label
  std::int32_t first_sample = 0;  ///< the first sample it touches: where DCD first finds it, or
                                  ///< the start of the interval in which CCD first finds it
  std::int32_t last_sample = 0;   ///< the last sample it touches
  double t_first = 0;             ///< time of first_sample, seconds
  double t_last = 0;              ///< time of last_sample, seconds
  /// Time of first contact (seconds) when the event starts between two samples and CCD ran: the
  /// earliest lower bound of its contacts' times of impact in that interval.
  std::optional<double> t_first_contact;
  std::vector<std::int32_t> parts;  ///< part ids (index into the log's /parts), ascending
  /// Bones driving its triangles (the bone with the largest skin weight over a triangle's corners;
  /// a robot's links), most triangles first; empty when the model has no skeleton.
  std::vector<std::string> bones;
  std::int64_t peak_pairs = 0;    ///< most new DCD pairs at one sample
  std::int32_t peak_sample = -1;  ///< the sample with peak_pairs (-1 when it had none)
  std::int64_t dcd_pairs = 0;     ///< new DCD pairs summed over its samples
  std::int64_t ccd_contacts = 0;  ///< new CCD contacts summed over its intervals
  /// Depth measure: the largest length, over its samples, of the intersection curve (the summed
  /// lengths of its pairs' intersection segments), in model units; 0 for an event CCD alone found.
  double depth = 0;
  std::int32_t merged_into = -1;  ///< the event it ran into (its last sample is before that), or -1
  friend bool operator==(const EventRecord&, const EventRecord&) = default;
};

}  // namespace skelcd::tools
