#pragma once
// Hierarchies built once and copied where several methods over one mesh are built at the same
// time (docs/culling.md "One build for every thread"): a parallel run's workers each hold a
// method of their own, and the baseline's DCD builds a `bvh` beside them.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "culling/bvh.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

class FeatureTopology;
struct SlotAdjacency;

/// Built hierarchies keyed by what they were built from: the first caller asking for one builds
/// it, callers asking for the same while it builds wait for it, and every caller gets a copy —
/// the same bits as its own build (the build is deterministic), for the cost of copying its
/// arrays instead of sorting the triangles again. The key is the inputs themselves, compared
/// byte for byte (the triangles, the positions, the subset, the options and the volume), so two
/// callers share a tree only when they would have built the same one. Thread-safe.
///
/// It holds every tree it built until close(): its owner closes it once the methods that share
/// it are built (the runner does), so that the copies are not held for the whole run. Each tree
/// also keeps its key — a copy of the triangles and positions it was built from, the whole mesh's
/// even for a subset — so it suits a few trees over one mesh (a parallel check keeps one or two:
/// 58–314 KB of keys on the bundled characters and the Panda), not one per cluster.
class HierarchyCache {
 public:
  /// How a tree reaches its callers.
  enum class Sharing {
    /// Every caller of get() gets a copy: methods built at the same time (a parallel run).
    copies,
    /// One method over the mesh at a time (a serial check's baseline `bvh`, then its runner's
    /// method): lend() hands the one tree it holds to the next caller once the last one has let
    /// go of it, instead of each building its own. get() builds for its caller alone.
    hand_over,
  };
  explicit HierarchyCache(Sharing sharing = Sharing::copies);
  HierarchyCache(const HierarchyCache&) = delete;
  HierarchyCache& operator=(const HierarchyCache&) = delete;
  ~HierarchyCache();

  /// Bvh<N>(triangles, positions, options), or Bvh<N>(triangles, positions, *subset, options)
  /// when `subset` is not null. A build that throws throws in every caller waiting for it (the
  /// same message as their own build).
  template <int N>
  [[nodiscard]] Bvh<N> get(
      const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const std::vector<std::int32_t>* subset,
      const BvhOptions& options);

  /// The whole mesh's Bvh<N>(triangles, positions, options), shared rather than copied. A
  /// hand-over cache (Sharing::hand_over) keeps the tree it builds and lends that same object to
  /// a later caller of the same inputs when no caller holds it any more — refit by its last
  /// holder, which a caller's first query refits again (Bvh::refit writes every volume a
  /// traversal reads). Held still, or closed: a tree of the caller's own, not kept. It keeps one
  /// tree at a time: a caller of other inputs frees the one no caller holds before its build.
  /// A copies cache: a copy, as get().
  template <int N>
  [[nodiscard]] std::shared_ptr<Bvh<N>> lend(
      const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const BvhOptions& options);
  [[nodiscard]] Sharing sharing() const { return sharing_; }

  /// Builds the tree get<N>(triangles, positions, subset, options) would, and keeps it for the
  /// callers that ask for it later, when no call has asked for it yet; returns at once when one
  /// has (its tree built or being built) or when the cache is closed. For a thread that would
  /// otherwise wait idle for another to ask (a parallel check's main thread while its baseline
  /// thread builds the feature topology: docs/check.md "Threads"). A build that throws is not
  /// reported here: the callers that ask get its exception, as from their own build.
  template <int N>
  void prebuild(
      const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const std::vector<std::int32_t>* subset,
      const BvhOptions& options);
  /// An immutable object that the methods built at the same time share instead of each building
  /// its own (`dynamic`'s rim-first FeatureTopology): the first caller of `key` builds it,
  /// callers asking while it builds wait for it (and get its build's exception), every caller
  /// gets the same object. `key` names what it is built from; callers build from the same
  /// objects (the runner's mesh, weld and segmentation), so their addresses may stand for them
  /// while the cache is open. After close(), or in a hand-over cache, each caller builds its own.
  template <class T, class Build>
  [[nodiscard]] std::shared_ptr<const T> shared(const std::string& key, Build&& build) {
    return std::static_pointer_cast<const T>(
        shared_object(key, [&]() -> std::shared_ptr<const void> { return build(); }));
  }

