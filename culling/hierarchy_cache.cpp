#include "culling/hierarchy_cache.hpp"

#include <cstring>
#include <exception>
#include <future>
#include <memory>
#include <string>

#include "culling/feature_topology.hpp"
#include "culling/traversal.hpp"

namespace skelcd::culling {

struct HierarchyCache::Entry {
  int volume_axes = 0;  // N
  skinning::Triangles triangles;
  skinning::Positions positions;
  bool whole = true;  // built over every triangle, not a subset
  std::vector<std::int32_t> subset;
  BvhOptions options;
  /// The tree (a Bvh<volume_axes>), once built; its build's exception otherwise.
  std::shared_future<std::shared_ptr<const void>> tree;
  /// A hand-over cache's tree instead (a Bvh<volume_axes>), lent while a caller holds it.
  std::shared_ptr<void> lent;
};

namespace {

template <typename Matrix>
bool same_bytes(const Matrix& a, const Matrix& b) {
  using Scalar = typename Matrix::Scalar;
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         (a.size() == 0 ||
          std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(Scalar)) ==
              0);
}

}  // namespace

HierarchyCache::HierarchyCache(Sharing sharing) : sharing_(sharing) {}
HierarchyCache::~HierarchyCache() = default;

const HierarchyCache::Entry* HierarchyCache::find(
    int volume_axes,
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const std::vector<std::int32_t>* subset,
    const BvhOptions& options) const {
  for (const Entry& e : entries_) {
    if (e.volume_axes == volume_axes && e.options == options && e.whole == (subset == nullptr) &&
        (subset == nullptr || e.subset == *subset) && same_bytes(e.triangles, triangles) &&
        same_bytes(e.positions, positions)) {
      return &e;
    }
  }
  return nullptr;
}

void HierarchyCache::add(
    int volume_axes,
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const std::vector<std::int32_t>* subset,
    const BvhOptions& options,
    std::shared_future<std::shared_ptr<const void>> tree) {
  Entry& e = entries_.emplace_back();
  e.volume_axes = volume_axes;
  e.triangles = triangles;
  e.positions = positions;
  e.whole = subset == nullptr;
  if (subset != nullptr) e.subset = *subset;
  e.options = options;
  e.tree = std::move(tree);
  ++builds_;
}

template <int N>
Bvh<N> HierarchyCache::get(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const std::vector<std::int32_t>* subset,
    const BvhOptions& options) {
  std::promise<std::shared_ptr<const void>> promise;       // set when this call builds
  std::shared_future<std::shared_ptr<const void>> theirs;  // valid when another call did
  bool keep = true;  // false once closed: built for this caller alone
  {
    std::lock_guard lock(mutex_);
    keep = !closed_ && sharing_ == Sharing::copies;
    if (keep) {
      if (const Entry* e = find(N, triangles, positions, subset, options); e != nullptr) {
        theirs = e->tree;
        ++reuses_;
      }
    }
    if (keep && !theirs.valid()) {  // this call builds it, outside the lock
      add(N, triangles, positions, subset, options, promise.get_future().share());
    }
  }
  // Another call's tree: its build waited for (get() rethrows its failure), then copied.
  if (theirs.valid()) return *static_cast<const Bvh<N>*>(theirs.get().get());
  if (!keep) return build_hierarchy<N>(nullptr, triangles, positions, subset, options);
  try {
    auto built = std::make_shared<const Bvh<N>>(
        build_hierarchy<N>(nullptr, triangles, positions, subset, options));
    promise.set_value(built);
    return *built;
  } catch (...) {
    promise.set_exception(std::current_exception());
    throw;
  }
}

template <int N>
std::shared_ptr<Bvh<N>> HierarchyCache::lend(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const BvhOptions& options) {
  if (sharing_ == Sharing::copies) {
    return std::make_shared<Bvh<N>>(get<N>(triangles, positions, nullptr, options));
  }
  std::lock_guard lock(mutex_);  // one method at a time: the build under the lock costs nobody
  // entries_ is this object's own: the entry found may be lent again.
  auto* held =
      const_cast<Entry*>(closed_ ? nullptr : find(N, triangles, positions, nullptr, options));
  if (held != nullptr && held->lent.use_count() == 1) {  // the cache alone holds it
    ++reuses_;
    return std::static_pointer_cast<Bvh<N>>(held->lent);
  }
  // It keeps one tree at a time: one of other inputs that no caller holds is not wanted by the
  // method being built, and goes before this build (a serial `kdop` after the baseline's `bvh`).
  if (held == nullptr) entries_.remove_if([](const Entry& e) { return e.lent.use_count() == 1; });
  auto built =
      std::make_shared<Bvh<N>>(build_hierarchy<N>(nullptr, triangles, positions, nullptr, options));
  // Kept for the next caller unless closed, or another caller holds the one kept already.
  if (!closed_ && keeping_ && held == nullptr) {
    ++builds_;
    Entry& e = entries_.emplace_back();
    e.volume_axes = N;
    e.triangles = triangles;
    e.positions = positions;
    e.options = options;
    e.lent = built;
  }
  return built;
}

