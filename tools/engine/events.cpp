#include "tools/engine/events.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <utility>

#include "culling/method.hpp"
#include "skinning/errors.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {
namespace {

using Pair = std::pair<std::int32_t, std::int32_t>;

/// Union-find over 0 … n-1 (path halving, union by smaller root id so roots are deterministic).
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n = 0) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  void resize(std::size_t n) {
    const auto old = parent_.size();
    parent_.resize(n);
    for (std::size_t i = old; i < n; ++i) parent_[i] = static_cast<std::int32_t>(i);
  }
  /// n singletons again, keeping the capacity.
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  std::int32_t find(std::int32_t x) {
    while (parent_[static_cast<std::size_t>(x)] != x) {
      auto& p = parent_[static_cast<std::size_t>(x)];
      p = parent_[static_cast<std::size_t>(p)];
      x = p;
    }
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    parent_[static_cast<std::size_t>(b)] = a;
  }

 private:
  std::vector<std::int32_t> parent_;
};

/// Part and driving bone (node) of a finding's feature: what allowances match against.
struct Owner {
  std::int32_t part = -1;
  std::int32_t driver = -1;  ///< skeleton node, -1 when none
};

/// Per part, the mesh triangle of each of its triangles in the file's numbering (-1: none).
std::vector<std::vector<std::int32_t>> faces_by_part(const skinning::Mesh& mesh) {
  std::vector<std::vector<std::int32_t>> table(static_cast<std::size_t>(mesh.num_parts()));
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(mesh.num_triangles()); ++f) {
    auto& list = table[static_cast<std::size_t>(mesh.face_part[static_cast<std::size_t>(f)])];
    const auto i = static_cast<std::size_t>(mesh.face_index_in_part[static_cast<std::size_t>(f)]);
    if (list.size() <= i) list.resize(i + 1, -1);
    list[i] = f;
  }
  return table;
}

}  // namespace

BaselineSpec parse_baseline(std::string_view text) {
  BaselineSpec spec;
  if (text == "rest") return spec;
  if (text == "none") {
    spec.kind = BaselineSpec::Kind::none;
    return spec;
  }
  if (text.starts_with("sample:")) {
    const auto digits = text.substr(7);
    std::int32_t k = 0;
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), k);
    if (digits.empty() || error != std::errc() || end != digits.data() + digits.size() || k < 0) {
      throw InvalidInput(
          "--baseline '" + std::string(text) + "': expected sample:K with K a sample number >= 0");
    }
    spec.kind = BaselineSpec::Kind::sample;
    spec.sample = k;
    return spec;
  }
  if (text.size() > 3 && text.ends_with(".h5")) {
    spec.kind = BaselineSpec::Kind::log;
    spec.log_path = std::string(text);
    return spec;
  }
  throw InvalidInput(
      "--baseline '" + std::string(text) + "': expected rest, sample:K, none or a log file (.h5)");
}

std::string describe(const BaselineSpec& baseline) {
  switch (baseline.kind) {
    case BaselineSpec::Kind::rest:
      return "rest pose";
    case BaselineSpec::Kind::sample:
      return "sample " + std::to_string(baseline.sample);
    case BaselineSpec::Kind::none:
      return "none";
    case BaselineSpec::Kind::log:
      break;
  }
  std::string text = "log ";
  text += baseline.log_path;
  return text;
}

double intersection_length(
    const Eigen::Vector3d& p0,
    const Eigen::Vector3d& p1,
    const Eigen::Vector3d& p2,
    const Eigen::Vector3d& q0,
    const Eigen::Vector3d& q1,
    const Eigen::Vector3d& q2) {
  const Eigen::Vector3d np = (p1 - p0).cross(p2 - p0);
  const Eigen::Vector3d nq = (q1 - q0).cross(q2 - q0);
  Eigen::Vector3d dir = np.cross(nq);
  const double scale = np.norm() * nq.norm();
  if (!(scale > 0) || dir.norm() <= 1e-12 * scale) return 0.0;  // degenerate or coplanar
  dir.normalize();
  // The interval, along `dir`, of the segment where triangle (a0, a1, a2) crosses the plane
  // through o with normal n; empty when the triangle is on one side.
  const auto interval = [&](const Eigen::Vector3d& a0,
                            const Eigen::Vector3d& a1,
                            const Eigen::Vector3d& a2,
                            const Eigen::Vector3d& o,
                            const Eigen::Vector3d& n) -> std::optional<std::pair<double, double>> {
    const std::array<const Eigen::Vector3d*, 3> a{&a0, &a1, &a2};
    std::array<double, 3> d{};
    for (int i = 0; i < 3; ++i)
      d[static_cast<std::size_t>(i)] = n.dot(*a[static_cast<std::size_t>(i)] - o);
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    const auto add = [&](const Eigen::Vector3d& x) {
      const double s = dir.dot(x);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    };
    for (int i = 0; i < 3; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      const auto uj = static_cast<std::size_t>((i + 1) % 3);
      if (d[ui] == 0) add(*a[ui]);
      if ((d[ui] < 0 && d[uj] > 0) || (d[ui] > 0 && d[uj] < 0)) {
        const double s = d[ui] / (d[ui] - d[uj]);
        add(*a[ui] + s * (*a[uj] - *a[ui]));
      }
    }
    if (lo > hi) return std::nullopt;
    return std::make_pair(lo, hi);
  };
  const auto a = interval(p0, p1, p2, q0, nq);
  const auto b = interval(q0, q1, q2, p0, np);
  if (!a || !b) return 0.0;
  return std::max(0.0, std::min(a->second, b->second) - std::max(a->first, b->first));
}

