#include "tools/engine/run_summary.hpp"

#include <algorithm>
#include <set>

namespace skelcd::tools {

std::int64_t findings(const FrameRow& row) {
  return row.counters.dcd_pairs + row.counters.vf_contacts + row.counters.ee_contacts;
}

namespace {
/// A labelled row accounts for each of its findings as new, baseline or allowed.
bool labelled(const FrameRow& row) {
  const auto& c = row.counters;
  return c.new_dcd_pairs + c.new_ccd_contacts + c.baseline_dcd_pairs + c.baseline_ccd_contacts +
             c.allowed_dcd_pairs + c.allowed_ccd_contacts ==
         findings(row);
}
}  // namespace

std::int64_t new_dcd_pairs(const FrameRow& row) {
  return labelled(row) ? row.counters.new_dcd_pairs : row.counters.dcd_pairs;
}

std::int64_t new_ccd_contacts(const FrameRow& row) {
  return labelled(row) ? row.counters.new_ccd_contacts
                       : row.counters.vf_contacts + row.counters.ee_contacts;
}

std::int64_t new_findings(const FrameRow& row) {
  return new_dcd_pairs(row) + new_ccd_contacts(row);
}

RunSummary summarize(std::span<const FrameRow> rows, std::size_t worst) {
  RunSummary s;
  s.rows = static_cast<std::int64_t>(rows.size());
  std::set<std::int32_t> frames_with_findings;
  std::int32_t dcd_rows = 0;
  culling::StageTimes stage_us;
  for (const auto& row : rows) {
    const auto& c = row.counters;
    if (row.kind == QueryKind::dcd) {
      ++dcd_rows;
      s.dcd_pairs += c.dcd_pairs;
      if (new_dcd_pairs(row) > 0) ++s.frames_with_interpenetration;
    } else {
      ++s.intervals;
      s.ccd_vf += c.vf_contacts;
      s.ccd_ee += c.ee_contacts;
      if (new_ccd_contacts(row) > 0) ++s.intervals_with_contacts;
    }
    s.new_dcd_pairs += new_dcd_pairs(row);
    s.new_ccd_contacts += new_ccd_contacts(row);
    s.baseline_dcd_pairs += c.baseline_dcd_pairs;
    s.baseline_ccd_contacts += c.baseline_ccd_contacts;
    s.allowed_dcd_pairs += c.allowed_dcd_pairs;
    s.allowed_ccd_contacts += c.allowed_ccd_contacts;
    if (new_findings(row) > 0) frames_with_findings.insert(row.sample);
    s.max_candidate_pairs = std::max(s.max_candidate_pairs, c.candidate_pairs);
    s.bv_tests += c.bv_tests;
    s.candidate_pairs += c.candidate_pairs;
    s.total_ms += row.total_us / 1000.0;
    stage_us.skin_us += row.times.skin_us;
    stage_us.refit_us += row.times.refit_us;
    stage_us.classify_us += row.times.classify_us;
    stage_us.merge_us += row.times.merge_us;
    stage_us.traverse_us += row.times.traverse_us;
    stage_us.elementary_us += row.times.elementary_us;
  }
  s.frames_with_contacts = static_cast<std::int32_t>(frames_with_findings.size());
  s.samples = dcd_rows > 0 ? dcd_rows : (s.intervals > 0 ? s.intervals + 1 : 0);
  const double steps = s.intervals > 0 ? s.intervals : std::max(dcd_rows, 1);
  s.ms_per_interval = s.total_ms / steps;
  const auto per_step = [&](double us) { return us / 1000.0 / steps; };
  s.skin_ms = per_step(stage_us.skin_us);
  s.refit_ms = per_step(stage_us.refit_us);
  s.classify_ms = per_step(stage_us.classify_us);
  s.merge_ms = per_step(stage_us.merge_us);
  s.traverse_ms = per_step(stage_us.traverse_us);
  s.elementary_ms = per_step(stage_us.elementary_us);
  s.other_ms = std::max(
      0.0,
      s.ms_per_interval -
          (s.skin_ms + s.refit_ms + s.classify_ms + s.merge_ms + s.traverse_ms + s.elementary_ms));

  for (const auto& row : rows) {
    if (new_findings(row) > 0) s.worst.push_back(row);
  }
  std::stable_sort(s.worst.begin(), s.worst.end(), [](const FrameRow& a, const FrameRow& b) {
    return new_findings(a) > new_findings(b);
  });
  if (s.worst.size() > worst) s.worst.resize(worst);
  return s;
}

std::vector<const EventRecord*> root_events(const std::vector<EventRecord>& events) {
  std::vector<const EventRecord*> roots;
  for (const auto& e : events) {
    if (e.merged_into < 0) roots.push_back(&e);
  }
  return roots;
}

}  // namespace skelcd::tools
