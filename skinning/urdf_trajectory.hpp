#pragma once
// A joint trajectory for a URDF robot, read from CSV, and the Clip it becomes: each moved link's
// local transform keyed at each row's time.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "skinning/rig.hpp"
#include "skinning/urdf.hpp"

namespace skelcd::skinning {

/// Rows of joint positions. CSV: a header `time,<joint name>,...`, then one row per sample:
/// time in seconds (strictly increasing), one position per named joint (radians or metres).
/// Blank lines and lines starting with '#' are skipped.
struct JointTrajectory {
  std::vector<std::int32_t> joints;  ///< robot joint index of each column
  std::vector<double> times;         ///< #rows, seconds, as in the file
  Eigen::MatrixXd positions;         ///< #rows × #columns
  std::string source;                ///< file name, for messages
  [[nodiscard]] Eigen::Index num_rows() const { return positions.rows(); }
};

struct TrajectoryOptions {
  /// Refuse positions outside a revolute or prismatic joint's [lower, upper] limits.
  bool check_limits = true;
};

/// Reads a trajectory CSV for `robot`.
/// @throws IoError when the file cannot be read.
/// @throws InvalidInput naming the file and line for: a header not starting with `time`, an
///   unknown, fixed, mimic or repeated joint name, a row with the wrong number of cells, a cell
///   that is not a finite number, a time not above the previous row's, a position outside the
///   joint's limits (when checked), no data rows.
[[nodiscard]] JointTrajectory read_joint_trajectory(
    const std::filesystem::path& csv_file,
    const Robot& robot,
    const TrajectoryOptions& options = {});

/// The same from CSV text; `source` names it in messages.
[[nodiscard]] JointTrajectory parse_joint_trajectory(
    std::string_view text,
    const std::string& source,
    const Robot& robot,
    const TrajectoryOptions& options = {});

/// Writes `trajectory` as CSV (positions with 17 significant digits: reading it back is exact).
/// @throws IoError when the file cannot be written.
void write_joint_trajectory(
    const std::filesystem::path& csv_file,
    const Robot& robot,
    const JointTrajectory& trajectory);

/// The clip of a trajectory: for every link whose joint is listed (or mimics a listed joint), a
/// channel with the link's local transform joint_transform(joint, q) keyed at each row's time
/// minus the first row's time. Joints not listed stay at 0 (the rest pose).
/// Revolute and continuous joints key rotations: slerp between two keys of a fixed-axis rotation
/// is exactly the rotation by the linearly interpolated angle when the step is below pi, so a
/// step larger than pi/2 is split into equal sub-steps by extra keys on that channel (also added
/// to Clip::key_times). Prismatic joints key translations (lerp is exact).
/// Its frame rate is the rows' (rows - 1) / duration (FrameRateSource::trajectory_rows), so the
/// default motion samples every row when the rows are evenly spaced; extra keys do not count.
/// @pre trajectory was read for `robot`.
[[nodiscard]] Clip trajectory_clip(
    const Robot& robot,
    const JointTrajectory& trajectory,
    const std::string& name);

/// Joint positions (#joints, for forward_kinematics) of row `row`; unlisted joints 0.
[[nodiscard]] std::vector<double> trajectory_row_positions(
    const Robot& robot,
    const JointTrajectory& trajectory,
    Eigen::Index row);

}  // namespace skelcd::skinning
