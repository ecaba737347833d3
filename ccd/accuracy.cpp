#include "ccd/accuracy.hpp"

namespace skelcd::ccd {

std::string_view to_string(Accuracy accuracy) {
  switch (accuracy) {
    case Accuracy::exact:
      return "exact";
    case Accuracy::conservative:
      return "conservative";
    case Accuracy::fast:
      return "fast";
  }
  return "unknown";
}

std::optional<Accuracy> parse_accuracy(std::string_view name) {
  if (name == "exact") return Accuracy::exact;
  if (name == "conservative") return Accuracy::conservative;
  if (name == "fast") return Accuracy::fast;
  return std::nullopt;
}

}  // namespace skelcd::ccd
