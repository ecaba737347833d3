#pragma once
// The Panda trajectories the generators make: one that folds the arm until the hand presses into
// links 0–2, and one that moves as much without any self-collision. Written to
// assets/trajectories/ by `skelcd generate panda-trajectories` and read back by tests.

#include <filesystem>

#include "skinning/urdf.hpp"
#include "skinning/urdf_trajectory.hpp"

namespace skelcd::skinning {

/// The bundled Panda description folder (assets/robots/example-robot-data/robots/panda_description),
/// found from the environment variable SKELCD_ASSETS (an assets/ folder) when set, else from
/// this source file's location in the repository.
/// @throws IoError when it does not exist.
[[nodiscard]] std::filesystem::path panda_description_dir();

/// The bundled Panda with its SRDF's disabled pairs excluded.
[[nodiscard]] Robot load_bundled_panda();

/// `rows` rows at 30 Hz along q(τ) = q_a + smoothstep(τ) (q_b − q_a), τ = i / (rows − 1), over
/// the 7 arm joints and finger joint 1, from the ready pose to a folded pose where the hand is
/// pressed into link 0–2 (reach = true) or to a far pose that stays collision-free (reach = false).
/// @pre rows >= 2
[[nodiscard]] JointTrajectory panda_trajectory(const Robot& panda, int rows, bool reach);

/// The range of τ outside which the reach trajectory's state is decided: every sample with
/// τ < free_below is free of self-intersection, every sample with τ > intersecting_above has the
/// hand intersecting link 0, 1 or 2 (found by bisection with exact triangle tests; see
/// docs/generators.md).
struct PandaReachWindow {
  double free_below;
  double intersecting_above;
};
[[nodiscard]] PandaReachWindow panda_reach_window();

}  // namespace skelcd::skinning
