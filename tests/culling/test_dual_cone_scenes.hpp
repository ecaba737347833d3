#pragma once
// Open-boundary scenes for the cone-method tests and benchmark (paper 000 §6.2 in kind): the
// penetrating pipe, a sheet wrapped around onto itself (a wrap skirt crossing through its own
// other end), an accordion-crumpled open tube (T-shirt-like), a skirt on a closed body, and the
// cloth-funnel frames. Procedural scenes are deterministic, already welded (no duplicate
// positions), and take their size as parameters so tests stay small and benchmarks large.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "skinning/frame_sequence.hpp"
#include "skinning/generators.hpp"
#include "skinning/mesh.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::test {

/// A mesh, its (real) topology and welded positions at a few samples: DCD at each, CCD between
/// consecutive ones.
struct OpenScene {
  std::string name;
  skinning::Mesh mesh;
  skinning::Topology topo;
  std::vector<skinning::Positions> frames;  ///< welded, #W × 3 each
};

/// A grid of quads (nu × nv cells) over positions given per grid vertex, split into triangles with
/// consistent orientation; `wrap_u` joins column nu−1 to column 0 (a tube).
inline skinning::Triangles grid_triangles(int nu, int nv, bool wrap_u) {
  const int cols = wrap_u ? nu : nu + 1;
  skinning::Triangles f(2 * nu * nv, 3);
  int t = 0;
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const int i1 = wrap_u ? (i + 1) % nu : i + 1;
      const int a = j * cols + i;
      const int b = j * cols + i1;
      const int c = (j + 1) * cols + i;
      const int d = (j + 1) * cols + i1;
      f.row(t++) << a, b, d;
      f.row(t++) << a, d, c;
    }
  }
  return f;
}

/// The paper's pipe (Fig. 1, 3): an open tube of radius r lying in the plane z ≈ 0 along a circle
/// of radius R, running once around and `overlap` radians further, rising by 0.6 r per turn so
/// that its end section is pushed through its start section (the walls cross along two lines).
/// `around` × `along` cells.
inline skinning::Positions pipe_positions(int around, int along, double overlap) {
  constexpr double kR = 3.0;
  constexpr double kr = 0.5;
  const double theta_max = 2.0 * std::numbers::pi + overlap;
  skinning::Positions x(around * (along + 1), 3);
  for (int k = 0; k <= along; ++k) {
    const double theta = theta_max * k / along;
    const Eigen::Vector3d radial(std::cos(theta), std::sin(theta), 0.0);
    const Eigen::Vector3d centre =
        kR * radial + Eigen::Vector3d(0, 0, 0.6 * kr * theta / (2.0 * std::numbers::pi));
    for (int i = 0; i < around; ++i) {
      const double phi = 2.0 * std::numbers::pi * (i + 0.5) / around;
      const Eigen::Vector3d p =
          centre + kr * (std::cos(phi) * radial + std::sin(phi) * Eigen::Vector3d::UnitZ());
      x.row(k * around + i) = p.transpose();
    }
  }
  return x;
}

inline OpenScene pipe_scene(int around, int along, std::vector<double> overlaps) {
  OpenScene s;
  s.name = "pipe";
  s.mesh = single_part_mesh(
      pipe_positions(around, along, overlaps.front()), grid_triangles(around, along, true), "pipe");
  s.topo = skinning::build_topology(s.mesh);
  for (const double o : overlaps)
    s.frames.push_back(welded(s.topo, pipe_positions(around, along, o)));
  return s;
}

/// A sheet (nu × nv cells) wrapped 1.25 times around the z axis as a gently rising spiral ramp
/// (a wrap skirt): the height z = H (v − ½)² makes the last fifth of the sheet cross through the
/// first fifth along a radial line — two layers with the same normal direction meeting at a
/// shallow angle, away from the sheet's own boundary in the middle of its width.
inline skinning::Positions wrap_sheet_positions(int nu, int nv, double height) {
  constexpr double kInner = 1.0;
  constexpr double kWidth = 1.0;
  const double alpha = 2.5 * std::numbers::pi;
  skinning::Positions x((nu + 1) * (nv + 1), 3);
  for (int j = 0; j <= nv; ++j) {
    const double v = static_cast<double>(j) / nv;
    const double angle = alpha * v;
    const double z = height * (v - 0.5) * (v - 0.5);
    for (int i = 0; i <= nu; ++i) {
      const double rho = kInner + kWidth * i / nu;
      x.row(j * (nu + 1) + i) << rho * std::cos(angle), rho * std::sin(angle), z;
    }
  }
  return x;
}

inline OpenScene wrap_sheet_scene(int nu, int nv, std::vector<double> heights) {
  OpenScene s;
  s.name = "wrap-sheet";
  s.mesh = single_part_mesh(
      wrap_sheet_positions(nu, nv, heights.front()), grid_triangles(nu, nv, false), "sheet");
  s.topo = skinning::build_topology(s.mesh);
  for (const double h : heights)
    s.frames.push_back(welded(s.topo, wrap_sheet_positions(nu, nv, h)));
  return s;
}

