#include "clustering/mega_clusters.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::clustering {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::int64_t kNoLimit = std::numeric_limits<std::int64_t>::max();

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

double micros(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

Eigen::Vector3d apply(const skinning::BoneTransform& T, const Eigen::Vector3d& p) {
  return T.leftCols<3>() * p + T.col(3);
}

/// A draw in [0, n) from a 64-bit generator (modulo: the bias is below n / 2⁶⁴). Unlike
/// std::uniform_int_distribution its values are the same with every standard library, so a seed
/// means the same clusters everywhere.
std::size_t draw(std::mt19937_64& rng, std::size_t n) {
  return static_cast<std::size_t>(rng() % static_cast<std::uint64_t>(n));
}

}  // namespace

std::int64_t merge_limit(std::int64_t size, double gamma) {
  if (size <= 0) return 1;  // D of an empty cluster is taken as 0: it always joins
  if (!(gamma > 0.0)) return 0;
  const auto n_size = static_cast<double>(size);
  if (gamma > 1.0) return size + 1;
  // The smallest n with n / size >= gamma, evaluated exactly as D is (double division).
  auto n = static_cast<std::int64_t>(std::ceil(gamma * n_size));
  while (n > 0 && static_cast<double>(n - 1) / n_size >= gamma) --n;
  while (static_cast<double>(n) / n_size < gamma) ++n;
  return n;
}

void pose_observers(
    const ClusterSet& clusters,
    std::span<const skinning::BoneTransform> t0,
    std::span<const skinning::BoneTransform> t1,
    IntervalObservers& out) {
  const std::int32_t num_atomic = clusters.num_atomic();
  const auto check = [&](std::int32_t bone) {
    if (bone < 0 || at(bone) >= t0.size() || at(bone) >= t1.size()) {
      throw InvalidInput(
          "clustering: bone " + std::to_string(bone) + " has no transform (" +
          std::to_string(t0.size()) + " and " + std::to_string(t1.size()) + " given)");
    }
  };
  out.atomic.resize(at(num_atomic));
  for (std::int32_t a = 0; a < num_atomic; ++a) {
    const std::int32_t b = clusters.bone(a);
    check(b);
    const auto& rest = clusters.observer(a);
    auto& o = out.atomic[at(a)];
    o.kind = rest.kind;
    if (rest.kind == segmentation::ObserverKind::point) {
      const Eigen::Vector3d mid = rest.segment.midpoint();
      o.point = {apply(t0[at(b)], mid), apply(t1[at(b)], mid)};
    } else {
      o.segment = {apply(t0[at(b)], rest.segment.head), apply(t0[at(b)], rest.segment.tail),
                   apply(t1[at(b)], rest.segment.head), apply(t1[at(b)], rest.segment.tail)};
    }
  }
  const auto joints = clusters.joints();
  out.joints.resize(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    check(joints[j].bone);
    out.joints[j] = {apply(t0[at(joints[j].bone)], joints[j].rest),
                     apply(t1[at(joints[j].bone)], joints[j].rest)};
  }
}

MegaClusterBuilder::MegaClusterBuilder(const ClusterSet& clusters, const MegaClusterOptions& options)
    : clusters_(clusters), options_(options) {
  const auto num_atomic = at(clusters.num_atomic());
  previous_offsets_.assign(num_atomic + 1, 0);
  stamp_.assign(at(clusters.num_triangles()), 0);
  unplaced_.reserve(num_atomic);
  unplaced_slot_.assign(num_atomic, -1);
  queue_.reserve(num_atomic + 2 * clusters.joints().size());
  tried_by_.assign(num_atomic, 0);
  joint_offsets_.assign(1, 0);
  for (std::int32_t a = 0; a < clusters.num_atomic(); ++a) {
    const auto first = joint_ids_.size();
    for (const ClusterNeighbour& nb : clusters.neighbours(a)) {
      if (std::find(
              joint_ids_.begin() + static_cast<std::ptrdiff_t>(first), joint_ids_.end(), nb.edge) ==
          joint_ids_.end()) {
        joint_ids_.push_back(nb.edge);
      }
    }
    joint_offsets_.push_back(static_cast<std::int32_t>(joint_ids_.size()));
  }
  joint_failed_.assign(joint_ids_.size(), 0);
  joint_failures_.resize(joint_ids_.size());
}

