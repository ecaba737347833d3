#include "tools/runner.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <utility>

#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"

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
    throw InvalidInput("--frames " + std::to_string(plan.first_sample) + ":" +
                       std::to_string(plan.last_sample) + " is outside the " +
                       std::to_string(samples) + " samples (0:" + std::to_string(samples - 1) +
                       ") of " + motion.name());
  }
  plan.samples = plan.last_sample - plan.first_sample + 1;
  const bool dcd = options.query != QuerySet::ccd;
  const bool ccd = options.query != QuerySet::dcd;
  plan.intervals = ccd ? plan.samples - 1 : 0;
  if (ccd && !dcd && plan.intervals == 0) {
    throw InvalidInput("--query ccd needs at least two samples; --frames selects only sample " +
                       std::to_string(plan.first_sample));
  }
  plan.rows = (dcd ? plan.samples : 0) + plan.intervals;
  return plan;
}


/// What one row needs from the run: the motion, the welded topology and the file numbering.
struct RowContext {
  const skinning::Motion& motion;
  const skinning::Topology& topology;
  const FeatureNumbering& numbering;
};

/// Poses sample i into `welded` (`posed`: scratch); returns the microseconds it took.
/// Finiteness is checked once per sample, here, where positions enter.
double pose_sample(const RowContext& c, std::int32_t i, skinning::Positions& posed,
                   skinning::Positions& welded) {
  const auto start = Clock::now();
  const auto& mesh = c.motion.mesh();
  c.motion.positions(i, posed);
  if (posed.rows() != mesh.num_vertices()) {
    throw InvalidInput(c.motion.name() + ": sample " + std::to_string(i) + " has " +
                       std::to_string(posed.rows()) + " positions, expected " +
                       std::to_string(mesh.num_vertices()));
  }
  if (!posed.allFinite()) {
    Eigen::Index bad = 0;
    while (bad < posed.rows() && posed.row(bad).allFinite()) ++bad;
    throw InvalidInput(c.motion.name() + ": sample " + std::to_string(i) + " (t = " +
                       std::to_string(c.motion.sample_time(i)) + " s): vertex " +
                       std::to_string(bad) + " has a non-finite position");
  }
  skinning::gather_welded(c.topology, posed, welded);
  return microseconds_since(start);
}

/// Converts the method's findings (welded numbering) into a row in the file's numbering. The
/// found-counters are taken from the findings themselves so that a row's counts always equal its
/// rows in /contacts and /dcd_pairs.
void make_report(const RowContext& c, QueryKind kind, std::int32_t sample,
                 const culling::FrameResult& result, double skin_us, Clock::time_point start,
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
    report.dcd_pairs.push_back(
        DcdPairRow{.frame = sample, .a = c.numbering.triangle(p.a), .b = c.numbering.triangle(p.b)});
  }
  if (kind == QueryKind::ccd) {
    report.row.counters.vf_contacts = vf;
    report.row.counters.ee_contacts = ee;
  } else {
    report.row.counters.dcd_pairs = static_cast<std::int64_t>(result.dcd_pairs.size());
  }
  report.row.total_us = skin_us + microseconds_since(start);
}

bool is_radial_view(std::string_view name) { return name == "rvbc" || name == "dynamic"; }

bool known_stateless(std::string_view name) {
  for (const char* n : {"brute", "bvh", "kdop", "normal-cone", "dual-cone", "enhanced-dual-cone",
                        "auto"}) {
    if (name == n) return true;
  }
  return false;
}