/// An open tube (T-shirt torso: open at both ends) crumpled like an accordion: length compressed
/// by `squash` with axial folds of amplitude `fold` and a radius that swells and shrinks out of
/// phase, so neighbouring folds press into each other.
inline skinning::Positions crumpled_tube_positions(int around, int along, double squash) {
  constexpr double kr = 0.5;
  constexpr double kLength = 4.0;
  constexpr double kFolds = 7.0;
  skinning::Positions x(around * (along + 1), 3);
  for (int k = 0; k <= along; ++k) {
    const double s = static_cast<double>(k) / along;
    const double w = 2.0 * std::numbers::pi * kFolds * s;
    const double z = kLength * ((1.0 - squash) * s) + squash * 0.09 * std::sin(w);
    for (int i = 0; i < around; ++i) {
      const double phi = 2.0 * std::numbers::pi * (i + 0.5) / around;
      const double r = kr * (1.0 + squash * 0.35 * std::cos(w + 0.3 * std::sin(3.0 * phi)));
      x.row(k * around + i) << r * std::cos(phi), r * std::sin(phi), z;
    }
  }
  return x;
}

inline OpenScene crumpled_tube_scene(int around, int along, std::vector<double> squashes) {
  OpenScene s;
  s.name = "crumpled-tube";
  s.mesh = single_part_mesh(
      crumpled_tube_positions(around, along, squashes.front()),
      grid_triangles(around, along, true),
      "shirt");
  s.topo = skinning::build_topology(s.mesh);
  for (const double q : squashes) {
    s.frames.push_back(welded(s.topo, crumpled_tube_positions(around, along, q)));
  }
  return s;
}

/// A closed body (an ellipsoid) wearing an open skirt (a cone frustum around its lower half) that
/// sways sideways by `sway` and so presses into the body: one closed part, one open part.
inline std::pair<skinning::Positions, skinning::Positions> skirt_body_positions(
    int lat, int lon, int around, int along, double sway) {
  skinning::Mesh body = uv_sphere(lat, lon, 1.0);
  skinning::Positions b = body.rest_positions;
  b.col(2) *= 1.6;
  skinning::Positions skirt(around * (along + 1), 3);
  for (int k = 0; k <= along; ++k) {
    const double s = static_cast<double>(k) / along;
    const double z = -0.2 - 1.5 * s;
    const double r = 0.95 + 0.6 * s;
    for (int i = 0; i < around; ++i) {
      const double phi = 2.0 * std::numbers::pi * (i + 0.5) / around;
      skirt.row(k * around + i) << r * std::cos(phi) + sway * s * s, r * std::sin(phi), z;
    }
  }
  return {b, skirt};
}

inline OpenScene skirt_body_scene(
    int lat, int lon, int around, int along, std::vector<double> sways) {
  OpenScene s;
  s.name = "skirt-on-body";
  auto [b, k] = skirt_body_positions(lat, lon, around, along, sways.front());
  skinning::Mesh body = uv_sphere(lat, lon, 1.0);
  body.rest_positions = b;
  body.part_names = {"body"};
  s.mesh = combine(body, single_part_mesh(k, grid_triangles(around, along, true), "skirt"));
  s.topo = skinning::build_topology(s.mesh);
  for (const double w : sways) {
    auto [bb, kk] = skirt_body_positions(lat, lon, around, along, w);
    skinning::Positions all(bb.rows() + kk.rows(), 3);
    all << bb, kk;
    s.frames.push_back(welded(s.topo, all));
  }
  return s;
}

/// The cloth-funnel step 227 → 228 (three open cloth parts and a closed funnel; 18,484
/// triangles), read in double precision by the frame-sequence reader from `dir`
/// (assets/cloth-funnel/frames).
inline OpenScene cloth_funnel_scene(const std::filesystem::path& dir) {
  OpenScene s;
  s.name = "cloth-funnel";
  const auto f227 = skinning::read_frame_mesh(dir / "227.ply");
  const auto f228 = skinning::read_frame_mesh(dir / "228.ply");
  s.mesh = single_part_mesh(f227.positions, f227.triangles, "cloth-funnel");
  s.topo = skinning::build_topology(s.mesh);
  s.frames.push_back(welded(s.topo, f227.positions));
  s.frames.push_back(welded(s.topo, f228.positions));
  return s;
}

/// A generated rig of the skinning generators (`pipe`, `cloth`: open boundaries), posed by its
/// clip at its last two samples (the known answer says both intersect).
inline OpenScene generated_scene(const std::string& name, std::int64_t triangles, int frames) {
  skinning::GeneratedRig g = skinning::generate({name, triangles, frames});
  const auto rig = std::make_shared<const skinning::Rig>(std::move(g.rig));
  const skinning::RigMotion motion(rig, {.clip = 0, .rate_hz = skinning::kGeneratorFrameRateHz});
  OpenScene s;
  s.name = "gen:" + name;
  s.mesh = rig->mesh;
  s.topo = skinning::build_topology(s.mesh);
  skinning::Positions x;
  for (int i = motion.num_samples() - 2; i < motion.num_samples(); ++i) {
    motion.positions(i, x);
    s.frames.push_back(welded(s.topo, x));
  }
  return s;
}

}  // namespace skelcd::test
