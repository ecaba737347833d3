#pragma once
// A bundled character loaded for the culling tests: its topology, its welded rest pose and its
// first clip's samples in welded numbering.

#include <string>

#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::test {

/// The welded rest pose of a bundled character (assets/characters/FILE) and its topology.
struct WeldedCharacter {
  explicit WeldedCharacter(const std::string& file)
      : loaded(skinning::load_model(asset("characters/" + file))),
        topology(skinning::build_topology(*loaded.mesh)) {
    skinning::gather_welded(topology, loaded.mesh->rest_positions, rest);
  }
  /// The welded positions of sample k of the first clip.
  [[nodiscard]] skinning::Positions sample(int k) const {
    skinning::Positions posed, welded;
    loaded.motion()->positions(k, posed);
    skinning::gather_welded(topology, posed, welded);
    return welded;
  }
  skinning::LoadedModel loaded;
  skinning::Topology topology;
  skinning::Positions rest;
};

}  // namespace skelcd::test