/// Samples an event may go unseen and still continue when a region touches its last triangles.
constexpr std::int32_t kEventGap = 2;
/// … or within this many seconds, whichever is longer: at 120 Hz two samples are 17 ms, and a
/// contact that flickers for a tenth of a second is still the same contact.
constexpr double kEventGapSeconds = 0.1;

struct EventTracker::Impl {
  const skinning::Mesh& mesh;
  const skinning::Topology& topology;
  const skinning::Rig* rig;
  PositionsAt positions_at;

  // File numbering → mesh ids.
  std::vector<std::vector<std::int32_t>> face_of_part;
  std::vector<std::vector<std::int32_t>> vertex_of_part;
  // Welded vertex → incident triangles (CSR).
  std::vector<std::int32_t> vt_offsets;
  std::vector<std::int32_t> vt_faces;
  // Drivers (skeleton nodes) of triangles and file vertices, and each driver's parent driver.
  std::vector<std::int32_t> face_driver;
  std::vector<std::int32_t> vertex_driver;
  std::vector<std::int32_t> driver_bone;    ///< per skeleton node: its bone (node), or itself
  std::vector<std::int32_t> driver_parent;  ///< per skeleton node: its bone's parent bone
  std::vector<std::string> node_names;
  std::string no_name;
  // Allowances: per rule, the parts and drivers each side names.
  struct Side {
    std::vector<std::int32_t> parts;
    std::vector<std::int32_t> drivers;
    [[nodiscard]] bool matches(const Owner& o) const {
      return std::find(parts.begin(), parts.end(), o.part) != parts.end() ||
             (o.driver >= 0 &&
              std::find(drivers.begin(), drivers.end(), o.driver) != drivers.end());
    }
  };
  std::vector<std::pair<Side, Side>> rules;
  bool adjacent_bones = false;
  // Baseline zone of each triangle (-1: none).
  std::vector<std::int32_t> zone;

  // Tracking.
  std::optional<FrameReport> held_ccd;
  std::vector<EventRecord> events;
  std::vector<std::map<std::int32_t, std::int64_t>> event_driver_counts;
  /// Per event still linkable: the triangles (and their neighbours) of its last step, and that
  /// step's sample. A region links to an event seen within kEventGap samples before it.
  struct Footprint {
    std::int32_t sample = 0;
    double time = 0;
    std::vector<std::int32_t> faces;
  };
  std::map<std::int32_t, Footprint> recent;
  skinning::Positions posed;

  Impl(const skinning::Mesh& m, const skinning::Topology& t, const skinning::Rig* r, PositionsAt p)
      : mesh(m), topology(t), rig(r), positions_at(std::move(p)) {}

  [[nodiscard]] std::int32_t face(const FeatureId& id) const {
    return face_of_part[static_cast<std::size_t>(id.part)][static_cast<std::size_t>(id.index)];
  }
  [[nodiscard]] std::int32_t vertex(const FeatureId& id) const {
    return vertex_of_part[static_cast<std::size_t>(id.part)][static_cast<std::size_t>(id.index)];
  }
  [[nodiscard]] Owner face_owner(std::int32_t f) const {
    return {mesh.face_part[static_cast<std::size_t>(f)], face_driver[static_cast<std::size_t>(f)]};
  }
  [[nodiscard]] Owner vertex_owner(std::int32_t v) const {
    return {
        mesh.vertex_part[static_cast<std::size_t>(v)], vertex_driver[static_cast<std::size_t>(v)]};
  }

