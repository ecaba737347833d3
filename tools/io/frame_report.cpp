#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

std::string_view to_string(QueryKind kind) { return kind == QueryKind::dcd ? "dcd" : "ccd"; }

std::string_view to_string(QuerySet queries) {
  switch (queries) {
    case QuerySet::dcd:
      return "dcd";
    case QuerySet::ccd:
      return "ccd";
    case QuerySet::both:
      return "both";
  }
  return "both";
}

std::optional<QuerySet> parse_query_set(std::string_view name) {
  if (name == "dcd") return QuerySet::dcd;
  if (name == "ccd") return QuerySet::ccd;
  if (name == "both") return QuerySet::both;
  return std::nullopt;
}

}  // namespace skelcd::tools