template <int N>
void HierarchyCache::prebuild(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const std::vector<std::int32_t>* subset,
    const BvhOptions& options) {
  std::promise<std::shared_ptr<const void>> promise;
  {
    std::lock_guard lock(mutex_);
    // Asked for already: built, or being built by that call. A hand-over cache lends what its
    // callers built only.
    if (closed_ || sharing_ == Sharing::hand_over ||
        find(N, triangles, positions, subset, options) != nullptr)
      return;
    add(N, triangles, positions, subset, options, promise.get_future().share());
  }
  try {
    promise.set_value(std::make_shared<const Bvh<N>>(
        build_hierarchy<N>(nullptr, triangles, positions, subset, options)));
  } catch (...) {
    promise.set_exception(std::current_exception());  // for the callers that ask
  }
}

std::shared_ptr<const void> HierarchyCache::shared_object(
    const std::string& key, const std::function<std::shared_ptr<const void>()>& build) {
  std::promise<std::shared_ptr<const void>> promise;       // set when this call builds
  std::shared_future<std::shared_ptr<const void>> theirs;  // valid when another call did
  {
    std::lock_guard lock(mutex_);
    // A hand-over cache lends trees only: an object kept would be held through the next
    // method's set-up, which would reuse it only when it is a `bvh` (its slot adjacency, 3 ms
    // on CesiumMan-dense) — not a `kdop`, whose peak it would raise, nor `dynamic`.
    if (closed_ || sharing_ == Sharing::hand_over) return build();
    for (const auto& [k, object] : objects_) {
      if (k == key) {
        theirs = object;
        ++reuses_;
        break;
      }
    }
    if (!theirs.valid()) {
      objects_.emplace_back(key, promise.get_future().share());
      ++builds_;
    }
  }
  if (theirs.valid()) return theirs.get();  // rethrows its build's failure
  try {
    std::shared_ptr<const void> built = build();
    promise.set_value(built);
    return built;
  } catch (...) {
    promise.set_exception(std::current_exception());
    throw;
  }
}

std::shared_ptr<const SlotAdjacency> shared_slot_adjacency(
    HierarchyCache* cache,
    const std::shared_ptr<const FeatureTopology>& features,
    std::span<const std::int32_t> order) {
  struct Held {
    std::shared_ptr<const FeatureTopology> features;
    SlotAdjacency slots;
  };
  const auto build = [&] {
    auto held = std::make_shared<const Held>(Held{features, SlotAdjacency(*features, order)});
    return std::shared_ptr<const SlotAdjacency>(held, &held->slots);
  };
  if (cache == nullptr) return build();
  std::string key =
      "SlotAdjacency " + std::to_string(reinterpret_cast<std::uintptr_t>(features.get())) + ' ';
  key.append(reinterpret_cast<const char*>(order.data()), order.size_bytes());
  return cache->shared<SlotAdjacency>(key, build);
}

void HierarchyCache::keep_no_more() {
  std::lock_guard lock(mutex_);
  keeping_ = false;
}

void HierarchyCache::close() {
  std::list<Entry> freed;
  std::list<std::pair<std::string, std::shared_future<std::shared_ptr<const void>>>> shared;
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
    freed.swap(entries_);
    shared.swap(objects_);
  }
  // Freed outside the lock; a caller still waiting on an entry holds its future, which keeps
  // the tree it waits for.
}

std::size_t HierarchyCache::builds() const {
  std::lock_guard lock(mutex_);
  return builds_;
}

std::size_t HierarchyCache::reuses() const {
  std::lock_guard lock(mutex_);
  return reuses_;
}

template Bvh<3> HierarchyCache::get<3>(
    const skinning::Triangles&,
    const skinning::Positions&,
    const std::vector<std::int32_t>*,
    const BvhOptions&);
template Bvh<8> HierarchyCache::get<8>(
    const skinning::Triangles&,
    const skinning::Positions&,
    const std::vector<std::int32_t>*,
    const BvhOptions&);
template std::shared_ptr<Bvh<3>> HierarchyCache::lend<3>(
    const skinning::Triangles&, const skinning::Positions&, const BvhOptions&);
template std::shared_ptr<Bvh<8>> HierarchyCache::lend<8>(
    const skinning::Triangles&, const skinning::Positions&, const BvhOptions&);
template void HierarchyCache::prebuild<3>(
    const skinning::Triangles&,
    const skinning::Positions&,
    const std::vector<std::int32_t>*,
    const BvhOptions&);

}  // namespace skelcd::culling