  void build_numbering() {
    face_of_part = faces_by_part(mesh);
    vertex_of_part.assign(static_cast<std::size_t>(mesh.num_parts()), {});
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.num_vertices()); ++v) {
      auto& list =
          vertex_of_part[static_cast<std::size_t>(mesh.vertex_part[static_cast<std::size_t>(v)])];
      const auto i =
          static_cast<std::size_t>(mesh.vertex_index_in_part[static_cast<std::size_t>(v)]);
      if (list.size() <= i) list.resize(i + 1, -1);
      list[i] = v;
    }
    const auto w = static_cast<std::size_t>(topology.num_welded_vertices());
    vt_offsets.assign(w + 1, 0);
    const auto& tri = topology.welded_triangles;
    for (Eigen::Index f = 0; f < tri.rows(); ++f) {
      for (int k = 0; k < 3; ++k) ++vt_offsets[static_cast<std::size_t>(tri(f, k)) + 1];
    }
    for (std::size_t i = 0; i < w; ++i) vt_offsets[i + 1] += vt_offsets[i];
    vt_faces.resize(static_cast<std::size_t>(vt_offsets[w]));
    auto fill = vt_offsets;
    for (Eigen::Index f = 0; f < tri.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        vt_faces[static_cast<std::size_t>(fill[static_cast<std::size_t>(tri(f, k))]++)] =
            static_cast<std::int32_t>(f);
      }
    }
  }

  void build_drivers() {
    face_driver.assign(static_cast<std::size_t>(mesh.num_triangles()), -1);
    vertex_driver.assign(static_cast<std::size_t>(mesh.num_vertices()), -1);
    if (rig == nullptr || rig->mesh.num_vertices() != mesh.num_vertices()) return;
    const auto& nodes = rig->skeleton.nodes;
    const auto& bones = rig->skeleton.bones;
    node_names.resize(nodes.size());
    for (std::size_t n = 0; n < nodes.size(); ++n) node_names[n] = nodes[n].name;
    std::vector<bool> is_driver(nodes.size(), false);
    const auto attachment = [&](std::int32_t v) {
      const auto part = static_cast<std::size_t>(mesh.vertex_part[static_cast<std::size_t>(v)]);
      return part < rig->part_attachments.size() ? rig->part_attachments[part].node : -1;
    };
    const bool weighted = rig->weights.rows() == mesh.num_vertices();
    // Per triangle: the driver with the largest summed weight over its corners.
    std::vector<double> vertex_best(static_cast<std::size_t>(mesh.num_vertices()), 0.0);
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.num_vertices()); ++v) {
      std::int32_t best = -1;
      double best_w = 0;
      if (weighted) {
        for (skinning::SkinWeights::InnerIterator it(rig->weights, v); it; ++it) {
          if (it.value() > best_w) {
            best_w = it.value();
            best = bones[static_cast<std::size_t>(it.col())].node;
          }
        }
      }
      if (best < 0) {
        best = attachment(v);
        best_w = 1;
      }
      vertex_driver[static_cast<std::size_t>(v)] = best;
      vertex_best[static_cast<std::size_t>(v)] = best_w;
      if (best >= 0) is_driver[static_cast<std::size_t>(best)] = true;
    }
    for (std::int32_t f = 0; f < static_cast<std::int32_t>(mesh.num_triangles()); ++f) {
      std::array<std::pair<std::int32_t, double>, 16> sums{};
      std::size_t used = 0;
      const auto add = [&](std::int32_t node, double w) {
        if (node < 0) return;
        for (std::size_t i = 0; i < used; ++i) {
          if (sums[i].first == node) {
            sums[i].second += w;
            return;
          }
        }
        if (used < sums.size()) sums[used++] = {node, w};
      };
      for (int k = 0; k < 3; ++k) {
        const std::int32_t v = mesh.triangles(f, k);
        bool any = false;
        if (weighted) {
          for (skinning::SkinWeights::InnerIterator it(rig->weights, v); it; ++it) {
            add(bones[static_cast<std::size_t>(it.col())].node, it.value());
            any = true;
          }
        }
        if (!any) add(attachment(v), 1.0);
      }
      std::int32_t best = -1;
      double best_w = 0;
      for (std::size_t i = 0; i < used; ++i) {
        if (sums[i].second > best_w || (sums[i].second == best_w && sums[i].first < best)) {
          best_w = sums[i].second;
          best = sums[i].first;
        }
      }
      face_driver[static_cast<std::size_t>(f)] = best;
    }
    // For adjacency, a node that is no bone (a rigid part's attachment node) counts as the bone
    // it hangs from: RobotExpressive's arm mesh hangs beside the lower arm bone, under the upper
    // arm's. Each node's bone, and that bone's parent bone.
    std::vector<bool> is_bone(nodes.size(), false);
    for (const auto& b : bones) {
      if (b.node >= 0) is_bone[static_cast<std::size_t>(b.node)] = true;
    }
    const auto bone_at_or_above = [&](std::int32_t n) {
      while (n >= 0 && !is_bone[static_cast<std::size_t>(n)])
        n = nodes[static_cast<std::size_t>(n)].parent;
      return n;
    };
    driver_bone.assign(nodes.size(), -1);
    driver_parent.assign(nodes.size(), -1);
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      const auto b = bone_at_or_above(static_cast<std::int32_t>(n));
      driver_bone[n] = b >= 0 ? b : static_cast<std::int32_t>(n);
      driver_parent[n] = b >= 0 ? bone_at_or_above(nodes[static_cast<std::size_t>(b)].parent) : -1;
    }
    (void)is_driver;
  }

  void build_allowances(const Allowances& allowances) {
    adjacent_bones = allowances.adjacent_bones;
    const auto side = [&](const std::string& name, const std::string& rule) {
      Side s;
      for (std::int32_t p = 0; p < mesh.num_parts(); ++p) {
        if (mesh.part_names[static_cast<std::size_t>(p)] == name) s.parts.push_back(p);
      }
      for (std::size_t n = 0; n < node_names.size(); ++n) {
        if (node_names[n] == name) s.drivers.push_back(static_cast<std::int32_t>(n));
      }
      if (s.parts.empty() && s.drivers.empty()) {
        std::string parts;
        for (std::size_t p = 0; p < mesh.part_names.size() && p < 8; ++p) {
          parts += (p == 0 ? "" : ", ") + mesh.part_names[p];
        }
        if (mesh.part_names.size() > 8) parts += ", …";
        throw InvalidInput(
            "--allow '" + rule + "': '" + name +
            "' names neither a part nor a bone of the model (parts: " + parts +
            "; `skelcd info` lists bones)");
      }
      return s;
    };
    for (const auto& rule : allowances.rules) {
      const auto colon = rule.find(':');
      if (colon == std::string::npos || colon == 0 || colon + 1 == rule.size() ||
          rule.find(':', colon + 1) != std::string::npos) {
        throw InvalidInput("--allow '" + rule + "': expected PART_A:PART_B (part or bone names)");
      }
      rules.emplace_back(side(rule.substr(0, colon), rule), side(rule.substr(colon + 1), rule));
    }
  }

  [[nodiscard]] bool allowed(const Owner& a, const Owner& b) const {
    for (const auto& [x, y] : rules) {
      if ((x.matches(a) && y.matches(b)) || (x.matches(b) && y.matches(a))) return true;
    }
    if (adjacent_bones && a.driver >= 0 && b.driver >= 0) {
      const auto ua = static_cast<std::size_t>(a.driver);
      const auto ub = static_cast<std::size_t>(b.driver);
      if (driver_bone[ua] == driver_bone[ub]) return true;
      if (driver_parent[ua] == driver_bone[ub] || driver_parent[ub] == driver_bone[ua]) return true;
    }
    return false;
  }

  template <typename F>
  void for_each_neighbour(std::int32_t f, F&& visit) const {
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(topology.welded_triangles(f, k));
      for (auto i = vt_offsets[v]; i < vt_offsets[v + 1]; ++i)
        visit(vt_faces[static_cast<std::size_t>(i)]);
    }
  }

  void build_zones(const BaselineFindings& baseline, std::int32_t slack) {
    const auto nf = static_cast<std::size_t>(mesh.num_triangles());
    zone.assign(nf, -1);
    DisjointSets sets(nf);
    std::vector<std::int32_t> frontier;
    for (const auto& [a, b] : baseline.pairs) {
      if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= nf ||
          static_cast<std::size_t>(b) >= nf) {
        continue;
      }
      sets.unite(a, b);
      for (const auto f : {a, b}) {
        if (zone[static_cast<std::size_t>(f)] < 0) {
          zone[static_cast<std::size_t>(f)] = f;
          frontier.push_back(f);
        }
      }
    }
    // Baseline triangles that share a vertex are one region.
    for (const auto f : frontier) {
      for_each_neighbour(f, [&](std::int32_t g) {
        if (zone[static_cast<std::size_t>(g)] >= 0) sets.unite(f, g);
      });
    }
    // Dilate by `slack` rings; zones that meet merge.
    for (std::int32_t ring = 0; ring < slack; ++ring) {
      std::vector<std::int32_t> next;
      for (const auto f : frontier) {
        for_each_neighbour(f, [&](std::int32_t g) {
          auto& z = zone[static_cast<std::size_t>(g)];
          if (z < 0) {
            z = zone[static_cast<std::size_t>(f)];
            next.push_back(g);
          } else {
            sets.unite(z, zone[static_cast<std::size_t>(f)]);
          }
        });
      }
      frontier = std::move(next);
    }
    for (auto& z : zone) {
      if (z >= 0) z = sets.find(z);
    }
  }

  /// Triangles a CCD feature touches: a vertex's incident triangles, an edge's or face's triangle.
  void feature_faces(const FeatureId& id, bool is_vertex, std::vector<std::int32_t>& out) const {
    out.clear();
    if (!is_vertex) {
      out.push_back(face(id));
      return;
    }
    const auto w =
        static_cast<std::size_t>(topology.welded_of_vertex[static_cast<std::size_t>(vertex(id))]);
    for (auto i = vt_offsets[w]; i < vt_offsets[w + 1]; ++i)
      out.push_back(vt_faces[static_cast<std::size_t>(i)]);
  }

  [[nodiscard]] bool in_one_zone(
      const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) const {
    for (const auto f : a) {
      const auto z = zone[static_cast<std::size_t>(f)];
      if (z < 0) continue;
      for (const auto g : b) {
        if (zone[static_cast<std::size_t>(g)] == z) return true;
      }
    }
    return false;
  }

  /// A new finding of the current step: its triangles and where its label goes.
  struct NewFinding {
    std::int32_t a = -1;  ///< first triangle (a pair's, or a contact's feature a's first)
    std::int32_t b = -1;
    bool dcd = true;
    std::int32_t* label = nullptr;
    double toi = 1;  ///< CCD: toi_lower
    /// Every triangle it touches: step.finding_faces[first_face, end_face), `a` first.
    std::uint32_t first_face = 0;
    std::uint32_t end_face = 0;
  };

  /// What one step works with, kept between steps so that a step allocates nothing once the
  /// largest has been seen. The per-triangle and per-vertex arrays are -1 between steps (each
  /// step puts back what it set), so a step costs what its findings touch, not the mesh's size.
  struct StepScratch {
    std::vector<NewFinding> fresh;
    std::vector<std::int32_t> finding_faces;
    std::vector<std::int32_t> fa, fb;
    std::vector<std::int32_t> local_of_face;     ///< triangle → local id of this step
    std::vector<std::int32_t> local_of_vertex;   ///< welded vertex → a local id touching it
    std::vector<std::int32_t> previous_of_face;  ///< triangle → linkable event (the oldest)
    std::vector<std::int32_t> footprint_mark;    ///< triangle → the event whose footprint has it
    std::vector<std::int32_t> faces;             ///< local id → triangle
    DisjointSets sets;
    std::vector<std::pair<std::int32_t, std::int32_t>> links;  ///< (region root, event)
    std::vector<std::int32_t> region_event;                    ///< by region root; -1: none yet
    std::vector<std::uint8_t> region_has_ccd;
    std::vector<double> region_toi;
    std::vector<std::int32_t> roots;  ///< region roots in the order their events are settled
    std::vector<std::int32_t> owners;
    /// By event, 0 between steps (a step zeroes the entries of the events it touched): this
    /// step's new DCD pairs and their intersection length.
    std::vector<std::int64_t> pairs_now;
    std::vector<double> length_now;
    std::vector<std::pair<std::int32_t, std::int32_t>> by_event;  ///< (event, local id)
  };
  StepScratch step;

  void process(FrameReport* ccd, FrameReport* dcd) {
    auto& fresh = step.fresh;
    auto& ff = step.finding_faces;
    fresh.clear();
    ff.clear();
    if (dcd != nullptr) {
      auto& c = dcd->row.counters;
      c.new_dcd_pairs = c.baseline_dcd_pairs = c.allowed_dcd_pairs = 0;
      for (auto& p : dcd->dcd_pairs) {
        const auto a = face(p.a);
        const auto b = face(p.b);
        if (allowed(face_owner(a), face_owner(b))) {
          p.label = kLabelAllowed;
          ++c.allowed_dcd_pairs;
        } else if (
            zone[static_cast<std::size_t>(a)] >= 0 &&
            zone[static_cast<std::size_t>(a)] == zone[static_cast<std::size_t>(b)]) {
          p.label = kLabelBaseline;
          ++c.baseline_dcd_pairs;
        } else {
          ++c.new_dcd_pairs;
          const auto first = static_cast<std::uint32_t>(ff.size());
          ff.push_back(a);
          ff.push_back(b);
          fresh.push_back(NewFinding{
              .a = a,
              .b = b,
              .dcd = true,
              .label = &p.label,
              .first_face = first,
              .end_face = first + 2});
        }
      }
    }
    if (ccd != nullptr) {
      auto& c = ccd->row.counters;
      c.new_ccd_contacts = c.baseline_ccd_contacts = c.allowed_ccd_contacts = 0;
      auto& fa = step.fa;
      auto& fb = step.fb;
      for (auto& contact : ccd->contacts) {
        const bool vf = contact.kind == culling::CcdContact::Kind::vf;
        feature_faces(contact.a, vf, fa);
        feature_faces(contact.b, false, fb);
        const Owner oa = vf ? vertex_owner(vertex(contact.a)) : face_owner(fa.front());
        const Owner ob = face_owner(fb.front());
        if (allowed(oa, ob)) {
          contact.label = kLabelAllowed;
          ++c.allowed_ccd_contacts;
        } else if (in_one_zone(fa, fb)) {
          contact.label = kLabelBaseline;
          ++c.baseline_ccd_contacts;
        } else {
          ++c.new_ccd_contacts;
          const auto first = static_cast<std::uint32_t>(ff.size());
          ff.insert(ff.end(), fa.begin(), fa.end());
          ff.insert(ff.end(), fb.begin(), fb.end());
          fresh.push_back(NewFinding{
              .a = fa.front(),
              .b = fb.front(),
              .dcd = false,
              .label = &contact.label,
              .toi = contact.toi_lower,
              .first_face = first,
              .end_face = static_cast<std::uint32_t>(ff.size())});
        }
      }
    }
    const std::int32_t sample = dcd != nullptr ? dcd->row.sample : ccd->row.sample + 1;
    const double t_sample = dcd != nullptr ? dcd->row.t0 : ccd->row.t1;
    std::erase_if(recent, [&](const auto& entry) {
      return sample - entry.second.sample > kEventGap + 1 &&
             t_sample - entry.second.time > kEventGapSeconds;
    });
    if (fresh.empty()) return;
    const auto nf = static_cast<std::size_t>(mesh.num_triangles());
    if (step.local_of_face.size() != nf) {
      step.local_of_face.assign(nf, -1);
      step.previous_of_face.assign(nf, -1);
      step.footprint_mark.assign(nf, -1);
      step.local_of_vertex.assign(static_cast<std::size_t>(topology.num_welded_vertices()), -1);
    }
    // Triangle → the oldest event still linkable whose last step touched it or a neighbour.
    auto& previous = step.previous_of_face;
    for (const auto& [e, footprint] : recent) {
      for (const auto f : footprint.faces) {
        auto& p = previous[static_cast<std::size_t>(f)];
        p = p < 0 ? e : std::min(p, e);
      }
    }

    // Regions: the new findings' triangles, joined by the findings and by shared vertices.
    auto& local = step.local_of_face;
    auto& faces = step.faces;
    faces.clear();
    for (const auto f : ff) {
      auto& id = local[static_cast<std::size_t>(f)];
      if (id < 0) {
        id = static_cast<std::int32_t>(faces.size());
        faces.push_back(f);
      }
    }
    const auto local_of = [&](std::int32_t f) { return local[static_cast<std::size_t>(f)]; };
    auto& sets = step.sets;
    sets.reset(faces.size());
    for (const auto& n : fresh) {
      const auto first = local_of(n.a);
      for (auto k = n.first_face; k < n.end_face; ++k) sets.unite(first, local_of(ff[k]));
    }
    auto& at_vertex = step.local_of_vertex;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        auto& id = at_vertex[static_cast<std::size_t>(topology.welded_triangles(faces[i], k))];
        if (id < 0) {
          id = static_cast<std::int32_t>(i);
        } else {
          sets.unite(id, static_cast<std::int32_t>(i));
        }
      }
    }
    for (const auto f : faces) {
      for (int k = 0; k < 3; ++k) {
        at_vertex[static_cast<std::size_t>(topology.welded_triangles(f, k))] = -1;
      }
    }
    // Each region continues the events whose previous triangles it touches (oldest wins; the
    // others end, merged into it) or starts a new one.
    auto& links = step.links;
    links.clear();
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const auto p = previous[static_cast<std::size_t>(faces[i])];
      if (p >= 0) links.emplace_back(sets.find(static_cast<std::int32_t>(i)), p);
    }
    for (const auto& [e, footprint] : recent) {
      (void)e;
      for (const auto f : footprint.faces) previous[static_cast<std::size_t>(f)] = -1;
    }
    std::sort(links.begin(), links.end());
    const auto n_local = faces.size();
    step.region_event.assign(n_local, -1);
    step.region_has_ccd.assign(n_local, 0);
    step.region_toi.resize(n_local);
    for (const auto& n : fresh) {
      if (n.dcd) continue;
      const auto root = static_cast<std::size_t>(sets.find(local_of(n.a)));
      if (step.region_has_ccd[root] == 0) {
        step.region_has_ccd[root] = 1;
        step.region_toi[root] = n.toi;
      } else {
        step.region_toi[root] = std::min(step.region_toi[root], n.toi);
      }
    }
    auto& roots = step.roots;
    roots.clear();
    auto& list = step.owners;
    for (std::size_t i = 0; i < n_local; ++i) {
      const auto root = sets.find(static_cast<std::int32_t>(i));
      const auto r = static_cast<std::size_t>(root);
      if (step.region_event[r] >= 0) continue;
      list.clear();
      const auto begin = std::lower_bound(
          links.begin(),
          links.end(),
          std::make_pair(root, std::numeric_limits<std::int32_t>::min()));
      for (auto it = begin; it != links.end() && it->first == root; ++it) {
        list.push_back(resolve(it->second));  // an earlier region may have merged it
      }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      std::int32_t e = -1;
      if (list.empty()) {
        e = static_cast<std::int32_t>(events.size());
        EventRecord rec;
        rec.id = e;
        const bool between = ccd != nullptr && step.region_has_ccd[r] != 0;
        rec.first_sample = between ? ccd->row.sample : sample;
        rec.t_first = between ? ccd->row.t0 : t_sample;
        if (between) {
          rec.t_first_contact = ccd->row.t0 + step.region_toi[r] * (ccd->row.t1 - ccd->row.t0);
        }
        events.push_back(std::move(rec));
        event_driver_counts.emplace_back();
      } else {
        e = list.front();
        for (std::size_t j = 1; j < list.size(); ++j) merge(list[j], e);
      }
      step.region_event[r] = e;
      roots.push_back(root);
    }
    const auto event_of = [&](std::int32_t i) {
      return step.region_event[static_cast<std::size_t>(sets.find(i))];
    };
    // Labels, counts, parts, bones, depth.
    const auto n_events = events.size();
    step.pairs_now.resize(n_events, 0);
    step.length_now.resize(n_events, 0.0);
    const bool need_positions =
        dcd != nullptr &&
        std::any_of(fresh.begin(), fresh.end(), [](const NewFinding& n) { return n.dcd; });
    if (need_positions && positions_at) positions_at(sample, posed);
    const bool have_positions =
        need_positions && positions_at && posed.rows() == mesh.num_vertices();
    for (const auto& n : fresh) {
      const auto e = event_of(local_of(n.a));
      *n.label = e;
      const auto ue = static_cast<std::size_t>(e);
      auto& r = events[ue];
      if (n.dcd) {
        ++r.dcd_pairs;
        ++step.pairs_now[ue];
        if (have_positions) {
          const auto corner = [&](std::int32_t f, int k) -> Eigen::Vector3d {
            return posed.row(mesh.triangles(f, k)).transpose();
          };
          step.length_now[ue] += intersection_length(
              corner(n.a, 0),
              corner(n.a, 1),
              corner(n.a, 2),
              corner(n.b, 0),
              corner(n.b, 1),
              corner(n.b, 2));
        }
      } else {
        ++r.ccd_contacts;
      }
    }
    for (std::size_t i = 0; i < n_local; ++i) {
      const auto e = event_of(static_cast<std::int32_t>(i));
      auto& r = events[static_cast<std::size_t>(e)];
      const auto f = static_cast<std::size_t>(faces[i]);
      const auto part = mesh.face_part[f];
      if (std::find(r.parts.begin(), r.parts.end(), part) == r.parts.end()) {
        r.parts.insert(std::upper_bound(r.parts.begin(), r.parts.end(), part), part);
      }
      if (face_driver[f] >= 0) ++event_driver_counts[static_cast<std::size_t>(e)][face_driver[f]];
    }
    for (const auto root : roots) {
      const auto e = static_cast<std::size_t>(step.region_event[static_cast<std::size_t>(root)]);
      auto& r = events[e];
      r.last_sample = sample;
      r.t_last = t_sample;
      const auto pairs = step.pairs_now[e];
      if (pairs > r.peak_pairs) {
        r.peak_pairs = pairs;
        r.peak_sample = sample;
      }
      // Lengths are >= 0 and a depth starts at 0: an event without positions keeps its depth.
      r.depth = std::max(r.depth, step.length_now[e]);
      step.pairs_now[e] = 0;  // another root of the same event sees 0: nothing changes twice
      step.length_now[e] = 0.0;
    }
    // What later steps link to: this step's triangles and their neighbours, per event.
    auto& by_event = step.by_event;
    by_event.clear();
    for (std::size_t i = 0; i < n_local; ++i) {
      by_event.emplace_back(event_of(static_cast<std::int32_t>(i)), static_cast<std::int32_t>(i));
    }
    std::sort(by_event.begin(), by_event.end());
    auto& mark = step.footprint_mark;
    for (std::size_t j = 0; j < by_event.size();) {
      const auto e = by_event[j].first;
      std::vector<std::int32_t> footprint;
      const auto take = [&](std::int32_t g) {
        auto& m = mark[static_cast<std::size_t>(g)];
        if (m != e) {
          m = e;
          footprint.push_back(g);
        }
      };
      for (; j < by_event.size() && by_event[j].first == e; ++j) {
        const auto f = faces[static_cast<std::size_t>(by_event[j].second)];
        take(f);
        for_each_neighbour(f, take);
      }
      for (const auto g : footprint) mark[static_cast<std::size_t>(g)] = -1;
      recent[e] = Footprint{sample, t_sample, std::move(footprint)};
    }
    for (const auto f : faces) local[static_cast<std::size_t>(f)] = -1;
    std::erase_if(recent, [&](const auto& entry) {
      return events[static_cast<std::size_t>(entry.first)].merged_into >= 0;
    });
  }

  /// Folds event `from` into `into` (they ran into each other): its span, counts and bones.
  void merge(std::int32_t from, std::int32_t into) {
    auto& a = events[static_cast<std::size_t>(into)];
    auto& b = events[static_cast<std::size_t>(from)];
    b.merged_into = into;
    // The merged event starts where the earlier of the two started.
    if (b.first_sample < a.first_sample) {
      a.first_sample = b.first_sample;
      a.t_first = b.t_first;
      a.t_first_contact = b.t_first_contact;
    } else if (
        b.first_sample == a.first_sample && b.t_first_contact &&
        (!a.t_first_contact || *b.t_first_contact < *a.t_first_contact)) {
      a.t_first_contact = b.t_first_contact;
    }
    for (const auto part : b.parts) {
      if (std::find(a.parts.begin(), a.parts.end(), part) == a.parts.end()) {
        a.parts.insert(std::upper_bound(a.parts.begin(), a.parts.end(), part), part);
      }
    }
    a.dcd_pairs += b.dcd_pairs;
    a.ccd_contacts += b.ccd_contacts;
    if (b.peak_pairs > a.peak_pairs) {
      a.peak_pairs = b.peak_pairs;
      a.peak_sample = b.peak_sample;
    }
    a.depth = std::max(a.depth, b.depth);
    for (const auto& [driver, count] : event_driver_counts[static_cast<std::size_t>(from)]) {
      event_driver_counts[static_cast<std::size_t>(into)][driver] += count;
    }
  }

  [[nodiscard]] std::int32_t resolve(std::int32_t e) const {
    while (events[static_cast<std::size_t>(e)].merged_into >= 0) {
      e = events[static_cast<std::size_t>(e)].merged_into;
    }
    return e;
  }

  void finish_bones() {
    for (std::size_t e = 0; e < events.size(); ++e) {
      std::vector<std::pair<std::int64_t, std::int32_t>> ranked;
      for (const auto& [driver, count] : event_driver_counts[e])
        ranked.emplace_back(-count, driver);
      std::sort(ranked.begin(), ranked.end());
      events[e].bones.clear();
      for (const auto& [count, driver] : ranked) {
        (void)count;
        events[e].bones.push_back(node_names[static_cast<std::size_t>(driver)]);
      }
    }
  }
};

