#include "skinning/pose.hpp"

#include <algorithm>
#include <cassert>

#include "skinning/errors.hpp"

namespace skelcd::skinning {
namespace {

// Index k of the key interval [times[k], times[k+1]] holding t, and the fraction of the way
// through it; callers handle t outside the keys first.
std::pair<std::size_t, double> locate(std::span<const double> times, double t) {
  const auto upper = std::upper_bound(times.begin(), times.end(), t);
  const auto k = static_cast<std::size_t>(upper - times.begin()) - 1;
  const double a = (t - times[k]) / (times[k + 1] - times[k]);
  return {k, a};
}

Eigen::Affine3d compose_trs(const Eigen::Vector3d& t, const Eigen::Quaterniond& r, const Eigen::Vector3d& s) {
  Eigen::Affine3d m = Eigen::Affine3d::Identity();
  m.linear() = r.toRotationMatrix() * s.asDiagonal();
  m.translation() = t;
  return m;
}

BoneTransform to_bone_transform(const Eigen::Affine3d& m) { return m.matrix().topRows<3>(); }

}  // namespace

Eigen::Vector3d interpolate_vector(
    std::span<const double> times,
    std::span<const Eigen::Vector3d> values,
    double t) {
  assert(!times.empty() && times.size() == values.size());
  if (!(t > times.front())) return values.front();
  if (!(t < times.back())) return values.back();
  const auto [k, a] = locate(times, t);
  return (1.0 - a) * values[k] + a * values[k + 1];
}

Eigen::Quaterniond interpolate_rotation(
    std::span<const double> times,
    std::span<const Eigen::Quaterniond> values,
    double t) {
  assert(!times.empty() && times.size() == values.size());
  if (!(t > times.front())) return values.front();
  if (!(t < times.back())) return values.back();
  const auto [k, a] = locate(times, t);
  // Eigen's slerp follows the shorter arc (it flips the sign of a negative dot product).
  return values[k].slerp(a, values[k + 1]).normalized();
}

PoseEvaluator::PoseEvaluator(const Rig& rig) : rig_(&rig) {
  validate_rig(rig);
  const auto& nodes = rig.skeleton.nodes;
  const auto nn = nodes.size();
  rest_translation_.resize(nn);
  rest_rotation_.resize(nn);
  rest_scale_.resize(nn);
  rest_global_.resize(nn);
  for (std::size_t i = 0; i < nn; ++i) {
    const auto& local = nodes[i].rest_local;
    Eigen::Matrix3d rotation;
    Eigen::Matrix3d scaling;
    local.computeRotationScaling(&rotation, &scaling);
    rest_translation_[i] = local.translation();
    rest_rotation_[i] = Eigen::Quaterniond(rotation).normalized();
    rest_scale_[i] = scaling.diagonal();
    const auto parent = nodes[i].parent;
    rest_global_[i] = (parent < 0 ? rig.skeleton.root_transform : rest_global_[static_cast<std::size_t>(parent)]) * local;
  }
  channel_of_node_.resize(rig.clips.size());
  for (std::size_t c = 0; c < rig.clips.size(); ++c) {
    auto& map = channel_of_node_[c];
    map.assign(nn, -1);
    const auto& channels = rig.clips[c].channels;
    for (std::size_t k = 0; k < channels.size(); ++k) {
      auto& slot = map[static_cast<std::size_t>(channels[k].node)];
      if (slot >= 0) {
        throw InvalidInput(rig.source + ": clip '" + rig.clips[c].name + "' has two channels for node '" +
                           nodes[static_cast<std::size_t>(channels[k].node)].name + "'");
      }
      slot = static_cast<std::int32_t>(k);
    }
  }
}

std::int32_t PoseEvaluator::num_transforms() const {
  return rig_->skeleton.num_bones() + rig_->mesh.num_parts();
}

void PoseEvaluator::prepare(Pose& pose) const {
  pose.node_global.resize(rig_->skeleton.nodes.size());
  pose.transforms.resize(static_cast<std::size_t>(num_transforms()));
}

void PoseEvaluator::finish(Pose& pose) const {
  // node_global holds local transforms here; parents precede children, so one forward pass
  // turns them into globals.
  const auto& nodes = rig_->skeleton.nodes;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto parent = nodes[i].parent;
    const Eigen::Affine3d& above = parent < 0 ? rig_->skeleton.root_transform : pose.node_global[static_cast<std::size_t>(parent)];
    pose.node_global[i] = above * pose.node_global[i];
  }
  const auto& bones = rig_->skeleton.bones;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    pose.transforms[b] = to_bone_transform(pose.node_global[static_cast<std::size_t>(bones[b].node)] * bones[b].inverse_bind);
  }
  const auto np = static_cast<std::size_t>(rig_->mesh.num_parts());
  for (std::size_t p = 0; p < np; ++p) {
    auto& t = pose.transforms[bones.size() + p];
    if (p < rig_->part_attachments.size() && rig_->part_attachments[p].node >= 0) {
      const auto& a = rig_->part_attachments[p];
      t = to_bone_transform(pose.node_global[static_cast<std::size_t>(a.node)] * a.inverse_bind);
    } else {
      t = BoneTransform::Identity();
    }
  }
}

