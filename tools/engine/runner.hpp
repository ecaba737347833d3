#pragma once
// The per-interval runner: poses a Motion sample by sample, welds, and asks a culling method for
// DCD findings at each sample and CCD contacts over each interval between consecutive samples,
// reporting every row in the file's own numbering as soon as it completes. With several threads
// (RunOptions::threads) it checks blocks of consecutive samples in parallel, one method object
// per worker, and still reports the rows strictly in order with the same contents as a serial run
// (docs/check.md, "Threads").

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "culling/method.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/motion.hpp"
#include "skinning/topology.hpp"
#include "tools/io/frame_report.hpp"
#include "tools/io/log/log_header.hpp"

namespace skelcd::tools {

/// Samples first … last, both included (`--frames A:B`); last unset means the final sample.
struct FrameRange {
  std::int32_t first = 0;
  std::optional<std::int32_t> last;
};

/// Parses `--frames`: "A:B", "A:" (to the end), ":B" (from 0) or "A" (one sample); A <= B, both >=
/// 0.
/// @throws InvalidInput quoting `text` when it is malformed.
[[nodiscard]] FrameRange parse_frame_range(std::string_view text);

struct RunOptions {
  std::string clip;  ///< clip to check (empty: the model's first clip) — used by the loader
  double fps = 0;    ///< samples/s (0: the clip's frame rate, else 30) — used by the loader
  FrameRange frames;
  std::string method = "bvh";
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  QuerySet query = QuerySet::both;
  double min_separation = 0;  ///< contact distance, model units
  /// The mesh's segmentation for methods that need one (rvbc, dynamic, auto's closed parts:
  /// tools/engine/radial_view_setup.hpp); null otherwise.
  std::shared_ptr<const segmentation::Segmentation> segmentation;
  /// Parameters of methods declared above culling/ (γ, seed).
  culling::MethodParameters method_parameters;
  /// Worker threads: 1 = serial (the default here), 0 = all cores (tbb::info::default_concurrency).
  /// A run is serial anyway when its method carries state between queries that would change its
  /// rows (RunPlan::serial_reason says why).
  std::int32_t threads = 1;
  /// Samples per block a worker checks in a row (0: chosen from the clip length, whatever the
  /// thread count: an eighth of the clip, between 4 and 64, then smaller blocks towards the end).
  std::int32_t block_samples = 0;
  /// The factory's methods keep no state between queries that changes their findings or counters
  /// (methods of make_method are classified by name; a custom factory's only through this).
  bool factory_methods_stateless = false;
  /// When set, elementary tests add to it as they finish (culling::ElementaryTests::tests_done):
  /// a progress line can move inside one long query.
  std::atomic<std::int64_t>* elementary_tests_done = nullptr;
  /// With both queries, the DCD at sample k+1 is the DCD at k updated from the contacts of the
  /// CCD k → k+1 (culling/incremental_dcd.hpp; the same pairs as a full DCD, proof in
  /// docs/culling.md "Incremental DCD"). Only for registered methods (no factory) and accuracies
  /// that never miss; false: every DCD is a full query (`--full-dcd`).
  bool incremental_dcd = true;
  /// A CCD interval whose positions and bone transforms are the same at both ends, bit for bit,
  /// and the same as those of the last such interval the worker checked, gets that interval's
  /// findings and counters instead of a query: a method that keeps no state between queries
  /// answers an identical query identically (docs/check.md, "Static intervals"). Only where the
  /// method is known to be stateless for the run (RunPlan::serial_reason would be empty; a
  /// factory's only with factory_methods_stateless) or to carry only what follows from the pose
  /// (culling::MethodInfo::carried_state_follows_pose; then only rows the method calls reusable,
  /// CullingMethod::last_ccd_row_reusable, are handed on). False: every interval is queried.
  bool reuse_static_intervals = true;
  /// A method that takes rigid rows (culling::MethodInfo::takes_rigid_rows: `kdop`, `auto`) gets
  /// them when the run has CCD intervals and the motion is linear blend skinning
  /// (skinning::Motion::skin_weights): its CCD skips
  /// the pairs that skinning moves by one matrix (docs/culling.md "Rigid rows"; the same
  /// contacts). False: none (`--no-rigid-rows`).
  bool rigid_rows = true;
};

/// What a run will do, resolved against the motion's sample count.
struct RunPlan {
  std::int32_t first_sample = 0;
  std::int32_t last_sample = 0;
  std::int32_t samples = 0;        ///< last - first + 1
  std::int32_t intervals = 0;      ///< CCD intervals checked (0 for --query dcd)
  std::int64_t rows = 0;           ///< FrameReports the run produces
  std::int32_t threads = 1;        ///< workers the run uses (1: serial)
  std::int32_t block_samples = 0;  ///< most samples in a block of a parallel run (0 when serial)
  std::int32_t blocks = 0;         ///< blocks of a parallel run (0 when serial)
  /// Why a run asked for several threads is serial (empty when it is not).
  std::string serial_reason;
};

/// The worker count `--threads N` means: N, or all cores for 0.
[[nodiscard]] std::int32_t resolve_threads(std::int32_t threads);

/// Starts oneTBB's thread pool for a run on `threads` (as `--threads`; nothing for 1) and returns
/// once it has. A process's first arena costs 2-3 ms on this project's 2-core VM (the scheduler's
/// set-up, its probe of the machine, the worker threads), which a parallel run would otherwise pay
/// inside ClipRunner's constructor, between its set-up and its first block. Meant for a stretch in
/// which this process only waits: `skelcd check` calls it while the import's child reads the model
/// (skinning::ImportOptions::while_importing). The pool stays up once this returns.
void warm_up_workers(std::int32_t threads);

/// Builds the culling method for a mesh; the default calls culling::make_method(options.method…).
using MethodFactory = std::function<std::unique_ptr<culling::CullingMethod>(
    const skinning::Mesh&, const skinning::Topology&, const culling::MethodOptions&)>;

/// Called once per completed row (a DCD sample or a CCD interval), in order. The row is the
/// callee's to keep: it may move from it (the cloth-ball step's 113,854 contacts are 6.4 MB, which
/// a copy first-touches again at every interval), and the runner starts its next row from what is
/// left. Vectors the callee puts back there (emptied rows it has done with) are refilled instead
/// of allocated anew: make_report clears them and keeps their capacity.
using FrameCallback = std::function<void(FrameReport&)>;

class ClipRunner {
 public:
  /// Builds the welded topology of motion.mesh() and the method; validates the options against the
  /// motion (frame range inside [0, num_samples)).
  /// @throws InvalidInput for a bad frame range, an unknown method or an unusable mesh.
  ClipRunner(const skinning::Motion& motion, const RunOptions& options, MethodFactory factory = {});
  /// The same on a topology the caller built (skinning::build_topology(motion.mesh())), so that
  /// what it computes on the topology first — the baseline DCD with its own `bvh` — is freed
  /// before this runner builds its method, and the two never hold memory at once. `features`,
  /// when the caller built it from motion.mesh() and this topology before moving the topology in
  /// (culling::FeatureTopology::built_from still holds), is the one the runner's methods share
  /// instead of a new one (a serial check's baseline `bvh` used it first). `hierarchies`, in a
  /// parallel run, the cache its workers' methods build their hierarchies through (one build,
  /// copied: culling::HierarchyCache), shared with whatever the caller builds beside them (a
  /// parallel check's baseline `bvh`); without one a parallel run makes its own. A hand-over cache
  /// (culling::HierarchyCache::Sharing::hand_over, a serial check's) lends a serial run's one
  /// method the tree the caller's baseline `bvh` built; a parallel run closes one unused. Closed
  /// once the methods are built.
  /// @pre topology == skinning::build_topology(motion.mesh()).
  ClipRunner(
      const skinning::Motion& motion,
      const RunOptions& options,
      skinning::Topology topology,
      MethodFactory factory = {},
      std::shared_ptr<const culling::FeatureTopology> features = {},
      std::shared_ptr<culling::HierarchyCache> hierarchies = {});
  /// The same on a topology the caller keeps reading while the runner is built (a parallel
  /// check's baseline thread): one object, so that a FeatureTopology built from it
  /// (culling::FeatureTopology::built_from) is the runner's too, where a copy would need a
  /// second one.
  ClipRunner(
      const skinning::Motion& motion,
      const RunOptions& options,
      std::shared_ptr<const skinning::Topology> topology,
      MethodFactory factory = {},
      std::shared_ptr<const culling::FeatureTopology> features = {},
      std::shared_ptr<culling::HierarchyCache> hierarchies = {});