EventTracker::EventTracker(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const skinning::Rig* rig,
    const BaselineFindings& baseline,
    const Allowances& allowances,
    std::int32_t baseline_slack,
    PositionsAt positions_at,
    DcdRows dcd_rows)
    : impl_(std::make_unique<Impl>(mesh, topology, rig, std::move(positions_at))),
      dcd_rows_(dcd_rows) {
  if (baseline_slack < 0) {
    throw InvalidInput(
        "--baseline-slack " + std::to_string(baseline_slack) + ": expected a number of rings >= 0");
  }
  impl_->build_numbering();
  impl_->build_drivers();
  impl_->build_allowances(allowances);
  impl_->build_zones(baseline, baseline_slack);
}

EventTracker::~EventTracker() = default;

std::vector<FrameReport> EventTracker::push(FrameReport report) {
  std::vector<FrameReport> out;
  auto& held = impl_->held_ccd;
  if (report.row.kind == QueryKind::ccd) {
    if (held) {  // CCD only: the held interval has no DCD row
      impl_->process(&*held, nullptr);
      out.push_back(std::move(*held));
      held.reset();
    }
    if (dcd_rows_ == DcdRows::none) {
      impl_->process(&report, nullptr);
      out.push_back(std::move(report));
    } else {
      held = std::move(report);
    }
    return out;
  }
  if (held && held->row.sample + 1 == report.row.sample) {
    impl_->process(&*held, &report);
    out.push_back(std::move(*held));
    held.reset();
  } else {
    if (held) {
      impl_->process(&*held, nullptr);
      out.push_back(std::move(*held));
      held.reset();
    }
    impl_->process(nullptr, &report);
  }
  out.push_back(std::move(report));
  impl_->finish_bones();
  return out;
}