std::int32_t MegaClusterBuilder::joint_slot(std::int32_t a, std::int32_t e) const {
  for (auto i = joint_offsets_[at(a)]; i < joint_offsets_[at(a) + 1]; ++i) {
    if (joint_ids_[at(i)] == e) return i;
  }
  return -1;
}

bool MegaClusterBuilder::evaluate_at_joint(
    std::int32_t a,
    std::int32_t e,
    const MovingObserver& joint,
    std::int64_t limit,
    IntervalClasses& out) {
  const std::int32_t slot = joint_slot(a, e);
  if (slot < 0) return evaluate(a, joint, limit, out);
  std::vector<std::int32_t>& failed_on = joint_failures_[at(slot)];
  const bool passed = evaluate(a, joint, limit, out, failed_on);
  joint_failed_[at(slot)] = passed ? 0 : 1;
  // A failure's non-positive triangles (at most `limit`): the next evaluation here starts there.
  failed_on.assign(passed ? found_.end() : found_.begin(), found_.end());
  return passed;
}

bool MegaClusterBuilder::evaluate(
    std::int32_t a,
    const MovingObserver& observer,
    std::int64_t limit,
    IntervalClasses& out,
    std::span<const std::int32_t> first) {
  const auto start = Clock::now();
  found_.clear();
  if (++evaluation_ == 0) {  // the stamps wrapped around: clear them once
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    evaluation_ = 1;
  }
  const auto& F = *triangles_;
  const auto& x0 = *x_t0_;
  const auto& x1 = *x_t1_;
  std::int64_t non_positive = 0;
  std::int64_t classified = 0;
  bool below = true;
  const bool point = observer.kind == segmentation::ObserverKind::point;
  const auto classify_scalar = [&](std::int32_t f) {
    const Eigen::Index i = f;
    const MovingTriangle t{x0.row(F(i, 0)).transpose(), x0.row(F(i, 1)).transpose(),
                           x0.row(F(i, 2)).transpose(), x1.row(F(i, 0)).transpose(),
                           x1.row(F(i, 1)).transpose(), x1.row(F(i, 2)).transpose()};
    return point ? classify(t, observer.point) : classify(t, observer.segment);
  };
  const auto record = [&](std::int32_t f, OrientationClass c) {
    out.triangle_class[at(f)] = c;
    stamp_[at(f)] = evaluation_;
    ++classified;
    if (c != OrientationClass::positive) {
      ++non_positive;
      found_.push_back(f);
    }
    return non_positive < limit;
  };
  // The triangles are screened four at a time (screen_classes_x4: the classes classify gives
  // where the screens settle them, classify itself for the others) and recorded one by one in
  // the same order, up to the same one: what is recorded is what one at a time records.
  std::array<std::int32_t, 4> batch{};
  std::size_t in_batch = 0;
  const auto flush = [&] {
    if (in_batch == 0) return true;
    ccd::FaceCorners c0{}, c1{};
    for (std::size_t k = 0; k < 4; ++k) {
      const Eigen::Index i = batch[std::min(k, in_batch - 1)];  // spare lanes repeat the last
      for (std::size_t j = 0; j < 3; ++j) {
        const Eigen::Index row = F(i, static_cast<Eigen::Index>(j));
        c0[k][j] = x0.data() + 3 * row;
        c1[k][j] = x1.data() + 3 * row;
      }
    }
    const ScreenedClasses screened = point ? screen_classes_x4(c0, c1, observer.point)
                                           : screen_classes_x4(c0, c1, observer.segment);
    const std::size_t n = in_batch;
    in_batch = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::int32_t f = batch[k];
      const OrientationClass c =
          ((screened.settled >> k) & 1u) != 0 ? screened.classes[k] : classify_scalar(f);
      if (!record(f, c)) return false;
    }
    return true;
  };
  const auto classify_one = [&](std::int32_t f) {
    batch[in_batch++] = f;
    return in_batch < 4 || flush();
  };
  // The triangles a failing evaluation against this observer found last, then last interval's
  // non-positive triangles: they decide most failing merges early. Each list's stamps are set
  // before the next is looked at.
  for (auto i = first.begin(); i != first.end() && below; ++i) below = classify_one(*i);
  below = below && flush();
  const auto p_begin = previous_offsets_[at(a)];
  const auto p_end = previous_offsets_[at(a) + 1];
  for (auto i = p_begin; i < p_end && below; ++i) {
    if (stamp_[at(previous_[at(i)])] != evaluation_) below = classify_one(previous_[at(i)]);
  }
  below = below && flush();
  if (below) {
    for (const std::int32_t f : clusters_.triangles(a)) {
      if (stamp_[at(f)] == evaluation_) continue;
      if (!classify_one(f)) {
        below = false;
        break;
      }
    }
    below = below && flush();
  }
  out.classifications += classified;
  out.classify_us += micros(start, Clock::now());
  return below;
}

