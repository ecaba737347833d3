#include "tools/runner.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

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

ClipRunner::ClipRunner(
    const skinning::Motion& motion,
    const RunOptions& options,
    MethodFactory factory)
    : motion_(motion), options_(options), plan_(make_plan(motion, options)) {
  topology_ = skinning::build_topology(motion.mesh());
  const culling::MethodOptions method_options{
      .accuracy = options.accuracy, .min_separation = options.min_separation,
      .extension = options.method_extension};
  if (factory) {
    method_ = factory(motion.mesh(), topology_, method_options);
  } else {
    method_ = culling::make_method(options.method, motion.mesh(), topology_, method_options);
  }
  if (!method_) throw InvalidInput("method '" + options.method + "' could not be built");
}

void ClipRunner::run(const FrameCallback& on_frame) {
  const auto& mesh = motion_.mesh();
  const FeatureNumbering numbering(mesh, topology_);
  const bool dcd = options_.query != QuerySet::ccd;
  const bool ccd = options_.query != QuerySet::dcd;

  // Buffers reused across samples: the file positions of the sample being posed, and the welded
  // positions at the interval's two ends.
  skinning::Positions posed;
  skinning::Positions welded_t0;
  skinning::Positions welded_t1;
  culling::FrameResult result;
  FrameReport report;

  // Poses sample i into `welded`; returns the microseconds it took. Finiteness is checked once
  // per sample, here, where positions enter.
  const auto pose = [&](std::int32_t i, skinning::Positions& welded) {
    const auto start = Clock::now();
    motion_.positions(i, posed);
    if (posed.rows() != mesh.num_vertices()) {
      throw InvalidInput(motion_.name() + ": sample " + std::to_string(i) + " has " +
                         std::to_string(posed.rows()) + " positions, expected " +
                         std::to_string(mesh.num_vertices()));
    }
    if (!posed.allFinite()) {
      Eigen::Index bad = 0;
      while (bad < posed.rows() && posed.row(bad).allFinite()) ++bad;
      throw InvalidInput(motion_.name() + ": sample " + std::to_string(i) + " (t = " +
                         std::to_string(motion_.sample_time(i)) + " s): vertex " +
                         std::to_string(bad) + " has a non-finite position");
    }
    skinning::gather_welded(topology_, posed, welded);
    return microseconds_since(start);
  };

  // Converts the method's findings (welded numbering) into rows in the file's numbering and
  // reports the row. The found-counters are taken from the findings themselves so that a row's
  // counts always equal its rows in /contacts and /dcd_pairs.
  const auto finish_row = [&](QueryKind kind, std::int32_t sample, double skin_us,
                              Clock::time_point start) {
    report.row = FrameRow{};
    report.row.sample = sample;
    report.row.kind = kind;
    report.row.t0 = motion_.sample_time(sample);
    report.row.t1 = kind == QueryKind::ccd ? motion_.sample_time(sample + 1) : report.row.t0;
    report.row.counters = result.counters;
    report.row.times = result.times;
    report.row.times.skin_us = skin_us;
    report.contacts.clear();
    report.dcd_pairs.clear();
    std::int64_t vf = 0;
    std::int64_t ee = 0;
    for (const auto& c : result.contacts) {
      const bool is_vf = c.kind == culling::CcdContact::Kind::vf;
      (is_vf ? vf : ee) += 1;
      report.contacts.push_back(ContactRow{
          .frame = sample,
          .kind = c.kind,
          .a = is_vf ? numbering.vertex(c.a) : numbering.edge(c.a),
          .b = is_vf ? numbering.triangle(c.b) : numbering.edge(c.b),
          .toi_lower = c.toi_lower,
          .toi_upper = c.toi_upper,
      });
    }
    for (const auto& p : result.dcd_pairs) {
      report.dcd_pairs.push_back(
          DcdPairRow{.frame = sample, .a = numbering.triangle(p.a), .b = numbering.triangle(p.b)});
    }
    if (kind == QueryKind::ccd) {
      report.row.counters.vf_contacts = vf;
      report.row.counters.ee_contacts = ee;
    } else {
      report.row.counters.dcd_pairs = static_cast<std::int64_t>(result.dcd_pairs.size());
    }
    report.row.total_us = skin_us + microseconds_since(start);
    on_frame(report);
  };

  const auto run_dcd = [&](std::int32_t sample, const skinning::Positions& x, double skin_us) {
    const auto start = Clock::now();
    result.clear();
    if (options_.before_query) options_.before_query(sample, sample);
    method_->detect_dcd(x, result);
    finish_row(QueryKind::dcd, sample, skin_us, start);
  };

  // Skinning time is charged to the first row that needs the sample.
  double pending_skin_us = pose(plan_.first_sample, welded_t1);
  if (dcd) {
    run_dcd(plan_.first_sample, welded_t1, std::exchange(pending_skin_us, 0.0));
  }
  for (std::int32_t i = plan_.first_sample; i < plan_.last_sample; ++i) {
    std::swap(welded_t0, welded_t1);
    pending_skin_us += pose(i + 1, welded_t1);
    if (ccd) {
      const auto start = Clock::now();
      result.clear();
      if (options_.before_query) options_.before_query(i, i + 1);
      method_->detect_ccd(welded_t0, welded_t1, result);
      finish_row(QueryKind::ccd, i, std::exchange(pending_skin_us, 0.0), start);
    }
    if (dcd) run_dcd(i + 1, welded_t1, std::exchange(pending_skin_us, 0.0));
  }
}

}  // namespace skelcd::tools
