#include "skinning/urdf_trajectory.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "skinning/errors.hpp"

namespace skelcd::skinning {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_cells(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

}  // namespace

JointTrajectory parse_joint_trajectory(
    std::string_view text,
    const std::string& source,
    const Robot& robot,
    const TrajectoryOptions& options) {
  JointTrajectory trajectory;
  trajectory.source = source;
  std::vector<double> values;  // row-major
  bool have_header = false;
  std::size_t line_number = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view line = trim(text.substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    if (line.empty() || line.front() == '#') continue;
    const std::string where = source + ":" + std::to_string(line_number) + ": ";
    const std::vector<std::string_view> cells = split_cells(line);
    if (!have_header) {
      // Header: time, then joint names.
      if (cells[0] != "time") {
        throw InvalidInput(where + "header must start with 'time', found '" + std::string(cells[0]) + "'");
      }
      std::set<std::int32_t> seen;
      for (std::size_t c = 1; c < cells.size(); ++c) {
        const std::string name(cells[c]);
        const std::int32_t j = robot.find_joint(name);
        if (j < 0) {
          throw InvalidInput(where + "unknown joint '" + name + "' (robot '" + robot.name + "')");
        }
        const RobotJoint& joint = robot.joints[static_cast<std::size_t>(j)];
        if (!joint.movable()) throw InvalidInput(where + "joint '" + name + "' is fixed");
        if (joint.mimic_joint >= 0) {
          throw InvalidInput(where + "joint '" + name + "' mimics joint '" +
                             robot.joints[static_cast<std::size_t>(joint.mimic_joint)].name +
                             "'; give that joint instead");
        }
        if (!seen.insert(j).second) throw InvalidInput(where + "joint '" + name + "' appears twice");
        trajectory.joints.push_back(j);
      }
      have_header = true;
      continue;
    }
    const std::size_t columns = trajectory.joints.size() + 1;
    if (cells.size() != columns) {
      throw InvalidInput(where + "row has " + std::to_string(cells.size()) + " cells, the header has " +
                         std::to_string(columns));
    }
    for (std::size_t c = 0; c < cells.size(); ++c) {
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(cells[c].data(), cells[c].data() + cells[c].size(), v);
      if (cells[c].empty() || ec != std::errc() || ptr != cells[c].data() + cells[c].size() || !std::isfinite(v)) {
        throw InvalidInput(where + "cell " + std::to_string(c + 1) + " ('" + std::string(cells[c]) +
                           "') is not a finite number");
      }
      if (c == 0) {
        if (!trajectory.times.empty() && !(v > trajectory.times.back())) {
          throw InvalidInput(where + "time " + std::string(cells[c]) +
                             " is not after the previous row's time (times must increase)");
        }
        trajectory.times.push_back(v);
      } else {
        const RobotJoint& joint = robot.joints[static_cast<std::size_t>(trajectory.joints[c - 1])];
        if (options.check_limits && joint.has_limits && (v < joint.lower || v > joint.upper)) {
          throw InvalidInput(where + "joint '" + joint.name + "' position " + std::string(cells[c]) +
                             " is outside its limits [" + std::to_string(joint.lower) + ", " +
                             std::to_string(joint.upper) + "]");
        }
        values.push_back(v);
      }
    }
  }
  if (!have_header) throw InvalidInput(source + ": no header line 'time,<joint names>'");
  if (trajectory.times.empty()) throw InvalidInput(source + ": no data rows after the header");
  const auto rows = static_cast<Eigen::Index>(trajectory.times.size());
  const auto cols = static_cast<Eigen::Index>(trajectory.joints.size());
  trajectory.positions.resize(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) trajectory.positions(r, c) = values[static_cast<std::size_t>(r * cols + c)];
  }
  return trajectory;
}