  [[nodiscard]] const RunPlan& plan() const { return plan_; }
  [[nodiscard]] const skinning::Topology& topology() const { return *topology_; }
  [[nodiscard]] std::string_view method_name() const { return method_->name(); }
  /// Whether the method was given rigid rows (RunOptions::rigid_rows; docs/culling.md "Rigid
  /// rows"): a method that takes them, CCD intervals, a skinned motion, and rows that hold a
  /// twentieth of the triangles; under `auto`, a closed group too.
  [[nodiscard]] bool has_rigid_rows() const { return method_options_.rigid_rows != nullptr; }
  /// Under `auto`, where each connected component went (the log's /routes rows); empty for any
  /// other method. `part_offset` is added to each route's part id (a scene's object offset).
  [[nodiscard]] std::vector<LogRoute> routes(std::int32_t part_offset = 0) const;

  /// Runs every row of the plan, calling `on_frame` after each, in plan order (one call at a time;
  /// in a parallel run possibly from a worker thread).
  /// @throws InvalidInput naming the motion and sample when a posed position is not finite;
  /// rows completed before it have been reported (also in a parallel run).
  void run(const FrameCallback& on_frame);

 private:
  /// The run's method, as the factory or culling::make_method builds it.
  /// @throws InvalidInput when it cannot be built.
  [[nodiscard]] std::unique_ptr<culling::CullingMethod> build_method() const;
  /// method_options_.features, which only the DCD updaters read once the methods are built:
  /// released without incremental DCD; else the method's own when the method did not take the
  /// runner's and its own describes this mesh and topology (any owner order).
  void adopt_method_features();
  void run_serial(const FrameCallback& on_frame);
  void run_queries_in_order(const FrameCallback& on_frame);
  void run_parallel(const FrameCallback& on_frame);