std::vector<FrameReport> EventTracker::flush() {
  std::vector<FrameReport> out;
  if (impl_->held_ccd) {
    impl_->process(&*impl_->held_ccd, nullptr);
    out.push_back(std::move(*impl_->held_ccd));
    impl_->held_ccd.reset();
  }
  impl_->finish_bones();
  return out;
}

const std::vector<EventRecord>& EventTracker::events() const { return impl_->events; }

const std::string& EventTracker::triangle_bone(std::int32_t f) const {
  const auto d = impl_->face_driver[static_cast<std::size_t>(f)];
  return d >= 0 ? impl_->node_names[static_cast<std::size_t>(d)] : impl_->no_name;
}

BaselineFindings baseline_findings(
    const BaselineSpec& spec,
    const skinning::Mesh& mesh,
    std::int32_t num_samples,
    const EventTracker::PositionsAt& positions_at,
    const std::function<std::vector<Pair>(const skinning::Positions&)>& dcd) {
  BaselineFindings out;
  switch (spec.kind) {
    case BaselineSpec::Kind::none:
      return out;
    case BaselineSpec::Kind::rest:
      out.pairs = dcd(mesh.rest_positions);
      return out;
    case BaselineSpec::Kind::sample: {
      if (spec.sample >= num_samples) {
        throw InvalidInput(
            "--baseline sample:" + std::to_string(spec.sample) +
            ": the clip has samples 0:" + std::to_string(num_samples - 1));
      }
      skinning::Positions x;
      positions_at(spec.sample, x);
      out.pairs = dcd(x);
      return out;
    }
    case BaselineSpec::Kind::log:
      break;
  }
  LogData log;
  try {
    log = read_log(spec.log_path);
  } catch (const IoError& e) {
    throw IoError(std::string(e.what()) + " (the --baseline log)");
  }
  if (log.header.num_triangles != mesh.num_triangles() ||
      log.header.part_names != mesh.part_names) {
    throw InvalidInput(
        spec.log_path + ": --baseline: a log of another model (" +
        std::to_string(log.header.num_triangles) + " triangles in " +
        std::to_string(log.header.part_names.size()) + " parts; this model has " +
        std::to_string(mesh.num_triangles()) + " in " + std::to_string(mesh.num_parts()) + ")");
  }
  const auto face_of_part = faces_by_part(mesh);
  // A vertex's first triangle, per part in the file's numbering (a VF contact's vertex side).
  std::vector<std::vector<std::int32_t>> vertex_face(static_cast<std::size_t>(mesh.num_parts()));
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(mesh.num_triangles()); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(mesh.triangles(f, k));
      auto& vl = vertex_face[static_cast<std::size_t>(mesh.vertex_part[v])];
      const auto vi = static_cast<std::size_t>(mesh.vertex_index_in_part[v]);
      if (vl.size() <= vi) vl.resize(vi + 1, -1);
      if (vl[vi] < 0) vl[vi] = f;
    }
  }
  const auto lookup = [&](const std::vector<std::vector<std::int32_t>>& table,
                          const FeatureId& id) {
    if (id.part < 0 || static_cast<std::size_t>(id.part) >= table.size()) return -1;
    const auto& list = table[static_cast<std::size_t>(id.part)];
    if (id.index < 0 || static_cast<std::size_t>(id.index) >= list.size()) return -1;
    return list[static_cast<std::size_t>(id.index)];
  };
  for (const auto& p : log.dcd_pairs) {
    out.pairs.emplace_back(lookup(face_of_part, p.a), lookup(face_of_part, p.b));
  }
  for (const auto& c : log.contacts) {
    const bool vf = c.kind == culling::CcdContact::Kind::vf;
    out.pairs.emplace_back(lookup(vf ? vertex_face : face_of_part, c.a), lookup(face_of_part, c.b));
  }
  std::erase_if(out.pairs, [](const Pair& p) { return p.first < 0 || p.second < 0; });
  std::sort(out.pairs.begin(), out.pairs.end());
  out.pairs.erase(std::unique(out.pairs.begin(), out.pairs.end()), out.pairs.end());
  return out;
}

BaselineFindings baseline_findings(
    const BaselineSpec& spec,
    const skinning::Motion& motion,
    const skinning::Topology& topology,
    std::shared_ptr<const culling::FeatureTopology> features,
    std::shared_ptr<culling::HierarchyCache> hierarchies) {
  const skinning::Mesh& mesh = motion.mesh();
  const auto positions_at = [&motion](std::int32_t sample, skinning::Positions& out) {
    motion.positions(sample, out);
  };
  const auto dcd = [&](const skinning::Positions& x) {
    culling::MethodOptions options;
    options.features = features;
    options.hierarchies = hierarchies;
    const auto method = culling::make_method("bvh", mesh, topology, options);
    skinning::Positions welded;
    skinning::gather_welded(topology, x, welded);
    culling::FrameResult found;
    method->detect_dcd(welded, found);
    std::vector<Pair> pairs;
    pairs.reserve(found.dcd_pairs.size());
    for (const auto& p : found.dcd_pairs) pairs.emplace_back(p.a, p.b);
    return pairs;
  };
  return baseline_findings(spec, mesh, motion.num_samples(), positions_at, dcd);
}

}  // namespace skelcd::tools