/// One parallel worker: its own method, hook and buffers.
struct Worker {
  std::unique_ptr<culling::CullingMethod> owned;
  culling::CullingMethod* method = nullptr;
  std::function<void(std::int32_t, std::int32_t)> before_query;
  skinning::Positions posed;
  skinning::Positions welded_t0;
  skinning::Positions welded_t1;
  culling::FrameResult result;
};

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
    return InvalidInput("--frames '" + std::string(text) + "': " + why +
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
    : mesh_(mesh), topology_(topology) {
  // Name every edge through the first triangle incident to it (CSR edge → faces) and the side of
  // that triangle it is.
  const std::int32_t num_edges = topology.num_edges();
  edges_.assign(static_cast<std::size_t>(num_edges), FeatureId{});
  for (std::int32_t e = 0; e < num_edges; ++e) {
    const auto begin = topology.edge_face_offsets[static_cast<std::size_t>(e)];
    const auto end = topology.edge_face_offsets[static_cast<std::size_t>(e) + 1];
    if (begin == end) continue;
    const std::int32_t f = topology.edge_faces[static_cast<std::size_t>(begin)];
    for (std::int8_t k = 0; k < 3; ++k) {
      if (topology.face_edges(f, k) == e) {
        auto& id = edges_[static_cast<std::size_t>(e)];
        id = triangle(f);
        id.side = k;
        break;
      }
    }
  }
}

FeatureId FeatureNumbering::vertex(std::int32_t welded_vertex) const {
  const auto v = static_cast<std::size_t>(
      topology_.representative_vertex[static_cast<std::size_t>(welded_vertex)]);
  return FeatureId{mesh_.vertex_part[v], mesh_.vertex_index_in_part[v], -1};
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

std::string serial_reason(std::string_view name, const RunOptions& options) {
  const bool radial_view =
      is_radial_view(name) || (name == "auto" && options.method_extension != nullptr);
  if (radial_view && options.min_separation == 0.0) {
    // What rvbc/dynamic carry from one query to the next (docs/check.md, "Threads").
    if (options.query == QuerySet::ccd) {
      return "method " + std::string(name) +
             " carries each interval's end state into the next; without the DCD at each sample "
             "(--query ccd) that changes its counters";
    }
    if (options.accuracy == ccd::Accuracy::fast) {
      return "method " + std::string(name) +
             " carries each interval's end state into the next; with --accuracy fast (which may "
             "miss contacts) that can change its rows";
    }
  } else if (!radial_view && !known_stateless(name)) {
    return "method " + std::string(name) + " is not known to be free of state between queries";
  }
  if (options.before_query && !options.make_worker_hooks) {
    return "the before-query hook cannot be copied per worker";
  }
  return {};
}

ClipRunner::ClipRunner(
    const skinning::Motion& motion,
    const RunOptions& options,
    MethodFactory factory)
    : motion_(motion),
      options_(options),
      factory_(std::move(factory)),
      method_options_{.accuracy = options.accuracy,
                      .min_separation = options.min_separation,
                      .extension = options.method_extension},
      plan_(make_plan(motion, options)) {
  // Within one query the elementary tests may split over the threads asked for (identical
  // output); across queries, blocks of samples go to workers (below) when the method allows.
  method_options_.elementary.threads = resolve_threads(options.threads);
  method_options_.elementary.tests_done = options.elementary_tests_done;
  topology_ = skinning::build_topology(motion.mesh());
  if (factory_) {
    method_ = factory_(motion.mesh(), topology_, method_options_);
  } else {
    method_ = culling::make_method(options.method, motion.mesh(), topology_, method_options_);
  }
  if (!method_) throw InvalidInput("method '" + options.method + "' could not be built");

  // Threads: blocks of consecutive samples (a DCD at k, then the CCD k → k+1) go to workers.
  const std::int32_t wanted = resolve_threads(options.threads);
  if (wanted > 1) {
    if (!factory_) {
      plan_.serial_reason = serial_reason(method_->name(), options);
    } else if (!options.factory_methods_stateless) {
      plan_.serial_reason = "the method factory's methods are not known to be stateless";
    } else if (options.before_query && !options.make_worker_hooks) {
      plan_.serial_reason = "the before-query hook cannot be copied per worker";
    }
    const bool dcd = options.query != QuerySet::ccd;
    const std::int32_t units = plan_.samples - (dcd ? 0 : 1);
    const std::int32_t block =
        options.block_samples > 0 ? options.block_samples
                                  : std::clamp(units / (wanted * 8), std::int32_t{4}, std::int32_t{64});
    const std::int32_t blocks = (units + block - 1) / block;
    if (plan_.serial_reason.empty() && blocks > 1) {
      plan_.threads = std::min(wanted, blocks);
      plan_.block_samples = block;
    }
  }
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
  const FeatureNumbering numbering(motion_.mesh(), topology_);
  const RowContext context{motion_, topology_, numbering};
  const bool dcd = options_.query != QuerySet::ccd;
  const bool ccd = options_.query != QuerySet::dcd;

  // Buffers reused across samples: the file positions of the sample being posed, and the welded
  // positions at the interval's two ends.
  skinning::Positions posed;
  skinning::Positions welded_t0;
  skinning::Positions welded_t1;
  culling::FrameResult result;
  FrameReport report;

  const auto run_dcd = [&](std::int32_t sample, const skinning::Positions& x, double skin_us) {
    const auto start = Clock::now();
    result.clear();
    if (options_.before_query) options_.before_query(sample, sample);
    method_->detect_dcd(x, result);
    make_report(context, QueryKind::dcd, sample, result, skin_us, start, report);
    on_frame(report);
  };

  // Skinning time is charged to the first row that needs the sample.
  double pending_skin_us = pose_sample(context, plan_.first_sample, posed, welded_t1);
  if (dcd) {
    run_dcd(plan_.first_sample, welded_t1, std::exchange(pending_skin_us, 0.0));
  }
  for (std::int32_t i = plan_.first_sample; i < plan_.last_sample; ++i) {
    std::swap(welded_t0, welded_t1);
    pending_skin_us += pose_sample(context, i + 1, posed, welded_t1);
    if (ccd) {
      const auto start = Clock::now();
      result.clear();
      if (options_.before_query) options_.before_query(i, i + 1);
      method_->detect_ccd(welded_t0, welded_t1, result);
      make_report(context, QueryKind::ccd, i, result, std::exchange(pending_skin_us, 0.0), start,
                  report);
      on_frame(report);
    }
    if (dcd) run_dcd(i + 1, welded_t1, std::exchange(pending_skin_us, 0.0));
  }
}

void ClipRunner::run_parallel(const FrameCallback& on_frame) {
  const FeatureNumbering numbering(motion_.mesh(), topology_);
  const RowContext context{motion_, topology_, numbering};
  const bool dcd = options_.query != QuerySet::ccd;
  const bool ccd = options_.query != QuerySet::dcd;
  const std::int32_t last = plan_.last_sample;
  // Block "units" k: the DCD at k (if asked) then the CCD k → k+1 (if asked and k < last) — the
  // serial row order, cut into runs of consecutive k.
  const std::int32_t end = dcd ? last + 1 : last;

  // Worker 0 is the method built by the constructor (with the caller's hook); the others are built
  // on first need, each with its own hooks.
  WorkerPool pool([&] {
    auto w = std::make_unique<Worker>();
    culling::MethodOptions method_options = method_options_;
    if (options_.make_worker_hooks) {
      auto hooks = options_.make_worker_hooks();
      method_options.extension = std::move(hooks.method_extension);
      w->before_query = std::move(hooks.before_query);
    }
    w->owned = factory_ ? factory_(motion_.mesh(), topology_, method_options)
                        : culling::make_method(options_.method, motion_.mesh(), topology_,
                                               method_options);
    if (!w->owned) throw InvalidInput("method '" + options_.method + "' could not be built");
    w->method = w->owned.get();
    return w;
  });
  {
    auto first = std::make_unique<Worker>();
    first->method = method_.get();
    first->before_query = options_.before_query;
    pool.add(std::move(first));
  }

  const auto check_block = [&](Block& block) {
    Worker* acquired = nullptr;
    try {
      acquired = &pool.acquire();
      Worker& w = *acquired;
      const auto query = [&](std::int32_t s0, std::int32_t s1) {
        w.result.clear();
        if (w.before_query) w.before_query(s0, s1);
      };
      double pending_skin_us = pose_sample(context, block.first, w.posed, w.welded_t1);
      for (std::int32_t k = block.first; k < block.end; ++k) {
        if (dcd) {
          if (k > block.first && !ccd) pending_skin_us += pose_sample(context, k, w.posed, w.welded_t1);
          const auto start = Clock::now();
          query(k, k);
          w.method->detect_dcd(w.welded_t1, w.result);
          make_report(context, QueryKind::dcd, k, w.result, std::exchange(pending_skin_us, 0.0),
                      start, block.reports.emplace_back());
        }
        if (ccd && k < last) {
          std::swap(w.welded_t0, w.welded_t1);
          pending_skin_us += pose_sample(context, k + 1, w.posed, w.welded_t1);
          const auto start = Clock::now();
          query(k, k + 1);
          w.method->detect_ccd(w.welded_t0, w.welded_t1, w.result);
          make_report(context, QueryKind::ccd, k, w.result, std::exchange(pending_skin_us, 0.0),
                      start, block.reports.emplace_back());
        }
      }
    } catch (...) {
      // Reported after the rows before it, in order: as a serial run would.
      block.error = std::current_exception();
    }
    if (acquired != nullptr) pool.release(*acquired);
  };

  const std::int32_t block_samples = plan_.block_samples;
  std::int32_t next = plan_.first_sample;
  const auto live_blocks = static_cast<std::size_t>(2 * plan_.threads);  // bounds the reorder buffer
  // As many threads as asked for, even beyond the cores (TBB caps its workers at the core count
  // otherwise and warns on stderr).
  const tbb::global_control allowed(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(plan_.threads));
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
              if (next >= end || failed.load()) {
                control.stop();
                return nullptr;
              }
              auto block = std::make_shared<Block>();
              block->first = next;
              block->end = std::min(end, next + block_samples);
              block->reports.reserve(static_cast<std::size_t>(2 * (block->end - block->first)));
              next = block->end;
              return block;
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
                    for (const auto& report : block->reports) on_frame(report);
                  } catch (...) {
                    failure = std::current_exception();
                  }
                  if (!failure && block->error) failure = block->error;
                  if (failure) failed.store(true);
                }));
  });
  if (failure) std::rethrow_exception(failure);
}

std::vector<LogRoute> method_routes(
    const skinning::Topology& topology, const RunOptions& options, std::int32_t part_offset) {
  std::vector<LogRoute> routes;
  if (options.method != "auto") return routes;
  const culling::MethodOptions method_options{
      .accuracy = options.accuracy,
      .min_separation = options.min_separation,
      .extension = options.method_extension};
  for (const auto& r : culling::route_components(topology, method_options)) {
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
