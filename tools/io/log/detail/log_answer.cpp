#include "tools/io/log/detail/log_answer.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "skinning/detail/answer_stream.hpp"

namespace skelcd::tools::detail {
namespace {

using skinning::detail::AnswerReader;
using skinning::detail::AnswerWriter;
using skinning::detail::kAnswerCountBytes;

// "SKLG" and a layout version (parent and child are one program, forked: these only catch a
// reader out of step with the writer, or bytes that are not an answer at all).
constexpr std::uint32_t kMagic = 0x474c4b53;
constexpr std::uint32_t kVersion = 1;
// Closes the stream: what follows the last field must be exactly this.
constexpr std::uint32_t kEnd = 0x444e4521;

// The tables' rows go as one block each.
static_assert(std::is_trivially_copyable_v<FrameRow>);
static_assert(std::is_trivially_copyable_v<ContactRow>);
static_assert(std::is_trivially_copyable_v<DcdPairRow>);

// Bytes each element takes at least in the stream: a count of N elements must leave N times this
// in the bytes still to read, which bounds every allocation by what was actually received.
constexpr std::size_t kStringMin = kAnswerCountBytes;
constexpr std::size_t kRouteMin = 3 * sizeof(std::int32_t) + sizeof(std::uint8_t) + kStringMin;
constexpr std::size_t kCheckMin = 6 * kStringMin;
constexpr std::size_t kEventMin =
    3 * sizeof(std::int32_t) + 2 * sizeof(double) + sizeof(std::uint8_t) + 2 * kAnswerCountBytes +
    3 * sizeof(std::int64_t) + sizeof(double) + 2 * sizeof(std::int32_t);

template <class T>
void write_optional(AnswerWriter& w, const std::optional<T>& value) {
  w.scalar(static_cast<std::uint8_t>(value.has_value()));
  if (value) w.scalar(*value);
}

template <class T>
std::optional<T> read_optional(AnswerReader& r) {
  const auto present = r.scalar<std::uint8_t>();
  if (present > 1) r.damaged("an optional value flagged " + std::to_string(present));
  if (present == 0) return std::nullopt;
  return r.scalar<T>();
}

bool read_flag(AnswerReader& r, const char* what) {
  const auto value = r.scalar<std::uint8_t>();
  if (value > 1) r.damaged(std::string(what) + " flagged " + std::to_string(value));
  return value == 1;
}

// --- writing, field by field in the order of the structs (log_header.hpp, log_reader.hpp) -----

void write_header(AnswerWriter& w, const LogHeader& h) {
  w.scalar(h.format_version);
  w.string(h.skelcd_version);
  w.string(h.command_line);
  w.string(h.input_path);
  w.string(h.input_hash);
  w.string(h.clip);
  w.string(h.method);
  w.string(h.accuracy);
  w.string(h.query);
  w.scalar(h.fps);
  w.scalar(h.min_separation);
  write_optional(w, h.gamma);
  write_optional(w, h.theta);
  write_optional(w, h.seed);
  w.string(h.segmentation);
  w.string(h.start_time);
  w.scalar(h.first_sample);
  w.scalar(h.last_sample);
  w.scalar(h.planned_rows);
  w.scalar(h.num_vertices);
  w.scalar(h.num_triangles);
  w.strings(h.part_names);
  w.count(h.routes.size());
  for (const auto& route : h.routes) {
    w.scalar(route.component);
    w.scalar(route.part);
    w.scalar(static_cast<std::uint8_t>(route.closed));
    w.scalar(route.triangles);
    w.string(route.method);
  }
  w.count(h.checks.size());
  for (const auto& check : h.checks) {
    w.string(check.name);
    w.string(check.object_a);
    w.string(check.object_b);
    w.string(check.query);
    w.string(check.method);
    w.string(check.accuracy);
  }
  w.string(h.baseline);
  w.scalar(h.baseline_slack);
  w.strings(h.allow);
  w.scalar(static_cast<std::uint8_t>(h.allow_adjacent_bones));
  w.scalar(static_cast<std::uint8_t>(h.complete));
}

void write_event(AnswerWriter& w, const EventRecord& e) {
  w.scalar(e.id);
  w.scalar(e.first_sample);
  w.scalar(e.last_sample);
  w.scalar(e.t_first);
  w.scalar(e.t_last);
  write_optional(w, e.t_first_contact);
  w.array(e.parts);
  w.strings(e.bones);
  w.scalar(e.peak_pairs);
  w.scalar(e.peak_sample);
  w.scalar(e.dcd_pairs);
  w.scalar(e.ccd_contacts);
  w.scalar(e.depth);
  w.scalar(e.merged_into);
}

// --- reading, in the same order ----------------------------------------------------------------

LogHeader read_header(AnswerReader& r) {
  LogHeader h;
  h.format_version = r.scalar<std::int32_t>();
  h.skelcd_version = r.string("version bytes");
  h.command_line = r.string("command line bytes");
  h.input_path = r.string("input path bytes");
  h.input_hash = r.string("input hash bytes");
  h.clip = r.string("clip name bytes");
  h.method = r.string("method name bytes");
  h.accuracy = r.string("accuracy name bytes");
  h.query = r.string("query name bytes");
  h.fps = r.scalar<double>();
  h.min_separation = r.scalar<double>();
  h.gamma = read_optional<double>(r);
  h.theta = read_optional<double>(r);
  h.seed = read_optional<std::int64_t>(r);
  h.segmentation = r.string("segmentation bytes");
  h.start_time = r.string("start time bytes");
  h.first_sample = r.scalar<std::int32_t>();
  h.last_sample = r.scalar<std::int32_t>();
  h.planned_rows = r.scalar<std::int64_t>();
  h.num_vertices = r.scalar<std::int64_t>();
  h.num_triangles = r.scalar<std::int64_t>();
  h.part_names = r.strings("part names");
  h.routes.resize(r.count(kRouteMin, "routes"));
  for (auto& route : h.routes) {
    route.component = r.scalar<std::int32_t>();
    route.part = r.scalar<std::int32_t>();
    route.closed = read_flag(r, "a route's closedness");
    route.triangles = r.scalar<std::int32_t>();
    route.method = r.string("route method bytes");
  }
  h.checks.resize(r.count(kCheckMin, "checks"));
  for (auto& check : h.checks) {
    check.name = r.string("check name bytes");
    check.object_a = r.string("object name bytes");
    check.object_b = r.string("object name bytes");
    check.query = r.string("query name bytes");
    check.method = r.string("method name bytes");
    check.accuracy = r.string("accuracy name bytes");
  }
  h.baseline = r.string("baseline bytes");
  h.baseline_slack = r.scalar<std::int32_t>();
  h.allow = r.strings("allowances");
  h.allow_adjacent_bones = read_flag(r, "allow-adjacent-bones");
  h.complete = read_flag(r, "completeness");
  return h;
}

EventRecord read_event(AnswerReader& r) {
  EventRecord e;
  e.id = r.scalar<std::int32_t>();
  e.first_sample = r.scalar<std::int32_t>();
  e.last_sample = r.scalar<std::int32_t>();
  e.t_first = r.scalar<double>();
  e.t_last = r.scalar<double>();
  e.t_first_contact = read_optional<double>(r);
  e.parts = r.array<std::int32_t>("event parts");
  e.bones = r.strings("event bones");
  e.peak_pairs = r.scalar<std::int64_t>();
  e.peak_sample = r.scalar<std::int32_t>();
  e.dcd_pairs = r.scalar<std::int64_t>();
  e.ccd_contacts = r.scalar<std::int64_t>();
  e.depth = r.scalar<double>();
  e.merged_into = r.scalar<std::int32_t>();
  return e;
}

// Rows arrive as the child's bytes: their enumerations must hold values the types have.
void check_rows(AnswerReader& r, const LogData& log) {
  for (const auto& row : log.frames) {
    if (row.kind != QueryKind::dcd && row.kind != QueryKind::ccd) r.damaged("a row of no query");
  }
  for (const auto& c : log.contacts) {
    if (c.kind != culling::CcdContact::Kind::vf && c.kind != culling::CcdContact::Kind::ee)
      r.damaged("a contact of no kind");
  }
}

}  // namespace

void write_log_answer(const LogData& log, const skinning::detail::AnswerSink& send) {
  AnswerWriter w(send);
  w.scalar(kMagic);
  w.scalar(kVersion);
  write_header(w, log.header);
  w.array(log.frames);
  w.array(log.contacts);
  w.array(log.dcd_pairs);
  w.array(log.frame_checks);
  w.count(log.events.size());
  for (const auto& e : log.events) write_event(w, e);
  w.scalar(static_cast<std::uint8_t>(log.events_recorded));
  w.scalar(static_cast<std::uint8_t>(log.verified));
  w.strings(log.damage);
  w.scalar(kEnd);
}

LogData read_log_answer(skinning::detail::ChildAnswer& bytes, const std::string& file) {
  AnswerReader r(bytes, file, "the log reader's");
  if (r.scalar<std::uint32_t>() != kMagic || r.scalar<std::uint32_t>() != kVersion)
    r.damaged("it does not start as a log");
  LogData log;
  log.header = read_header(r);
  log.frames = r.array<FrameRow>("rows");
  log.contacts = r.array<ContactRow>("contacts");
  log.dcd_pairs = r.array<DcdPairRow>("intersecting pairs");
  log.frame_checks = r.array<std::int32_t>("row checks");
  log.events.resize(r.count(kEventMin, "events"));
  for (auto& e : log.events) e = read_event(r);
  log.events_recorded = read_flag(r, "events-recorded");
  log.verified = read_flag(r, "verified");
  log.damage = r.strings("damage lines");
  if (r.scalar<std::uint32_t>() != kEnd) r.damaged("its fields do not end where the log does");
  if (r.left() != 0) r.damaged(std::to_string(r.left()) + " bytes after the log");
  check_rows(r, log);
  return log;
}

}  // namespace skelcd::tools::detail