void PoseEvaluator::rest_pose(Pose& pose) const {
  prepare(pose);
  const auto& nodes = rig_->skeleton.nodes;
  for (std::size_t i = 0; i < nodes.size(); ++i) pose.node_global[i] = nodes[i].rest_local;
  finish(pose);
}

void PoseEvaluator::bind_pose(Pose& pose) const {
  prepare(pose);
  std::copy(rest_global_.begin(), rest_global_.end(), pose.node_global.begin());
  const auto& bones = rig_->skeleton.bones;
  for (const auto& bone : bones) {
    pose.node_global[static_cast<std::size_t>(bone.node)] = bone.inverse_bind.inverse();
  }
  for (std::size_t b = 0; b < bones.size(); ++b) {
    pose.transforms[b] = to_bone_transform(pose.node_global[static_cast<std::size_t>(bones[b].node)] * bones[b].inverse_bind);
  }
  // Unweighted vertices at rest: their attachments' nodes at rest.
  const auto np = static_cast<std::size_t>(rig_->mesh.num_parts());
  for (std::size_t p = 0; p < np; ++p) {
    auto& t = pose.transforms[bones.size() + p];
    if (p < rig_->part_attachments.size() && rig_->part_attachments[p].node >= 0) {
      const auto& a = rig_->part_attachments[p];
      t = to_bone_transform(rest_global_[static_cast<std::size_t>(a.node)] * a.inverse_bind);
    } else {
      t = BoneTransform::Identity();
    }
  }
}

void PoseEvaluator::clip_pose(std::int32_t clip, double time_s, Pose& pose) const {
  assert(clip >= 0 && static_cast<std::size_t>(clip) < rig_->clips.size());
  prepare(pose);
  const auto& channels = rig_->clips[static_cast<std::size_t>(clip)].channels;
  const auto& map = channel_of_node_[static_cast<std::size_t>(clip)];
  const auto& nodes = rig_->skeleton.nodes;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto k = map[i];
    if (k < 0) {
      pose.node_global[i] = nodes[i].rest_local;
      continue;
    }
    const auto& ch = channels[static_cast<std::size_t>(k)];
    const Eigen::Vector3d t = ch.translations.empty() ? rest_translation_[i] : interpolate_vector(ch.translation_times, ch.translations, time_s);
    const Eigen::Quaterniond r = ch.rotations.empty() ? rest_rotation_[i] : interpolate_rotation(ch.rotation_times, ch.rotations, time_s);
    const Eigen::Vector3d s = ch.scales.empty() ? rest_scale_[i] : interpolate_vector(ch.scale_times, ch.scales, time_s);
    pose.node_global[i] = compose_trs(t, r, s);
  }
  finish(pose);
}

}  // namespace skelcd::skinning