void MegaClusterBuilder::remember_non_positive(IntervalClasses& out) {
  const std::int32_t num_atomic = clusters_.num_atomic();
  next_offsets_.assign(at(num_atomic) + 1, 0);
  next_.clear();
  for (std::int32_t a = 0; a < num_atomic; ++a) {
    for (const std::int32_t f : clusters_.triangles(a)) {
      const OrientationClass c = out.triangle_class[at(f)];
      if (c == OrientationClass::positive) continue;
      next_.push_back(f);
      (c == OrientationClass::negative ? out.h_minus : out.h_uncertain) += 1;
    }
    next_offsets_[at(a) + 1] = static_cast<std::int32_t>(next_.size());
  }
  std::swap(previous_offsets_, next_offsets_);
  std::swap(previous_, next_);
}

void MegaClusterBuilder::build(
    const skinning::Triangles& triangles,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const IntervalObservers& observers,
    IntervalClasses& out) {
  const auto start = Clock::now();
  triangles_ = &triangles;
  x_t0_ = &x_t0;
  x_t1_ = &x_t1;
  const std::int32_t num_atomic = clusters_.num_atomic();
  out.triangle_class.resize(at(clusters_.num_triangles()));
  out.atomic_mega.assign(at(num_atomic), -1);
  out.mega_observer.clear();
  out.mega_offsets.assign(1, 0);
  out.mega_members.clear();
  out.h_minus = 0;
  out.h_uncertain = 0;
  out.classifications = 0;
  out.merge_attempts = 0;
  out.classify_us = 0.0;
  out.merge_us = 0.0;

  const auto open_mega = [&](std::int32_t a, const MovingObserver& observer) {
    out.atomic_mega[at(a)] = out.num_mega();
    out.mega_members.push_back(a);
    out.mega_observer.push_back(observer);
  };
  const auto close_mega = [&] {
    out.mega_offsets.push_back(static_cast<std::int32_t>(out.mega_members.size()));
  };

  if (!options_.merge) {
    // rvbc: the atomic clusters as they are, each against its own observer.
    for (std::int32_t a = 0; a < num_atomic; ++a) {
      (void)evaluate(a, observers.atomic[at(a)], kNoLimit, out);
      open_mega(a, observers.atomic[at(a)]);
      close_mega();
    }
    remember_non_positive(out);
    out.merge_us = 0.0;
    return;
  }

  // dynamic (§5). Unplaced clusters in a swap-remove list (O(1) removal, deterministic order).
  unplaced_.clear();
  for (std::int32_t a = 0; a < num_atomic; ++a) {
    unplaced_slot_[at(a)] = a;
    unplaced_.push_back(a);
  }
  const auto place = [&](std::int32_t a) {
    const auto slot = at(unplaced_slot_[at(a)]);
    const std::int32_t last = unplaced_.back();
    unplaced_[slot] = last;
    unplaced_slot_[at(last)] = static_cast<std::int32_t>(slot);
    unplaced_.pop_back();
    unplaced_slot_[at(a)] = -1;
  };
  const auto placed = [&](std::int32_t a) { return unplaced_slot_[at(a)] < 0; };
  const auto limit = [&](std::int32_t a) {
    return merge_limit(static_cast<std::int64_t>(clusters_.triangles(a).size()), options_.gamma);
  };
  // tried_by_[a] == mega stamp: a was rejected by the mega cluster being grown (stamps are unique
  // over the builder's life: they never need clearing).
  std::mt19937_64 rng(options_.seed);

  while (!unplaced_.empty()) {
    // A random seed atomic cluster becomes a mega cluster.
    const std::int32_t seed = unplaced_[draw(rng, unplaced_.size())];
    place(seed);
    if (++mega_stamp_ == 0) {  // wrapped around: clear the stamps once
      std::fill(tried_by_.begin(), tried_by_.end(), 0u);
      mega_stamp_ = 1;
    }
    const std::uint32_t stamp = mega_stamp_;

    // The second atomic cluster decides the observer: the joint its bone shares with the seed's.
    // Both must stay below γ against that joint (the seed's triangles are re-classified too:
    // they are no longer seen from their own primitive).
    MovingObserver joint;
    joint.kind = segmentation::ObserverKind::point;
    std::int32_t second = -1;
    std::int32_t joint_edge = -1;
    // The seed's classes are for seed_joint (it passed there) until it is classified again; the
    // joints it failed at need no neighbour classified.
    std::int32_t seed_joint = -1;
    seed_failed_.clear();
    const auto seed_passes = [&](std::int32_t e) {
      if (seed_joint == e) return true;
      seed_joint = -1;
      if (!evaluate_at_joint(seed, e, joint, limit(seed), out)) {
        seed_failed_.push_back(e);
        return false;
      }
      seed_joint = e;
      return true;
    };
    for (const ClusterNeighbour& nb : clusters_.neighbours(seed)) {
      if (placed(nb.cluster)) continue;
      ++out.merge_attempts;
      const std::int32_t e = nb.edge;
      if (std::find(seed_failed_.begin(), seed_failed_.end(), e) != seed_failed_.end()) continue;
      joint.point = observers.joints[at(e)];
      // Both must pass; the seed first when it failed here last interval and the neighbour
      // did not.
      const auto failed_before = [&](std::int32_t a) {
        const std::int32_t slot = joint_slot(a, e);
        return slot >= 0 && joint_failed_[at(slot)] != 0;
      };
      const bool seed_first = seed_joint != e && failed_before(seed) && !failed_before(nb.cluster);
      if (seed_first && !seed_passes(e)) continue;
      if (!evaluate_at_joint(nb.cluster, e, joint, limit(nb.cluster), out)) continue;
      if (!seed_passes(e)) continue;
      second = nb.cluster;
      joint_edge = e;
      break;
    }
    if (second < 0) {
      // Nothing joins: the seed keeps its own observer (point or line).
      (void)evaluate(seed, observers.atomic[at(seed)], kNoLimit, out);
      open_mega(seed, observers.atomic[at(seed)]);
      close_mega();
      continue;
    }
    open_mega(seed, joint);
    place(second);
    out.atomic_mega[at(second)] = out.num_mega() - 1;
    out.mega_members.push_back(second);

    // Grow breadth-first over neighbours, the observer fixed at the joint.
    queue_.clear();
    const auto push_neighbours = [&](std::int32_t a) {
      for (const ClusterNeighbour& nb : clusters_.neighbours(a)) {
        if (!placed(nb.cluster) && tried_by_[at(nb.cluster)] != stamp) queue_.push_back(nb.cluster);
      }
    };
    push_neighbours(seed);
    push_neighbours(second);
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const std::int32_t c = queue_[head];
      if (placed(c) || tried_by_[at(c)] == stamp) continue;
      tried_by_[at(c)] = stamp;
      ++out.merge_attempts;
      if (!evaluate_at_joint(c, joint_edge, joint, limit(c), out)) continue;
      place(c);
      out.atomic_mega[at(c)] = out.num_mega() - 1;
      out.mega_members.push_back(c);
      push_neighbours(c);
    }
    close_mega();
  }
  remember_non_positive(out);
  out.merge_us = std::max(0.0, micros(start, Clock::now()) - out.classify_us);
}

}  // namespace skelcd::clustering