  const skinning::Motion& motion_;
  RunOptions options_;
  MethodFactory factory_;
  culling::MethodOptions method_options_;
  RunPlan plan_;
  std::shared_ptr<const skinning::Topology> topology_;  ///< never null
  std::unique_ptr<culling::CullingMethod> method_;
  /// A parallel run's other workers' methods (plan_.threads − 1), built with method_.
  std::vector<std::unique_ptr<culling::CullingMethod>> spare_methods_;
  bool bones_ = false;  ///< the queries carry the bones' transforms (the method needs them)
  /// DCD updated from the CCD contacts (RunOptions::incremental_dcd).
  bool incremental_dcd_ = false;
  /// Identical static intervals reuse the last one's row (RunOptions::reuse_static_intervals).
  bool reuse_static_ = false;
  /// Block i's sample units [first, end) (a unit: the DCD at k, then the CCD k → k+1), whatever
  /// the thread count: RunOptions::block_samples each, or large blocks first and smaller ones at
  /// the end (docs/check.md, "Threads").
  [[nodiscard]] std::pair<std::int32_t, std::int32_t> block(std::int32_t i) const;
  [[nodiscard]] std::int32_t blocks() const;

  std::int32_t units_ = 0;  ///< sample units of the run, from plan_.first_sample
  /// Each block's first unit (from plan_.first_sample), then units_.
  std::vector<std::int32_t> block_starts_;
};

/// Maps welded ids (culling's numbering) back to the file's own numbering (part, index).
class FeatureNumbering {
 public:
  FeatureNumbering(const skinning::Mesh& mesh, const skinning::Topology& topology);
  /// Welded vertex → the first of its file vertices in file order (least part, then index in it):
  /// the same name whatever order the mesh holds its vertices in (skinning::MeshOrder).
  [[nodiscard]] FeatureId vertex(std::int32_t welded_vertex) const;
  [[nodiscard]] FeatureId triangle(std::int32_t triangle) const;
  /// Edge (Topology::edges row) → its side of the first triangle incident to it in file order.
  [[nodiscard]] FeatureId edge(std::int32_t edge) const;

 private:
  const skinning::Mesh& mesh_;
  std::vector<FeatureId> vertices_;
  std::vector<FeatureId> edges_;
};

}  // namespace skelcd::tools