JointTrajectory read_joint_trajectory(
    const std::filesystem::path& csv_file,
    const Robot& robot,
    const TrajectoryOptions& options) {
  std::ifstream in(csv_file, std::ios::binary);
  if (!in) throw IoError(csv_file.string() + ": cannot open trajectory file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(csv_file.string() + ": cannot read trajectory file");
  return parse_joint_trajectory(text.str(), csv_file.string(), robot, options);
}

void write_joint_trajectory(
    const std::filesystem::path& csv_file,
    const Robot& robot,
    const JointTrajectory& trajectory) {
  std::ostringstream out;
  out << "time";
  for (const std::int32_t j : trajectory.joints) out << ',' << robot.joints[static_cast<std::size_t>(j)].name;
  out << '\n';
  char buffer[64];
  const auto put = [&](double v) {
    const int n = std::snprintf(buffer, sizeof buffer, "%.17g", v);
    out.write(buffer, n);
  };
  for (Eigen::Index r = 0; r < trajectory.num_rows(); ++r) {
    put(trajectory.times[static_cast<std::size_t>(r)]);
    for (Eigen::Index c = 0; c < trajectory.positions.cols(); ++c) {
      out << ',';
      put(trajectory.positions(r, c));
    }
    out << '\n';
  }
  std::ofstream file(csv_file, std::ios::binary);
  if (!file) throw IoError(csv_file.string() + ": cannot write trajectory file");
  file << out.str();
  if (!file.flush()) throw IoError(csv_file.string() + ": cannot write trajectory file");
}

std::vector<double> trajectory_row_positions(
    const Robot& robot,
    const JointTrajectory& trajectory,
    Eigen::Index row) {
  std::vector<double> q(robot.joints.size(), 0.0);
  for (std::size_t c = 0; c < trajectory.joints.size(); ++c) {
    q[static_cast<std::size_t>(trajectory.joints[c])] = trajectory.positions(row, static_cast<Eigen::Index>(c));
  }
  return resolve_mimic(robot, q);
}

Clip trajectory_clip(const Robot& robot, const JointTrajectory& trajectory, const std::string& name) {
  Clip clip;
  clip.name = name;
  const std::size_t rows = trajectory.times.size();
  const double t0 = trajectory.times.front();
  clip.duration_s = trajectory.times.back() - t0;
  // The rows are the trajectory's frames: sampled at their mean rate, which is every row when
  // they are evenly spaced (keys added between rows below do not count).
  if (rows > 1 && clip.duration_s > 0) {
    clip.frame_rate_hz = static_cast<double>(rows - 1) / clip.duration_s;
    clip.frame_rate_source = FrameRateSource::trajectory_rows;
  }

  // Which joints move: the listed ones and the mimic joints whose master chain ends at one.
  std::vector<bool> listed(robot.joints.size(), false);
  for (const std::int32_t j : trajectory.joints) listed[static_cast<std::size_t>(j)] = true;
  std::vector<std::vector<double>> q_rows(rows);
  for (std::size_t r = 0; r < rows; ++r) q_rows[r] = trajectory_row_positions(robot, trajectory, static_cast<Eigen::Index>(r));

  std::set<double> key_times;
  for (std::size_t r = 0; r < rows; ++r) key_times.insert(trajectory.times[r] - t0);

  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const RobotJoint& joint = robot.joints[j];
    if (!joint.movable()) continue;
    std::int32_t master = static_cast<std::int32_t>(j);
    while (robot.joints[static_cast<std::size_t>(master)].mimic_joint >= 0) {
      master = robot.joints[static_cast<std::size_t>(master)].mimic_joint;
    }
    if (!listed[static_cast<std::size_t>(master)]) continue;

    Channel channel;
    channel.node = joint.child_link;  // skeleton node i is link i
    const Eigen::Quaterniond origin_rotation(joint.origin.rotation());
    if (joint.type == JointType::kPrismatic) {
      // Translation keys, one per row: lerp between them is exactly the joint's linear motion.
      channel.rotation_times = {0.0};
      channel.rotations = {origin_rotation};
      for (std::size_t r = 0; r < rows; ++r) {
        channel.translation_times.push_back(trajectory.times[r] - t0);
        channel.translations.push_back(joint_transform(joint, q_rows[r][j]).translation());
      }
    } else {
      // Rotation keys: origin · R(axis, q). Slerp between R(axis, qa) and R(axis, qb) turns about
      // the same axis by the shorter way, which is q linear in time while |qb - qa| < pi; steps
      // above pi/2 get equally spaced extra keys, keeping every slerp step at most pi/2.
      channel.translation_times = {0.0};
      channel.translations = {joint.origin.translation()};
      const auto push = [&](double t, double q) {
        Eigen::Quaterniond rotation = origin_rotation * Eigen::Quaterniond(Eigen::AngleAxisd(q, joint.axis));
        if (!channel.rotations.empty() && channel.rotations.back().dot(rotation) < 0.0) {
          rotation.coeffs() = -rotation.coeffs();  // keep the sign continuous for the shorter arc
        }
        channel.rotation_times.push_back(t);
        channel.rotations.push_back(rotation);
      };
      for (std::size_t r = 0; r < rows; ++r) {
        const double t = trajectory.times[r] - t0;
        const double q = q_rows[r][j];
        if (r > 0) {
          const double t_prev = trajectory.times[r - 1] - t0;
          const double q_prev = q_rows[r - 1][j];
          const double steps = std::ceil(std::abs(q - q_prev) / (std::numbers::pi / 2));
          for (double s = 1; s < steps; ++s) {
            const double u = s / steps;
            const double ts = t_prev + u * (t - t_prev);
            push(ts, q_prev + u * (q - q_prev));
            key_times.insert(ts);
          }
        }
        push(t, q);
      }
    }
    clip.channels.push_back(std::move(channel));
  }
  clip.key_times.assign(key_times.begin(), key_times.end());
  return clip;
}

}  // namespace skelcd::skinning
