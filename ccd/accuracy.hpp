#pragma once
// The three accuracies of the elementary tests (DESIGN.md, Methods).

#include <optional>
#include <string_view>

namespace skelcd::ccd {

enum class Accuracy {
  exact,         ///< rational arithmetic on the exact input values: the judge, slow
  conservative,  ///< floating point with a proven error bound: never a false negative (default)
  fast,          ///< plain floating point, no guarantee: kept to show what accuracy costs
};

[[nodiscard]] std::string_view to_string(Accuracy accuracy);
/// "exact" | "conservative" | "fast" → Accuracy; std::nullopt for anything else.
[[nodiscard]] std::optional<Accuracy> parse_accuracy(std::string_view name);

}  // namespace skelcd::ccd
