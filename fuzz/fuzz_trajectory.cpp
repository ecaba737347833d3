// libFuzzer harness: joint trajectory CSV (skinning/urdf_trajectory.hpp, parse_joint_trajectory)
// for the bundled Panda (loaded once), with joint limits checked; an accepted trajectory is also
// turned into a clip (trajectory_clip), which is the next thing every caller does with it.
// A thrown std::exception is the parser refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz/fuzz_input.hpp"
#include "skinning/generators_panda.hpp"
#include "skinning/urdf_trajectory.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const skelcd::skinning::Robot panda = skelcd::skinning::load_bundled_panda();
  try {
    const auto trajectory = skelcd::skinning::parse_joint_trajectory(
        skelcd::fuzz::as_text(data, size), "fuzz.csv", panda);
    // Keep the clip small: a long accepted trajectory is not a finding by itself.
    if (trajectory.num_rows() <= 4096) {
      (void)skelcd::skinning::trajectory_clip(panda, trajectory, "fuzz");
    }
  } catch (const std::exception&) {
  }
  return 0;
}
