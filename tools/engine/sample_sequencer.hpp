#pragma once
// The row order of every check, self or pair, serial or a block of a parallel run: at each sample
// k of [first, end) the DCD at k (when asked), then the CCD interval k → k+1 (when asked and
// k < last). Each sample is posed once, into the slot of the interval's end; the caller's query
// functions read the two slots. One place, so that the runner and the scene's pair checks cannot
// drift apart (issue: "one sample sequencer").

#include <cstdint>
#include <utility>

namespace skelcd::tools {

/// What a sequence runs: which queries, over which samples.
struct SampleSequence {
  std::int32_t first = 0;  ///< first sample of this sequence (a block's first)
  std::int32_t end = 0;    ///< one past its last sample "unit" k
  std::int32_t last = 0;   ///< the run's last sample (CCD k → k+1 only for k < last)
  bool dcd = true;
  bool ccd = true;
};

/// Runs `s`: `pose(k, end_slot)` poses sample k into slot `end_slot` (0 or 1) and returns the
/// microseconds it took; `dcd(k, slot, skin_us)` queries the instant held in `slot`;
/// `ccd(k, start_slot, end_slot, skin_us)` the interval k → k+1. Posing time is charged to the
/// first row that needs the sample.
template <class Pose, class Dcd, class Ccd>
void run_sequence(const SampleSequence& s, Pose&& pose, Dcd&& dcd, Ccd&& ccd) {
  int now = 1;  // slot of the latest posed sample
  double pending_skin_us = pose(s.first, now);
  for (std::int32_t k = s.first; k < s.end; ++k) {
    if (s.dcd) {
      if (k > s.first && !s.ccd) pending_skin_us += pose(k, now);
      dcd(k, now, std::exchange(pending_skin_us, 0.0));
    }
    if (s.ccd && k < s.last) {
      now = 1 - now;
      pending_skin_us += pose(k + 1, now);
      ccd(k, 1 - now, now, std::exchange(pending_skin_us, 0.0));
    }
  }
}

}  // namespace skelcd::tools
