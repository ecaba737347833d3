#include "tools/io/log/log_header.hpp"

#include <array>
#include <ctime>
#include <utility>

#include "skelcd_version.hpp"

namespace skelcd::tools {

std::string iso8601_utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  std::array<char, 32> text{};
  const auto n = std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return std::string(text.data(), n);
}

LogHeader log_header_base(LogRunFacts facts) {
  LogHeader header;
  header.skelcd_version = kVersion;
  header.command_line = std::move(facts.command_line);
  header.input_path = std::move(facts.input_path);
  header.input_hash = std::move(facts.input_hash);
  header.start_time = iso8601_utc_now();
  header.first_sample = facts.first_sample;
  header.last_sample = facts.last_sample;
  header.planned_rows = facts.planned_rows;
  header.num_vertices = facts.num_vertices;
  header.num_triangles = facts.num_triangles;
  header.part_names = std::move(facts.part_names);
  return header;
}

}  // namespace skelcd::tools
