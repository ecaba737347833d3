#include "tools/engine/runner.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <mutex>
#include <tuple>
#include <utility>

#include "culling/hierarchy_cache.hpp"
#include "culling/incremental_dcd.hpp"
#include "culling/method_registry.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"
#include "tools/engine/sample_sequencer.hpp"

namespace skelcd::tools {
namespace {

using Clock = std::chrono::steady_clock;

double microseconds_since(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

std::optional<std::int32_t> parse_index(std::string_view text) {
  std::int32_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value < 0) return std::nullopt;
  return value;
}

RunPlan make_plan(const skinning::Motion& motion, const RunOptions& options) {
  const std::int32_t samples = motion.num_samples();
  if (samples < 1) throw InvalidInput(motion.name() + ": the motion has no samples");
  RunPlan plan;
  plan.first_sample = options.frames.first;
  plan.last_sample = options.frames.last.value_or(samples - 1);
  if (plan.first_sample > plan.last_sample || plan.last_sample >= samples) {
    throw InvalidInput(
        "--frames " + std::to_string(plan.first_sample) + ":" + std::to_string(plan.last_sample) +
        " is outside the " + std::to_string(samples) +
        " samples (0:" + std::to_string(samples - 1) + ") of " + motion.name());
  }
  plan.samples = plan.last_sample - plan.first_sample + 1;
  const bool dcd = options.query != QuerySet::ccd;
  const bool ccd = options.query != QuerySet::dcd;
  plan.intervals = ccd ? plan.samples - 1 : 0;
  if (ccd && !dcd && plan.intervals == 0) {
    throw InvalidInput(
        "--query ccd needs at least two samples; --frames selects only sample " +
        std::to_string(plan.first_sample));
  }
  plan.rows = (dcd ? plan.samples : 0) + plan.intervals;
  return plan;
}

/// What one row needs from the run: the motion, the welded topology and the file numbering, and
/// whether the method needs the bones' transforms.
struct RowContext {
  const skinning::Motion& motion;
  const skinning::Topology& topology;
  const FeatureNumbering& numbering;
  bool bones;
  /// DCD at k+1 from the DCD at k and the CCD contacts of k → k+1 (culling/incremental_dcd.hpp)
  /// with these elementary tests; null: every DCD is a full query of the method.
  const culling::ElementaryTests* incremental_dcd = nullptr;
  /// The mesh's FeatureTopology that the runner's methods share, lent to the DCD updaters.
  std::shared_ptr<const culling::FeatureTopology> features{};
  /// RunOptions::reuse_static_intervals, where the method allows it.
  bool reuse_static = false;
  /// Every vertex is its own welded vertex (identity_welding): a sample's positions are its
  /// welded positions as they are.
  bool identity_welding = false;
};

/// True when welding keeps every vertex as it is, in its place (no duplicates merged).
bool identity_welding(const skinning::Topology& t) {
  if (t.representative_vertex.size() != t.welded_of_vertex.size()) return false;
  for (std::size_t w = 0; w < t.representative_vertex.size(); ++w) {
    if (t.representative_vertex[w] != static_cast<std::int32_t>(w)) return false;
  }
  return true;
}

/// One posed sample: welded positions and, when the method needs them, the bone transforms.
struct PosedSample {
  /// The welded positions: `lent` (a held frame, where welding is the identity) or `own`.
  [[nodiscard]] const skinning::Positions& welded() const { return lent != nullptr ? *lent : own; }
  skinning::Positions own;
  const skinning::Positions* lent = nullptr;  ///< the motion's, valid while it lives
  std::vector<skinning::BoneTransform> bones;
};

/// Refuses sample i of the check's motion: `vertex` (the file's) has a non-finite position.
[[noreturn]] void throw_non_finite(const RowContext& c, std::int32_t i, std::int32_t vertex) {
  throw InvalidInput(
      c.motion.name() + ": sample " + std::to_string(i) +
      " (t = " + std::to_string(c.motion.sample_time(i)) + " s): vertex " + std::to_string(vertex) +
      " has a non-finite position");
}

/// Poses sample i into `out` (`posed`: scratch); returns the microseconds it took.
/// Finiteness is checked once per sample, here, where positions enter.
double pose_sample(
    const RowContext& c, std::int32_t i, skinning::Positions& posed, PosedSample& out) {
  const auto start = Clock::now();
  if (c.bones) c.motion.bone_transforms(i, out.bones);
  // A skinned rig poses the welded vertices alone (their representatives): no #V buffer, and no
  // duplicate skinned only to be dropped. A vertex that is no welded vertex's representative is
  // not posed, so not checked either: nothing reads it.
  if (c.motion.skin_weights() != nullptr && c.motion.held_positions(i) == nullptr) {
    out.lent = nullptr;
    c.motion.positions_of(i, c.topology.representative_vertex, out.own);
    if (!out.own.allFinite()) {
      Eigen::Index bad = 0;
      while (bad < out.own.rows() && out.own.row(bad).allFinite()) ++bad;
      throw_non_finite(c, i, c.topology.representative_vertex[static_cast<std::size_t>(bad)]);
    }
    return microseconds_since(start);
  }
  const auto& mesh = c.motion.mesh();
  // Held frames are read where they are (a copy would cost a sample's worth of fresh pages).
  const skinning::Positions* held = c.motion.held_positions(i);
  if (held == nullptr) {
    c.motion.positions(i, posed);
    held = &posed;
  }
  const skinning::Positions& x = *held;
  if (x.rows() != mesh.num_vertices()) {
    throw InvalidInput(
        c.motion.name() + ": sample " + std::to_string(i) + " has " + std::to_string(x.rows()) +
        " positions, expected " + std::to_string(mesh.num_vertices()));
  }
  if (!x.allFinite()) {
    Eigen::Index bad = 0;
    while (bad < x.rows() && x.row(bad).allFinite()) ++bad;
    throw_non_finite(c, i, static_cast<std::int32_t>(bad));
  }
  // A held frame that welding leaves as it is is lent, not copied (a sample's worth of fresh pages
  // and a copy less).
  out.lent = held != &posed && c.identity_welding ? held : nullptr;
  if (out.lent == nullptr) skinning::gather_welded(c.topology, x, out.own);
  return microseconds_since(start);
}

/// Converts the method's findings (welded numbering) into a row in the file's numbering. The
/// found-counters are taken from the findings themselves so that a row's counts always equal its
/// rows in /contacts and /dcd_pairs.
void make_report(
    const RowContext& c,
    QueryKind kind,
    std::int32_t sample,
    const culling::FrameResult& result,
    double skin_us,
    Clock::time_point start,
    FrameReport& report) {
  report.row = FrameRow{};
  report.row.sample = sample;
  report.row.kind = kind;
  report.row.t0 = c.motion.sample_time(sample);
  report.row.t1 = kind == QueryKind::ccd ? c.motion.sample_time(sample + 1) : report.row.t0;
  report.row.counters = result.counters;
  report.row.times = result.times;
  report.row.times.skin_us = skin_us;
  report.contacts.clear();
  report.dcd_pairs.clear();
  // Sized once: growing by doubling would copy a large row's contacts and first-touch about twice
  // their memory (113,854 contacts on the cloth-ball step: 6.4 MB).
  report.contacts.reserve(result.contacts.size());
  report.dcd_pairs.reserve(result.dcd_pairs.size());
  std::int64_t vf = 0;
  std::int64_t ee = 0;
  for (const auto& contact : result.contacts) {
    const bool is_vf = contact.kind == culling::CcdContact::Kind::vf;
    (is_vf ? vf : ee) += 1;
    report.contacts.push_back(ContactRow{
        .frame = sample,
        .kind = contact.kind,
        .a = is_vf ? c.numbering.vertex(contact.a) : c.numbering.edge(contact.a),
        .b = is_vf ? c.numbering.triangle(contact.b) : c.numbering.edge(contact.b),
        .toi_lower = contact.toi_lower,
        .toi_upper = contact.toi_upper,
    });
  }
  for (const auto& p : result.dcd_pairs) {
    report.dcd_pairs.push_back(DcdPairRow{
        .frame = sample, .a = c.numbering.triangle(p.a), .b = c.numbering.triangle(p.b)});
  }
  if (kind == QueryKind::ccd) {
    report.row.counters.vf_contacts = vf;
    report.row.counters.ee_contacts = ee;
  } else {
    report.row.counters.dcd_pairs = static_cast<std::int64_t>(result.dcd_pairs.size());
  }
  report.row.total_us = skin_us + microseconds_since(start);
}

/// The options the method is built with.
culling::MethodOptions method_options_of(
    const RunOptions& options, const skinning::Motion& motion) {
  culling::MethodOptions o;
  o.accuracy = options.accuracy;
  o.min_separation = options.min_separation;
  o.segmentation = options.segmentation;
  o.num_bones = motion.num_bones();
  o.parameters = options.method_parameters;
  o.dcd_queries = options.query != QuerySet::ccd;
  return o;
}

/// True when `name` (or, for `auto`, a method it routes to) needs the bones' transforms.
bool needs_bone_poses(std::string_view name, const culling::MethodOptions& options) {
  std::vector<std::string> names{std::string(name)};
  if (name == "auto") names = culling::auto_group_methods(options);
  for (const auto& n : names) {
    const auto* m = culling::find_method(n);
    if (m != nullptr && m->needs.bone_poses) return true;
  }
  return false;
}

/// The least share of a mesh's triangles its rigid rows must hold to be used
/// (RunOptions::rigid_rows).
constexpr double kMinRigidRowShare = 0.05;

/// True when `name` takes rigid rows (`auto` for the `bvh` it may send a whole mesh to).
bool takes_rigid_rows(std::string_view name) {
  const auto* m = culling::find_method(name);
  return m != nullptr && m->takes_rigid_rows;
}

/// One method and the buffers of the samples it checks: the serial run's, or a parallel worker's.
struct Worker {
  std::unique_ptr<culling::CullingMethod> owned;
  culling::CullingMethod* method = nullptr;
  skinning::Positions posed;  // a sample's #V positions, for motions that pose every vertex
  PosedSample samples[2];
  culling::FrameResult result;
  // Incremental DCD: the last DCD's pairs and the last CCD's contacts, with their samples.
  std::unique_ptr<culling::DcdUpdater> updater;
  std::vector<culling::TrianglePair> previous_pairs;
  std::int32_t previous_sample = -2;
  std::vector<culling::CcdContact> contacts;
  std::int32_t contacts_interval = -2;
  // The last static interval this worker queried (its pose, held at both ends) and its result,
  // for an identical one later (RunOptions::reuse_static_intervals).
  bool has_static = false;
  PosedSample static_pose;
  culling::FrameResult static_result;
};

/// The same positions and bone transforms, bit for bit (−0 and +0 differ: a method could tell).
bool same_pose(const PosedSample& a, const PosedSample& b) {
  const auto same = [](const double* x, const double* y, std::size_t n) {
    return n == 0 || std::memcmp(x, y, n * sizeof(double)) == 0;
  };
  const skinning::Positions& xa = a.welded();
  const skinning::Positions& xb = b.welded();
  if (xa.rows() != xb.rows() || a.bones.size() != b.bones.size()) return false;
  static_assert(
      sizeof(skinning::BoneTransform) ==
      skinning::BoneTransform::SizeAtCompileTime * sizeof(double));  // no padding
  const auto bone_doubles = static_cast<std::size_t>(skinning::BoneTransform::SizeAtCompileTime);
  return same(xa.data(), xb.data(), static_cast<std::size_t>(xa.size())) &&
         (a.bones.empty() ||
          same(a.bones.front().data(), b.bones.front().data(), a.bones.size() * bone_doubles));
}

/// Runs the rows of `sequence` with `w`, passing each completed row to `emit`, in order.
template <class Emit>
void check_samples(
    const RowContext& context, const SampleSequence& sequence, Worker& w, Emit&& emit) {
  FrameReport report;
  // Each sequence starts with a full DCD, so that a block's rows do not depend on what the worker
  // checked before.
  w.previous_sample = -2;
  w.contacts_interval = -2;
  if (context.incremental_dcd != nullptr && !w.updater) {
    w.updater = std::make_unique<culling::DcdUpdater>(
        context.motion.mesh(), context.topology, context.features);
  }
  run_sequence(
      sequence,
      [&](std::int32_t k, int slot) { return pose_sample(context, k, w.posed, w.samples[slot]); },
      [&](std::int32_t k, int slot, double skin_us) {
        const auto start = Clock::now();
        w.result.clear();
        const PosedSample& x = w.samples[slot];
        if (w.updater && w.previous_sample == k - 1 && w.contacts_interval == k - 1) {
          w.updater->update(
              w.previous_pairs, w.contacts, x.welded(), *context.incremental_dcd, w.result);
        } else {
          w.method->detect_dcd(
              culling::Instant{.x = x.welded(), .bones = x.bones, .sample = k}, w.result);
        }
        if (w.updater) {
          w.previous_pairs.assign(w.result.dcd_pairs.begin(), w.result.dcd_pairs.end());
          w.previous_sample = k;
        }
        make_report(context, QueryKind::dcd, k, w.result, skin_us, start, report);
        emit(report);
      },
      [&](std::int32_t k, int slot_t0, int slot_t1, double skin_us) {
        const auto start = Clock::now();
        w.result.clear();
        const PosedSample& a = w.samples[slot_t0];
        const PosedSample& b = w.samples[slot_t1];
        // A held pose: the same query as the last held one gets its answer (no stage ran: the
        // row's stage times stay 0).
        const bool held = context.reuse_static && same_pose(a, b);
        if (held && w.has_static && same_pose(a, w.static_pose)) {
          w.result.counters = w.static_result.counters;
          w.result.contacts = w.static_result.contacts;
          w.result.dcd_pairs = w.static_result.dcd_pairs;
        } else {
          w.method->detect_ccd(
              culling::Interval{
                  .x_t0 = a.welded(),
                  .x_t1 = b.welded(),
                  .bones_t0 = a.bones,
                  .bones_t1 = b.bones,
                  .sample_t0 = k,
                  .sample_t1 = k + 1},
              w.result);
          if (held && w.method->last_ccd_row_reusable()) {
            w.static_pose = a;
            w.static_result = w.result;
            w.has_static = true;
          }
        }
        if (w.updater) {
          w.contacts.assign(w.result.contacts.begin(), w.result.contacts.end());
          w.contacts_interval = k;
        }
        make_report(context, QueryKind::ccd, k, w.result, skin_us, start, report);
        emit(report);
      });
}

/// Workers handed out to the pipeline's parallel stage: one per block being checked, built on
/// first need (at most one per thread of the arena), returned after the block.
class WorkerPool {
 public:
  explicit WorkerPool(std::function<std::unique_ptr<Worker>()> make) : make_(std::move(make)) {}
  void add(std::unique_ptr<Worker> worker) {
    free_.push_back(worker.get());
    all_.push_back(std::move(worker));
  }
  Worker& acquire() {
    const std::lock_guard lock(mutex_);
    if (free_.empty()) {
      all_.push_back(make_());  // rare: construction is serialized under the lock
      return *all_.back();
    }
    Worker* w = free_.back();
    free_.pop_back();
    return *w;
  }
  void release(Worker& worker) {
    const std::lock_guard lock(mutex_);
    free_.push_back(&worker);
  }