  /// The last caller over the mesh is next (a serial run's one method): lend() still lends the
  /// tree held, and keeps no tree it builds (nor its key's copy) from now on.
  void keep_no_more();
  /// Frees every tree and object held; later calls build without keeping what they build.
  void close();

  /// Trees and shared objects built here and kept (not copies, nor a caller's own build after
  /// close() or in a hand-over cache's get()), since construction; for tests.
  [[nodiscard]] std::size_t builds() const;
  /// Copies handed out of a tree, trees lent again, or objects shared, that another call built;
  /// for tests.
  [[nodiscard]] std::size_t reuses() const;

 private:
  struct Entry;
  /// The entry of a tree of these inputs with `volume_axes` (N), or nullptr; under mutex_.
  [[nodiscard]] const Entry* find(
      int volume_axes,
      const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const std::vector<std::int32_t>* subset,
      const BvhOptions& options) const;
  /// A new entry for these inputs, whose tree `tree` will hold; under mutex_.
  void add(
      int volume_axes,
      const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const std::vector<std::int32_t>* subset,
      const BvhOptions& options,
      std::shared_future<std::shared_ptr<const void>> tree);
  std::shared_ptr<const void> shared_object(
      const std::string& key, const std::function<std::shared_ptr<const void>()>& build);
  std::list<std::pair<std::string, std::shared_future<std::shared_ptr<const void>>>> objects_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  // a list: an entry stays where it is while callers wait on it
  Sharing sharing_ = Sharing::copies;
  bool keeping_ = true;  // lend() keeps what it builds (keep_no_more)
  bool closed_ = false;
  std::size_t builds_ = 0;
  std::size_t reuses_ = 0;
};

/// The fan sieve's slot adjacency (culling/traversal.hpp) of a tree's triangle order over
/// `features`. Methods that copy one tree from `cache` (a parallel run's baseline `bvh` and its
/// workers' methods) share one: it is never written (FanSieve reads it). Keyed by the
/// FeatureTopology object and the order's bytes; the object holds that FeatureTopology, so that no
/// other takes its address while the cache keeps it. Without a cache (null), built here.
[[nodiscard]] std::shared_ptr<const SlotAdjacency> shared_slot_adjacency(
    HierarchyCache* cache,
    const std::shared_ptr<const FeatureTopology>& features,
    std::span<const std::int32_t> order);

/// HierarchyCache::prebuild of the tree `bvh`'s method builds over `mesh` (and the `bvh` a baseline
/// DCD builds): over its welded triangles at their rest positions, with `options` but no binary
/// node volumes (its traversals read the wide copy only).
void prebuild_bvh_hierarchy(
    HierarchyCache& cache,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const BvhOptions& options);

/// The whole mesh's tree that a method keeps for its run (`bvh`'s, `dynamic`'s DCD tree):
/// lent by `cache` when one is given (HierarchyCache::lend), its own build otherwise.
template <int N>
[[nodiscard]] std::shared_ptr<Bvh<N>> lend_hierarchy(
    HierarchyCache* cache,
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const BvhOptions& options) {
  if (cache != nullptr) return cache->lend<N>(triangles, positions, options);
  return std::make_shared<Bvh<N>>(triangles, positions, options);
}

/// What a method builds its hierarchy with: a copy from `cache` when one is given
/// (MethodOptions::hierarchies), its own build otherwise. `subset` as HierarchyCache::get.
template <int N>
[[nodiscard]] Bvh<N> build_hierarchy(
    HierarchyCache* cache,
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const std::vector<std::int32_t>* subset,
    const BvhOptions& options) {
  if (cache != nullptr) return cache->get<N>(triangles, positions, subset, options);
  return subset == nullptr ? Bvh<N>(triangles, positions, options)
                           : Bvh<N>(triangles, positions, *subset, options);
}

}  // namespace skelcd::culling
