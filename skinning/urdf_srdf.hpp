#pragma once
// The part of an SRDF (MoveIt's semantic robot description) that collision checking uses: the
// link pairs whose collisions are disabled.

#include <filesystem>
#include <string>
#include <vector>

namespace skelcd::skinning {

/// One <disable_collisions link1="..." link2="..." reason="..."/> element.
struct DisabledCollisionPair {
  std::string link1;
  std::string link2;
  std::string reason;  ///< empty when the element has none
};

/// Reads every <disable_collisions> element under the SRDF's <robot> root, in file order.
/// @throws IoError naming the file when it cannot be read or is not well-formed XML (with the
///   parser's row and column).
/// @throws InvalidInput naming the file and the element's row when the root is not <robot> or an
///   element lacks link1 or link2.
[[nodiscard]] std::vector<DisabledCollisionPair> read_srdf_disabled_collisions(
    const std::filesystem::path& srdf_file);

/// The same, from SRDF text; `source` names it in messages.
[[nodiscard]] std::vector<DisabledCollisionPair> parse_srdf_disabled_collisions(
    const std::string& text,
    const std::string& source);

}  // namespace skelcd::skinning