 private:
  std::function<std::unique_ptr<Worker>()> make_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Worker>> all_;
  std::vector<Worker*> free_;
};

/// The blocks' first units and, last, `units` (block i is [starts[i], starts[i + 1])), whatever
/// the thread count. `fixed` > 0: blocks of `fixed` units (RunOptions::block_samples). Otherwise
/// blocks of B = clamp(units / 8, 4, 64) units while more than 4·B units are left, then of a
/// quarter of what is left (at least kTailUnits): the blocks a pipeline hands out last are the
/// small ones, so the workers run out of blocks at nearly the same time however the blocks' costs
/// vary along the clip (equal blocks had left one worker idle for up to a block at the end). A
/// remainder smaller than kTailUnits joins the last block.
std::vector<std::int32_t> block_layout(std::int32_t units, std::int32_t fixed) {
  // A block starts with a full DCD (the others update it): blocks of one unit would pay it at
  // every sample.
  constexpr std::int32_t kTailUnits = 2;
  // The first blocks hold an eighth of the clip each. A sixteenth (until 2026-12-06) fed up to
  // 16 threads at once, but each block start's full DCD costs about a third of an interval on the
  // real characters: 20 blocks of BCN_Epileptic's 100 samples against 14 now took 2-4 % longer
  // per interval on one and two threads alike (docs/benchmarks.md, "Fewer block starts"). An
  // eighth still gives 8 threads a block each before the smaller ones at the end.
  constexpr std::int32_t kFirstBlockShare = 8;
  assert(units >= 1);
  std::vector<std::int32_t> starts{0};
  const std::int32_t largest =
      fixed > 0 ? fixed : std::clamp(units / kFirstBlockShare, std::int32_t{4}, std::int32_t{64});
  for (std::int32_t at = 0; at < units;) {
    const std::int32_t left = units - at;
    std::int32_t size =
        fixed > 0 ? fixed : std::clamp((left + 3) / 4, std::min(kTailUnits, left), largest);
    if (fixed == 0 && left - size < kTailUnits) size = left;
    at += std::min(size, left);
    starts.push_back(at);
  }
  return starts;
}

/// A block of consecutive samples [first, end) and the rows it produced (in order), followed by
/// the error that stopped it, if any.
struct Block {
  std::int32_t first = 0;
  std::int32_t end = 0;
  std::vector<FrameReport> reports;
  std::exception_ptr error;
};

}  // namespace

FrameRange parse_frame_range(std::string_view text) {
  const auto bad = [&](const char* why) {
    return InvalidInput(
        "--frames '" + std::string(text) + "': " + why +
        " (expected A:B, A:, :B or A with sample indices >= 0)");
  };
  FrameRange range;
  const auto colon = text.find(':');
  if (colon == std::string_view::npos) {
    const auto one = parse_index(text);
    if (!one) throw bad("not a sample index");
    range.first = *one;
    range.last = *one;
    return range;
  }
  const auto first = text.substr(0, colon);
  const auto last = text.substr(colon + 1);
  if (!first.empty()) {
    const auto value = parse_index(first);
    if (!value) throw bad("bad first sample");
    range.first = *value;
  }
  if (!last.empty()) {
    const auto value = parse_index(last);
    if (!value) throw bad("bad last sample");
    range.last = *value;
  }
  if (range.last && *range.last < range.first) throw bad("last sample before first");
  return range;
}

FeatureNumbering::FeatureNumbering(const skinning::Mesh& mesh, const skinning::Topology& topology)
    : mesh_(mesh) {
  // File order: by part, then by index within it. A mesh held in another order
  // (skinning::MeshOrder::spatial) names each feature as the file's order would.
  const auto before = [](const FeatureId& x, const FeatureId& y) {
    return x.part != y.part ? x.part < y.part : x.index < y.index;
  };
  const auto num_welded = static_cast<std::size_t>(topology.num_welded_vertices());
  vertices_.assign(num_welded, FeatureId{});
  std::vector<bool> named(num_welded, false);
  for (std::size_t v = 0; v < topology.welded_of_vertex.size(); ++v) {
    const auto w = static_cast<std::size_t>(topology.welded_of_vertex[v]);
    const FeatureId id{mesh.vertex_part[v], mesh.vertex_index_in_part[v], -1};
    if (!named[w] || before(id, vertices_[w])) {
      vertices_[w] = id;
      named[w] = true;
    }
  }
  // Name every edge through its first incident triangle (CSR edge → faces) and the side of that
  // triangle it is.
  const std::int32_t num_edges = topology.num_edges();
  edges_.assign(static_cast<std::size_t>(num_edges), FeatureId{});
  for (std::int32_t e = 0; e < num_edges; ++e) {
    const auto begin = topology.edge_face_offsets[static_cast<std::size_t>(e)];
    const auto end = topology.edge_face_offsets[static_cast<std::size_t>(e) + 1];
    std::int32_t first = -1;
    for (auto i = begin; i < end; ++i) {
      const std::int32_t f = topology.edge_faces[static_cast<std::size_t>(i)];
      if (first < 0 || before(triangle(f), triangle(first))) first = f;
    }
    if (first < 0) continue;
    for (std::int8_t k = 0; k < 3; ++k) {
      if (topology.face_edges(first, k) == e) {
        auto& id = edges_[static_cast<std::size_t>(e)];
        id = triangle(first);
        id.side = k;
        break;
      }
    }
  }
}

FeatureId FeatureNumbering::vertex(std::int32_t welded_vertex) const {
  return vertices_[static_cast<std::size_t>(welded_vertex)];
}

FeatureId FeatureNumbering::triangle(std::int32_t triangle) const {
  const auto f = static_cast<std::size_t>(triangle);
  return FeatureId{mesh_.face_part[f], mesh_.face_index_in_part[f], -1};
}

FeatureId FeatureNumbering::edge(std::int32_t edge) const {
  return edges_[static_cast<std::size_t>(edge)];
}

std::int32_t resolve_threads(std::int32_t threads) {
  if (threads < 0) throw InvalidInput("--threads " + std::to_string(threads) + ": expected >= 0");
  if (threads == 0) return std::max(1, tbb::info::default_concurrency());
  return threads;
}

void warm_up_workers(std::int32_t threads) {
  if (threads < 0 || threads == 1) return;  // a negative count is refused by the runner
  const std::int32_t n = resolve_threads(threads);
  if (n < 2) return;
  // One task offered to an arena of n slots: oneTBB creates its scheduler and asks for workers;
  // whether this thread or a worker then runs the task does not matter.
  tbb::task_arena arena(n);
  arena.execute([] {
    tbb::task_group offered;
    offered.run([] {});
    offered.wait();
  });
}

ClipRunner::ClipRunner(
    const skinning::Motion& motion, const RunOptions& options, MethodFactory factory)
    : ClipRunner(motion, options, skinning::build_topology(motion.mesh()), std::move(factory)) {}

ClipRunner::ClipRunner(
    const skinning::Motion& motion,
    const RunOptions& options,
    skinning::Topology topology,
    MethodFactory factory,
    std::shared_ptr<const culling::FeatureTopology> features,
    std::shared_ptr<culling::HierarchyCache> hierarchies)
    : ClipRunner(
          motion,
          options,
          std::make_shared<const skinning::Topology>(
              std::move(topology)),  // a move: built_from holds
          std::move(factory),
          std::move(features),
          std::move(hierarchies)) {}

ClipRunner::ClipRunner(
    const skinning::Motion& motion,
    const RunOptions& options,
    std::shared_ptr<const skinning::Topology> topology,
    MethodFactory factory,
    std::shared_ptr<const culling::FeatureTopology> features,
    std::shared_ptr<culling::HierarchyCache> hierarchies)
    : motion_(motion),
      options_(options),
      factory_(std::move(factory)),
      method_options_(method_options_of(options, motion)),
      plan_(make_plan(motion, options)),
      topology_(std::move(topology)) {
  if (topology_ == nullptr) throw InvalidInput("ClipRunner: no topology given");
  // Within one query the elementary tests may split over the threads asked for (identical
  // output) when the run is serial across queries; otherwise blocks of samples go to workers
  // (below), each query on one thread.
  method_options_.elementary.threads = resolve_threads(options.threads);
  method_options_.elementary.tests_done = options.elementary_tests_done;
  // Incremental DCD needs every contact of the interval: the registered methods with a CCD that
  // never misses (not `fast`), the ccd/ kernels, and both queries.
  incremental_dcd_ = options.incremental_dcd && !factory_ &&
                     options.accuracy != ccd::Accuracy::fast && options.query == QuerySet::both &&
                     method_options_.elementary.vertex_face == nullptr &&
                     method_options_.elementary.edge_edge == nullptr &&
                     method_options_.elementary.triangles == nullptr;
  // Rigid rows for a method that takes them, when the run has CCD intervals (only those skip
  // pairs), the motion is linear blend skinning and they hold a twentieth of the triangles at
  // least (fewer did not pay for their certificates: the stormtrooper's 2 %, docs/benchmarks.md
  // "Rigid rows in `kdop`"); their intervals then carry the bone transforms that certify them.
  // `auto` gives them only to its closed group's method (`dynamic`, or `bvh` for the whole mesh):
  // none when every part goes to the cones (a garment on its own skeleton; on gen:cloth's 20,000
  // triangles the rows took 200 ms of set-up for nothing). Should `auto` then drop an idle cone
  // group for `bvh`, that `bvh` runs without rows: the same findings, without their skipped pairs.
  if (!factory_ && options.rigid_rows && options.query != QuerySet::dcd &&
      motion.skin_weights() != nullptr && takes_rigid_rows(options.method) &&
      (options.method != "auto" ||
       culling::auto_groups(
           *topology_, motion.num_bones() > 0 && method_options_.segmentation != nullptr)
               .closed_components > 0)) {
    const skinning::SkinWeights& weights = *motion.skin_weights();
    auto rows = std::make_shared<const culling::RigidRows>(culling::build_rigid_rows(
        motion.mesh(),
        *topology_,
        weights,
        static_cast<std::int32_t>(weights.cols()),
        kMinRigidRowShare));
    if (rows->num_rows() > 0) method_options_.rigid_rows = std::move(rows);
  }
  bones_ = motion.num_bones() > 0 && (needs_bone_poses(options.method, method_options_) ||
                                      method_options_.rigid_rows != nullptr);
  // What the method carries from one query to the next that would change its rows (empty:
  // nothing). It keeps a run serial (RunPlan::serial_reason) and, for the same reason, keeps a
  // held interval from reusing the last held one's row — unless what is carried is a function
  // of the pose the last query ended at (the row is then stored only where the method says it
  // is the usual one, CullingMethod::last_ccd_row_reusable).
  std::string carried;
  bool state_follows_pose = true;
  if (!factory_) {
    const culling::MethodInfo* m = culling::find_method(options.method);
    if (m != nullptr && m->serial_reason) {
      carried = m->serial_reason(method_options_, options.query != QuerySet::ccd);
    }
    state_follows_pose = carried.empty() || (m->carried_state_follows_pose &&
                                             m->carried_state_follows_pose(method_options_));
  } else if (!options.factory_methods_stateless) {
    carried = "the method factory's methods are not known to be stateless";
    state_follows_pose = false;
  }
  reuse_static_ = options.reuse_static_intervals && state_follows_pose;

  // Threads: blocks of consecutive samples (a DCD at k, then the CCD k → k+1) go to workers. The
  // blocks do not depend on the thread count: with incremental DCD each block starts with a full
  // DCD, in a serial run too, so that every row is the same on any number of threads.
  const std::int32_t wanted = resolve_threads(options.threads);
  units_ = plan_.samples - (options.query != QuerySet::ccd ? 0 : 1);
  block_starts_ = block_layout(units_, std::max(options.block_samples, std::int32_t{0}));
  const auto blocks = static_cast<std::int32_t>(block_starts_.size()) - 1;
  if (wanted > 1) {
    plan_.serial_reason = carried;
    if (plan_.serial_reason.empty() && blocks > 1) {
      plan_.threads = std::min(wanted, blocks);
      plan_.blocks = blocks;
      const auto [first, end] = block(0);
      plan_.block_samples = end - first;  // the first block is a largest one
    }
  }

  // The workers of a parallel run keep each query's elementary tests on their own thread: the
  // other threads have blocks of their own, and splitting the tests there cost the whole
  // stormtrooper clip 3 % on 2 threads (`bvh`: 1.035 s against 1.002 s) for nothing.
  if (plan_.threads > 1) method_options_.elementary.threads = 1;

  // One FeatureTopology of the mesh, in triangle order, for every thread's method (and what they
  // build over the same mesh) and the DCD updaters: the same for all, where each used to build
  // its own (`dynamic` on one thread: its `bvh`, its updater and the runner's updater, three).
  // The caller's, when built from the mesh and the topology moved in here.
  method_options_.features =
      culling::shared_or_built(std::move(features), motion_.mesh(), *topology_);

  // The cache the methods are built through, closed and let go once they are (or fail).
  struct CloseWhenBuilt {
    culling::MethodOptions& options;
    ~CloseWhenBuilt() {
      if (options.hierarchies) options.hierarchies->close();
      options.hierarchies.reset();
    }
  };
  // The method; in a parallel run, the other workers' methods at the same time, so that every
  // worker starts checking with the first block instead of one waiting for its method (a serial
  // stretch of a parallel run: 20-40 ms of a 0.4-0.9 s check). They are built by oneTBB's
  // workers, the threads that check the blocks next: the pipeline then starts with its workers
  // running, where threads of their own left oneTBB to create its workers at the first block
  // (1.5-3 ms before the second thread took one, on this 2-core VM).
  if (plan_.threads <= 1) {
    // One method: nothing to share. A hand-over cache lends it the tree the caller's baseline
    // `bvh` built (the same key, refit at its first query) instead of a second build; closed
    // once it is built, so that nothing else is held for the run. Any other cache is closed
    // unused, and what the caller built through it freed.
    if (hierarchies && hierarchies->sharing() == culling::HierarchyCache::Sharing::hand_over) {
      hierarchies->keep_no_more();  // this method is the last: what it builds, it holds alone
      method_options_.hierarchies = std::move(hierarchies);
    } else if (hierarchies) {
      hierarchies->close();
    }
    const CloseWhenBuilt close_when_built{method_options_};
    method_ = build_method();
    adopt_method_features();
    return;
  }
  // The workers' methods are alike: each hierarchy is built once (by the first thread to ask,
  // or by the caller's baseline), the others copy it. Closed when they are built, so that the
  // trees it holds are not kept for the run; the methods keep their own copies.
  // A hand-over cache lends to one method at a time: the workers would build their trees one
  // after another under its lock. Closed (its tree freed), and a cache of copies instead.
  if (hierarchies && hierarchies->sharing() == culling::HierarchyCache::Sharing::hand_over) {
    hierarchies->close();
    hierarchies.reset();
  }
  method_options_.hierarchies =
      hierarchies ? std::move(hierarchies) : std::make_shared<culling::HierarchyCache>();
  const CloseWhenBuilt close_when_built{method_options_};
  spare_methods_.resize(static_cast<std::size_t>(plan_.threads - 1));
  const tbb::global_control allowed(
      tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(plan_.threads));
  tbb::task_arena arena(plan_.threads);
  arena.execute([this] {
    tbb::task_group others;
    for (auto& spare : spare_methods_) others.run([this, &spare] { spare = build_method(); });
    try {
      method_ = build_method();
    } catch (...) {
      try {
        others.wait();  // none may outlive this constructor
      } catch (...) {   // this thread's failure is the one reported
      }
      throw;
    }
    others.wait();  // rethrows the first failure of the others
  });
  adopt_method_features();
}

void ClipRunner::adopt_method_features() {
  // A method that works on features of its own owner order (`dynamic`: rims first) does not take
  // the runner's, which would then be held for the DCD updaters alone. They read no ownership:
  // they take the method's, and the runner's is freed (unless the caller still holds it) — one
  // FeatureTopology of the mesh where there were two (docs/culling.md "Bounded memory"). Not
  // one of a capped mesh (ghost caps): that one does not describe this mesh. Without incremental
  // DCD no updater is built, and the runner holds none at all (`dynamic` with ghost caps: 2.7 MB
  // on the 19k-triangle RobotExpressive copy).
  if (!incremental_dcd_) {
    method_options_.features.reset();
    return;
  }
  std::shared_ptr<const culling::FeatureTopology> own = method_->shared_features();
  if (own != nullptr && own != method_options_.features &&
      own->describes(motion_.mesh(), *topology_)) {
    method_options_.features = std::move(own);
  }
}

std::unique_ptr<culling::CullingMethod> ClipRunner::build_method() const {
  std::unique_ptr<culling::CullingMethod> m =
      factory_ ? factory_(motion_.mesh(), *topology_, method_options_)
               : culling::make_method(options_.method, motion_.mesh(), *topology_, method_options_);
  if (!m) throw InvalidInput("method '" + options_.method + "' could not be built");
  return m;
}

std::pair<std::int32_t, std::int32_t> ClipRunner::block(std::int32_t i) const {
  const auto at = [&](std::int32_t j) { return block_starts_[static_cast<std::size_t>(j)]; };
  return {plan_.first_sample + at(i), plan_.first_sample + at(i + 1)};
}

std::int32_t ClipRunner::blocks() const {
  return static_cast<std::int32_t>(block_starts_.size()) - 1;
}

void ClipRunner::run(const FrameCallback& on_frame) {
  if (plan_.threads > 1) {
    run_parallel(on_frame);
  } else {
    run_serial(on_frame);
  }
}

void ClipRunner::run_serial(const FrameCallback& on_frame) {
  // One query at a time; with more than one thread asked for, the elementary tests of a query
  // split over an arena of that many (the parallel loops run in the caller's arena).
  const std::int32_t threads = method_options_.elementary.threads;
  if (threads > 1) {
    const tbb::global_control allowed(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    tbb::task_arena arena(threads);
    arena.execute([&] { run_queries_in_order(on_frame); });
  } else {
    run_queries_in_order(on_frame);
  }
}

void ClipRunner::run_queries_in_order(const FrameCallback& on_frame) {
  const FeatureNumbering numbering(motion_.mesh(), *topology_);
  const RowContext context{
      motion_,
      *topology_,
      numbering,
      bones_,
      incremental_dcd_ ? &method_options_.elementary : nullptr,
      method_options_.features,
      reuse_static_,
      identity_welding(*topology_)};
  const bool dcd = options_.query != QuerySet::ccd;
  const SampleSequence all{
      .first = plan_.first_sample,
      .end = dcd ? plan_.last_sample + 1 : plan_.last_sample,
      .last = plan_.last_sample,
      .dcd = dcd,
      .ccd = options_.query != QuerySet::dcd};
  Worker w;
  w.method = method_.get();
  if (!incremental_dcd_) {
    check_samples(context, all, w, on_frame);
    return;
  }
  // The blocks of a parallel run, one after the other (each starts with a full DCD).
  for (std::int32_t i = 0; i < blocks(); ++i) {
    SampleSequence part = all;
    std::tie(part.first, part.end) = block(i);
    check_samples(context, part, w, on_frame);
  }
}

void ClipRunner::run_parallel(const FrameCallback& on_frame) {
  const FeatureNumbering numbering(motion_.mesh(), *topology_);
  const RowContext context{
      motion_,
      *topology_,
      numbering,
      bones_,
      incremental_dcd_ ? &method_options_.elementary : nullptr,
      method_options_.features,
      reuse_static_,
      identity_welding(*topology_)};
  const bool dcd = options_.query != QuerySet::ccd;
  const bool ccd = options_.query != QuerySet::dcd;
  const std::int32_t last = plan_.last_sample;
  // Block "units" k: the DCD at k (if asked) then the CCD k → k+1 (if asked and k < last) — the
  // serial row order, cut into runs of consecutive k.
  [[maybe_unused]] const std::int32_t end = dcd ? last + 1 : last;

  // Worker 0 is the method built by the constructor; the others are built on first need, each
  // with the same options (what a query needs travels with the query).
  WorkerPool pool([&] {
    auto w = std::make_unique<Worker>();
    w->owned = build_method();
    w->method = w->owned.get();
    return w;
  });
  // The runner's methods, one per thread (built together by the constructor); the pool builds
  // more only if a run needs more workers than threads.
  std::vector<culling::CullingMethod*> built{method_.get()};
  for (const auto& m : spare_methods_) built.push_back(m.get());
  for (culling::CullingMethod* m : built) {
    auto w = std::make_unique<Worker>();
    w->method = m;
    pool.add(std::move(w));
  }

  const auto check_block = [&](Block& block) {
    Worker* acquired = nullptr;
    try {
      acquired = &pool.acquire();
      const SampleSequence part{
          .first = block.first, .end = block.end, .last = last, .dcd = dcd, .ccd = ccd};
      check_samples(
          context, part, *acquired, [&](FrameReport& r) { block.reports.push_back(std::move(r)); });
    } catch (...) {
      // Reported after the rows before it, in order: as a serial run would.
      block.error = std::current_exception();
    }
    if (acquired != nullptr) pool.release(*acquired);
  };

  std::int32_t next = 0;  // the next block's index
  const auto live_blocks =
      static_cast<std::size_t>(2 * plan_.threads);  // bounds the reorder buffer
  // As many threads as asked for, even beyond the cores (TBB caps its workers at the core count
  // otherwise and warns on stderr).
  const tbb::global_control allowed(
      tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(plan_.threads));
  tbb::task_arena arena(plan_.threads);
  // The first failure in row order (a block's error, or on_frame's), rethrown once the pipeline
  // has drained: an exception thrown through parallel_pipeline would leave the blocks in flight
  // undestroyed (LeakSanitizer sees them). After it, no block is started or reported.
  std::exception_ptr failure;
  std::atomic<bool> failed{false};
  arena.execute([&] {
    tbb::parallel_pipeline(
        live_blocks,
        tbb::make_filter<void, std::shared_ptr<Block>>(
            tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& control) -> std::shared_ptr<Block> {
              if (next >= blocks() || failed.load()) {
                control.stop();
                return nullptr;
              }
              auto part = std::make_shared<Block>();
              std::tie(part->first, part->end) = block(next++);
              assert(part->end <= end);
              part->reports.reserve(static_cast<std::size_t>(2 * (part->end - part->first)));
              return part;
            }) &
            tbb::make_filter<std::shared_ptr<Block>, std::shared_ptr<Block>>(
                tbb::filter_mode::parallel,
                [&](std::shared_ptr<Block> block) {
                  // A block after a failure is never reported: no need to check it.
                  if (!failed.load()) check_block(*block);
                  return block;
                }) &
            tbb::make_filter<std::shared_ptr<Block>, void>(
                tbb::filter_mode::serial_in_order, [&](const std::shared_ptr<Block>& block) {
                  if (failure) return;  // rows after the first failure: a serial run has none
                  try {
                    for (auto& report : block->reports) on_frame(report);
                  } catch (...) {
                    failure = std::current_exception();
                  }
                  if (!failure && block->error) failure = block->error;
                  if (failure) failed.store(true);
                }));
  });
  if (failure) std::rethrow_exception(failure);
}

std::vector<LogRoute> ClipRunner::routes(std::int32_t part_offset) const {
  std::vector<LogRoute> routes;
  if (options_.method != "auto" || !method_) return routes;
  // The method's own: `auto` may change a route once built (a cone group whose cones do not pay).
  for (const auto& r : culling::routes_of(*method_)) {
    routes.push_back(LogRoute{
        .component = r.component,
        .part = r.part + part_offset,
        .closed = r.closed,
        .triangles = r.num_triangles,
        .method = r.method});
  }
  return routes;
}

}  // namespace skelcd::tools
