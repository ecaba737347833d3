#include "tools/report/summary_json.hpp"

#include <cstdint>

namespace skelcd::tools {

nlohmann::json stages_json(const RunSummary& s) {
  return nlohmann::json{
      {"skin", s.skin_ms},
      {"refit", s.refit_ms},
      {"classify", s.classify_ms},
      {"merge", s.merge_ms},
      {"traverse", s.traverse_ms},
      {"elementary", s.elementary_ms},
      {"other", s.other_ms}};
}

nlohmann::json setup_json(const SetupTimes& setup) {
  return nlohmann::json{
      {"topology", setup.topology},
      {"segmentation", setup.segmentation},
      {"baseline", setup.baseline},
      {"methods", setup.methods},
      {"total", setup.total},
  };
}

nlohmann::json events_json(
    const std::vector<EventRecord>& events, const std::vector<std::string>& part_names) {
  auto list = nlohmann::json::array();
  for (const auto* e : root_events(events)) {
    std::vector<std::int32_t> merged;
    for (const auto& other : events) {
      std::int32_t into = other.merged_into;
      while (into >= 0 && into != e->id && static_cast<std::size_t>(into) < events.size()) {
        into = events[static_cast<std::size_t>(into)].merged_into;
      }
      if (into == e->id) merged.push_back(other.id);
    }
    std::vector<std::string> parts;
    for (const auto p : e->parts) {
      parts.push_back(
          p >= 0 && static_cast<std::size_t>(p) < part_names.size()
              ? part_names[static_cast<std::size_t>(p)]
              : std::to_string(p));
    }
    list.push_back({
        {"id", e->id},
        {"first_sample", e->first_sample},
        {"last_sample", e->last_sample},
        {"t_first", e->t_first},
        {"t_last", e->t_last},
        {"t_first_contact",
         e->t_first_contact ? nlohmann::json(*e->t_first_contact) : nlohmann::json(nullptr)},
        {"parts", parts},
        {"bones", e->bones},
        {"peak_pairs", e->peak_pairs},
        {"peak_sample", e->peak_sample},
        {"dcd_pairs", e->dcd_pairs},
        {"ccd_contacts", e->ccd_contacts},
        {"depth", e->depth},
        {"merged_events", merged},
    });
  }
  return list;
}

nlohmann::json summary_json(const RunIdentity& id, const RunSummary& s, const RunLabels& labels) {
  auto worst = nlohmann::json::array();
  for (const auto& row : s.worst) {
    worst.push_back(
        {{"sample", row.sample},
         {"kind", std::string(to_string(row.kind))},
         {"t0", row.t0},
         {"t1", row.t1},
         {"new_dcd_pairs", new_dcd_pairs(row)},
         {"new_ccd_contacts", new_ccd_contacts(row)},
         {"dcd_pairs", row.counters.dcd_pairs},
         {"vf_contacts", row.counters.vf_contacts},
         {"ee_contacts", row.counters.ee_contacts}});
  }
  const bool labelled = !labels.baseline.empty();
  return nlohmann::json{
      {"model", id.model},
      {"clip", id.clip},
      {"fps", id.fps},
      {"first_sample", id.first_sample},
      {"last_sample", id.last_sample},
      {"method", id.method},
      {"accuracy", id.accuracy},
      {"query", id.query},
      {"frames", s.samples},
      {"intervals", s.intervals},
      {"dcd_pairs", s.dcd_pairs},
      {"ccd_vf", s.ccd_vf},
      {"ccd_ee", s.ccd_ee},
      {"baseline", labelled ? nlohmann::json(labels.baseline) : nlohmann::json(nullptr)},
      {"baseline_slack", labels.baseline_slack},
      {"allow", labels.allow},
      {"allow_adjacent_bones", labels.allow_adjacent_bones},
      {"events",
       labels.events_recorded ? events_json(labels.events, labels.part_names)
                              : nlohmann::json(nullptr)},
      {"new_dcd_pairs", s.new_dcd_pairs},
      {"new_ccd_contacts", s.new_ccd_contacts},
      {"baseline_dcd_pairs", s.baseline_dcd_pairs},
      {"baseline_ccd_contacts", s.baseline_ccd_contacts},
      {"allowed_dcd_pairs", s.allowed_dcd_pairs},
      {"allowed_ccd_contacts", s.allowed_ccd_contacts},
      {"frames_with_contacts", s.frames_with_contacts},
      {"frames_with_interpenetration", s.frames_with_interpenetration},
      {"intervals_with_contacts", s.intervals_with_contacts},
      {"max_candidate_pairs", s.max_candidate_pairs},
      {"bv_tests", s.bv_tests},
      {"candidate_pairs", s.candidate_pairs},
      {"ms_per_interval", s.ms_per_interval},
      {"total_ms", s.total_ms},
      {"stages_ms", stages_json(s)},
      {"worst", worst},
      {"log", id.log.empty() ? nlohmann::json(nullptr) : nlohmann::json(id.log)},
  };
}

}  // namespace skelcd::tools
