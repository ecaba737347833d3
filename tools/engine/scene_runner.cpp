// Scene runs: validate and load → plan → run each check → one log (docs/scenes.md).
#include "tools/engine/scene_runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "culling/feature_topology.hpp"
#include "culling/method_registry.hpp"
#include "culling/pair_checker.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tools/engine/events.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/sample_sequencer.hpp"
#include "tools/io/file_hash.hpp"
#include "tools/io/log/log_writer.hpp"

namespace skelcd::tools {
namespace {

using Clock = std::chrono::steady_clock;

double micros(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

/// A motion seen through a selection of parts and/or a translation: positions of the kept
/// vertices of `base`, shifted by `offset`.
class SelectedMotion final : public skinning::Motion {
 public:
  SelectedMotion(
      const skinning::Motion& base,
      skinning::Mesh mesh,
      std::vector<std::int32_t> vertex_map,
      Eigen::Vector3d offset)
      : base_(base), mesh_(std::move(mesh)), map_(std::move(vertex_map)), offset_(offset) {}
  const skinning::Mesh& mesh() const override { return mesh_; }
  int num_samples() const override { return base_.num_samples(); }
  double sample_time(int i) const override { return base_.sample_time(i); }
  std::string name() const override { return base_.name(); }
  double rate_hz() const override { return base_.rate_hz(); }
  std::int32_t num_bones() const override { return base_.num_bones(); }
  void bone_transforms(int i, std::vector<skinning::BoneTransform>& out) const override {
    base_.bone_transforms(i, out);
  }
  // Thread-safe: each call poses into its own buffer (a parallel runner calls it from workers).
  void positions(int i, skinning::Positions& out) const override {
    skinning::Positions all;
    base_.positions(i, all);
    out.resize(static_cast<Eigen::Index>(map_.size()), 3);
    for (std::size_t v = 0; v < map_.size(); ++v) {
      out.row(static_cast<Eigen::Index>(v)) = all.row(map_[v]) + offset_.transpose();
    }
  }

 private:
  const skinning::Motion& base_;
  skinning::Mesh mesh_;
  std::vector<std::int32_t> map_;
  Eigen::Vector3d offset_;
};

/// The parts of `mesh` named in `parts` (all when empty), translated by `offset`; `vertex_map`
/// receives the original vertex of each kept vertex.
skinning::Mesh select_parts(
    const skinning::Mesh& mesh,
    const std::vector<std::string>& parts,
    const Eigen::Vector3d& offset,
    std::vector<std::int32_t>& vertex_map,
    const std::function<void(const std::string&)>& fail) {
  std::vector<std::int32_t> new_part(static_cast<std::size_t>(mesh.num_parts()), -1);
  skinning::Mesh out;
  if (parts.empty()) {
    for (std::int32_t p = 0; p < mesh.num_parts(); ++p) new_part[at(p)] = p;
    out.part_names = mesh.part_names;
  } else {
    for (const auto& name : parts) {
      const auto it = std::find(mesh.part_names.begin(), mesh.part_names.end(), name);
      if (it == mesh.part_names.end()) {
        std::string known;
        for (const auto& n : mesh.part_names) known += (known.empty() ? "" : ", ") + n;
        fail("unknown part '" + name + "' (parts: " + known + ")");
      }
      const auto p = static_cast<std::size_t>(it - mesh.part_names.begin());
      if (new_part[p] < 0) {
        new_part[p] = static_cast<std::int32_t>(out.part_names.size());
        out.part_names.push_back(name);
      }
    }
  }
  // Triangles of the kept parts, and the vertices they use, in file order.
  std::vector<std::int32_t> new_vertex(static_cast<std::size_t>(mesh.num_vertices()), -1);
  std::vector<std::int32_t> faces;
  for (std::int32_t f = 0; f < mesh.num_triangles(); ++f) {
    const std::int32_t part = mesh.face_part.empty() ? 0 : mesh.face_part[at(f)];
    if (new_part[at(part)] < 0) continue;
    faces.push_back(f);
    for (int k = 0; k < 3; ++k) new_vertex[at(mesh.triangles(f, k))] = 0;
  }
  vertex_map.clear();
  for (std::int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (new_vertex[at(v)] < 0) continue;
    new_vertex[at(v)] = static_cast<std::int32_t>(vertex_map.size());
    vertex_map.push_back(v);
  }
  const auto nv = static_cast<Eigen::Index>(vertex_map.size());
  out.rest_positions.resize(nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const std::int32_t old = vertex_map[static_cast<std::size_t>(v)];
    out.rest_positions.row(v) = mesh.rest_positions.row(old) + offset.transpose();
    out.vertex_part.push_back(
        mesh.vertex_part.empty() ? 0 : std::max(0, new_part[at(mesh.vertex_part[at(old)])]));
    out.vertex_index_in_part.push_back(
        mesh.vertex_index_in_part.empty() ? old : mesh.vertex_index_in_part[at(old)]);
  }
  out.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t k = 0; k < faces.size(); ++k) {
    const std::int32_t f = faces[k];
    for (int c = 0; c < 3; ++c) {
      out.triangles(static_cast<Eigen::Index>(k), c) = new_vertex[at(mesh.triangles(f, c))];
    }
    out.face_part.push_back(new_part[at(mesh.face_part.empty() ? 0 : mesh.face_part[at(f)])]);
    out.face_index_in_part.push_back(
        mesh.face_index_in_part.empty() ? f : mesh.face_index_in_part[at(f)]);
  }
  for (const auto& [p, q] : mesh.excluded_part_pairs) {
    const std::int32_t a = new_part[at(p)];
    const std::int32_t b = new_part[at(q)];
    if (a >= 0 && b >= 0) out.excluded_part_pairs.emplace_back(std::min(a, b), std::max(a, b));
  }
  return out;
}

/// A sheet skinned with `target`'s skeleton: every sheet vertex takes the weights of the nearest
/// skinned vertex of the target at rest (the usual garment binding by closest point).
skinning::Rig sheet_rig(
    const SceneSheet& sheet,
    const skinning::Rig& target,
    const std::string& name,
    const std::string& source) {
  skinning::Rig rig;
  rig.source = source;
  rig.skeleton = target.skeleton;
  rig.clips = target.clips;
  auto& m = rig.mesh;
  const int nu = sheet.cells_u;
  const int nv = sheet.cells_v;
  const int side = nu + 1;
  const Eigen::Index vertices = static_cast<Eigen::Index>(side) * (nv + 1);
  m.rest_positions.resize(vertices, 3);
  for (int j = 0; j <= nv; ++j) {
    for (int i = 0; i <= nu; ++i) {
      const Eigen::Vector3d p = sheet.corner + sheet.u * (static_cast<double>(i) / nu) +
                                sheet.v * (static_cast<double>(j) / nv);
      m.rest_positions.row(j * side + i) = p.transpose();
    }
  }
  m.triangles.resize(2 * static_cast<Eigen::Index>(nu) * nv, 3);
  Eigen::Index f = 0;
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const int v = j * side + i;
      m.triangles.row(f++) << v, v + 1, v + side + 1;
      m.triangles.row(f++) << v, v + side + 1, v + side;
    }
  }
  skinning::label_one_part_in_file_order(m, name);

  // Weight transfer from the nearest skinned target vertex.
  const auto& w = target.weights;
  std::vector<Eigen::Triplet<double>> triplets;
  for (Eigen::Index v = 0; v < vertices; ++v) {
    double best = std::numeric_limits<double>::infinity();
    Eigen::Index nearest = -1;
    for (Eigen::Index t = 0; t < target.mesh.rest_positions.rows(); ++t) {
      if (t >= w.rows() || w.outerIndexPtr()[t + 1] == w.outerIndexPtr()[t]) continue;
      const double d = (target.mesh.rest_positions.row(t) - m.rest_positions.row(v)).squaredNorm();
      if (d < best) {
        best = d;
        nearest = t;
      }
    }
    if (nearest < 0) throw InvalidInput("has no skinned vertex to attach a sheet to");
    for (skinning::SkinWeights::InnerIterator it(w, nearest); it; ++it) {
      triplets.emplace_back(static_cast<int>(v), static_cast<int>(it.col()), it.value());
    }
  }
  rig.weights.resize(vertices, w.cols());
  rig.weights.setFromTriplets(triplets.begin(), triplets.end());
  skinning::validate_rig(rig);
  return rig;
}

struct LoadedObject {
  std::optional<skinning::LoadedModel> model;
  std::unique_ptr<skinning::Motion> base;
  std::unique_ptr<skinning::Motion> selected;
  const skinning::Motion* motion = nullptr;
  skinning::Topology topology;
  std::int32_t part_offset = 0;
};

/// Loads what object `i` needs (its model, or the sheet on its target) and its motion.
void load_object(
    const Scene& scene,
    std::size_t i,
    std::vector<LoadedObject>& loaded,
    const SceneRunOptions& options) {
  const SceneObject& so = scene.objects[i];
  LoadedObject& lo = loaded[i];
  const auto fail = [&](int line, const std::string& message) {
    throw InvalidInput(scene.where(line, "object '" + so.name + "': " + message));
  };
  try {
    if (so.sheet) {
      std::size_t t = 0;
      while (scene.objects[t].name != so.attach_to) ++t;
      const LoadedObject& target = loaded[t];
      if (!target.model || !target.model->rig) {
        fail(so.attach_line, "'" + so.attach_to + "' has no skeleton to attach a sheet to");
      }
      skinning::Rig rig;
      try {
        rig =
            sheet_rig(*so.sheet, *target.model->rig, so.name, scene.path.string() + "#" + so.name);
      } catch (const std::exception& e) {
        fail(so.attach_line, "'" + so.attach_to + "' " + e.what());
      }
      lo.model = skinning::model_from_rig(std::move(rig), skinning::ModelKind::rig, {});
      const SceneObject& ts = scene.objects[t];
      lo.base = lo.model->motion(skinning::MotionRequest{.clip = ts.clip, .rate_hz = ts.rate_hz});
    } else {
      lo.model = skinning::load_model(so.model, so.load);
      lo.base = lo.model->motion(skinning::MotionRequest{.clip = so.clip, .rate_hz = so.rate_hz});
    }
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    if (what.rfind(scene.path.string() + ":", 0) == 0) throw;
    fail(so.line, what);
  } catch (const std::exception& e) {
    fail(so.line, e.what());
  }
  if (options.on_load) options.on_load(so.name);
  // Parts and offset: a view of the motion (a sheet also takes its target's offset).
  Eigen::Vector3d offset = so.offset;
  if (so.sheet) offset += scene.find(so.attach_to)->offset;
  if (!so.parts.empty() || !offset.isZero()) {
    std::vector<std::int32_t> map;
    auto mesh = select_parts(lo.base->mesh(), so.parts, offset, map, [&](const std::string& m) {
      fail(so.parts_line, m);
    });
    if (mesh.num_triangles() == 0) fail(so.parts_line, "the parts selected have no triangles");
    lo.selected =
        std::make_unique<SelectedMotion>(*lo.base, std::move(mesh), std::move(map), offset);
    lo.motion = lo.selected.get();
  } else {
    lo.motion = lo.base.get();
  }
  try {
    lo.topology = skinning::build_topology(lo.motion->mesh());
  } catch (const std::exception& e) {
    fail(so.line, e.what());
  }
}

ObjectFacts facts_of(const SceneObject& so, const LoadedObject& lo) {
  ObjectFacts f;
  if (!lo.motion) return f;
  f.source = so.sheet ? "sheet on " + so.attach_to : so.model;
  f.motion = lo.motion->name();
  f.samples = lo.motion->num_samples();
  f.rate_hz = lo.motion->rate_hz();
  f.vertices = lo.motion->mesh().num_vertices();
  f.triangles = lo.motion->mesh().num_triangles();
  f.parts = lo.motion->mesh().num_parts();
  for (const auto& c : lo.topology.components)
    (c.closed ? f.closed_components : f.open_components)++;
  f.rig_motion = lo.motion->num_bones() > 0;
  const culling::AutoGroups groups = culling::auto_groups(lo.topology, f.rig_motion);
  f.auto_whole_to_bvh = groups.whole;
  f.auto_open_group = groups.open_components;
  f.auto_closed_group = groups.closed_components;
  return f;
}

/// Refuses a pair whose objects are not sampled at the same instants.
void check_time_bases(
    const Scene& scene, const ScenePair& p, const skinning::Motion& a, const skinning::Motion& b) {
  const std::string pair = "pair " + p.a + " × " + p.b + ": ";
  if (a.num_samples() != b.num_samples()) {
    char rates[96];
    std::snprintf(
        rates,
        sizeof rates,
        " (%.6g Hz) and %d (%.6g Hz)",
        a.rate_hz(),
        b.num_samples(),
        b.rate_hz());
    throw InvalidInput(scene.where(
        p.line,
        pair + "'" + p.a + "' has " + std::to_string(a.num_samples()) + " samples" + rates +
            " for '" + p.b + "': a pair check needs the same samples (same rate and clip length)"));
  }
  for (int i = 0; i < a.num_samples(); ++i) {
    const double ta = a.sample_time(i);
    const double tb = b.sample_time(i);
    if (std::abs(ta - tb) > 1e-9 * std::max(1.0, std::abs(ta))) {
      char text[160];
      std::snprintf(
          text,
          sizeof text,
          "sample %d is at %.9g s in '%s' and %.9g s in '%s'",
          i,
          ta,
          p.a.c_str(),
          tb,
          p.b.c_str());
      throw InvalidInput(scene.where(p.line, pair + text + ": the time bases differ"));
    }
  }
}

FeatureId shifted(FeatureId id, std::int32_t offset) {
  id.part += offset;
  return id;
}

void pose(
    const skinning::Motion& motion,
    const skinning::Topology& topology,
    int sample,
    skinning::Positions& file,
    skinning::Positions& welded,
    const std::string& what) {
  motion.positions(sample, file);
  if (!file.allFinite()) {
    throw InvalidInput(what + ": sample " + std::to_string(sample) + " has a non-finite position");
  }
  skinning::gather_welded(topology, file, welded);
}

/// Runs one pair check in the row order of ClipRunner: dcd A, ccd A, dcd A+1, …, dcd B.
void run_pair(
    const CheckPlan& c,
    const ScenePlan& plan,
    const LoadedObject& a,
    const LoadedObject& b,
    double min_separation,
    const std::function<void(const FrameReport&)>& on_frame) {
  culling::PairChecker checker(
      a.motion->mesh(),
      a.topology,
      b.motion->mesh(),
      b.topology,
      {.accuracy = c.accuracy, .min_separation = min_separation});
  const FeatureNumbering na(a.motion->mesh(), a.topology);
  const FeatureNumbering nb(b.motion->mesh(), b.topology);
  const bool dcd = c.query != QuerySet::ccd;
  const bool ccd = c.query != QuerySet::dcd;
  const std::string name_a = plan.objects[at(c.object_a)].name;
  const std::string name_b = plan.objects[at(c.object_b)].name;
  skinning::Positions file;
  skinning::Positions xa[2], xb[2];  // both objects at the two samples the sequencer holds
  culling::PairFrameResult result;
  FrameReport report;

  const auto emit = [&](QueryKind kind, int sample, double skin_us, Clock::time_point start) {
    report.row = FrameRow{};
    report.row.sample = sample;
    report.row.kind = kind;
    report.row.t0 = a.motion->sample_time(sample);
    report.row.t1 = kind == QueryKind::ccd ? a.motion->sample_time(sample + 1) : report.row.t0;
    report.row.counters = result.counters;
    report.row.times = result.times;
    report.row.times.skin_us = skin_us;
    report.contacts.clear();
    report.dcd_pairs.clear();
    for (const auto& k : result.contacts) {
      ContactRow r;
      r.frame = sample;
      r.kind = k.kind;
      r.toi_lower = k.toi_lower;
      r.toi_upper = k.toi_upper;
      if (k.kind == culling::CcdContact::Kind::ee) {
        r.a = shifted(na.edge(k.a), a.part_offset);
        r.b = shifted(nb.edge(k.b), b.part_offset);
      } else if (!k.vertex_of_b) {
        r.a = shifted(na.vertex(k.a), a.part_offset);
        r.b = shifted(nb.triangle(k.b), b.part_offset);
      } else {
        r.a = shifted(nb.vertex(k.a), b.part_offset);
        r.b = shifted(na.triangle(k.b), a.part_offset);
      }
      report.contacts.push_back(r);
    }
    for (const auto& p : result.dcd_pairs) {
      report.dcd_pairs.push_back(DcdPairRow{
          .frame = sample,
          .a = shifted(na.triangle(p.a), a.part_offset),
          .b = shifted(nb.triangle(p.b), b.part_offset)});
    }
    report.row.total_us = micros(start, Clock::now()) + skin_us;
    on_frame(report);
  };

  // The row order of every check (tools/engine/sample_sequencer.hpp): dcd A, ccd A, dcd A+1, …, dcd
  // B.
  const SampleSequence sequence{
      .first = c.first_sample,
      .end = dcd ? c.last_sample + 1 : c.last_sample,
      .last = c.last_sample,
      .dcd = dcd,
      .ccd = ccd};
  run_sequence(
      sequence,
      [&](std::int32_t k, int slot) {
        const auto start = Clock::now();
        pose(*a.motion, a.topology, k, file, xa[slot], "object '" + name_a + "'");
        pose(*b.motion, b.topology, k, file, xb[slot], "object '" + name_b + "'");
        return micros(start, Clock::now());
      },
      [&](std::int32_t k, int slot, double skin_us) {
        const auto start = Clock::now();
        result.clear();
        checker.detect_dcd(xa[slot], xb[slot], result);
        emit(QueryKind::dcd, k, skin_us, start);
      },
      [&](std::int32_t k, int s0, int s1, double skin_us) {
        const auto start = Clock::now();
        result.clear();
        checker.detect_ccd(xa[s0], xa[s1], xb[s0], xb[s1], result);
        emit(QueryKind::ccd, k, skin_us, start);
      });
}

std::string distinct_joined(const std::vector<std::string>& values) {
  std::vector<std::string> seen;
  for (const auto& v : values) {
    if (std::find(seen.begin(), seen.end(), v) == seen.end()) seen.push_back(v);
  }
  std::string out;
  for (const auto& v : seen) out += (out.empty() ? "" : ",") + v;
  return out;
}

}  // namespace

bool is_scene_path(std::string_view model_arg) {
  return model_arg.size() > 5 && model_arg.substr(model_arg.size() - 5) == ".toml";
}

LoadedSceneObject load_scene_object(const Scene& scene, const std::string& name) {
  const auto found =
      std::find_if(scene.objects.begin(), scene.objects.end(), [&](const SceneObject& o) {
        return o.name == name;
      });
  if (found == scene.objects.end()) {
    throw InvalidInput(scene.path.string() + ": no object '" + name + "'");
  }
  const auto i = static_cast<std::size_t>(found - scene.objects.begin());
  auto objects = std::make_shared<std::vector<LoadedObject>>(scene.objects.size());
  const SceneRunOptions options;
  if (found->sheet) {
    for (std::size_t t = 0; t < scene.objects.size(); ++t) {
      if (scene.objects[t].name == found->attach_to) load_object(scene, t, *objects, options);
    }
  }
  load_object(scene, i, *objects, options);
  const LoadedObject& lo = (*objects)[i];
  return LoadedSceneObject{.model = &*lo.model, .motion = lo.motion, .owner = objects};
}

SceneRunResult run_scene(const Scene& scene, const SceneRunOptions& options) {
  const auto started = Clock::now();
  // 1. Load what the checks need — attach targets first — and nothing else.
  const auto load = objects_to_load(scene);
  std::vector<LoadedObject> loaded(scene.objects.size());
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const bool sheet = scene.objects[i].sheet.has_value();
      if (load[i] && sheet == (pass == 1)) load_object(scene, i, loaded, options);
    }
  }
  std::vector<ObjectFacts> facts;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    facts.push_back(facts_of(scene.objects[i], loaded[i]));
  }
  // 2. Pairs need their objects sampled at the same instants.
  for (const auto& p : scene.pairs) {
    const auto index = [&](const std::string& n) {
      std::size_t i = 0;
      while (scene.objects[i].name != n) ++i;
      return i;
    };
    check_time_bases(scene, p, *loaded[index(p.a)].motion, *loaded[index(p.b)].motion);
  }
  // 3. The plan (refuses frames that do not fit).
  SceneRunResult result;
  result.plan = plan_scene(scene, facts, options.frames ? options.frames : scene.frames);
  const ScenePlan& plan = result.plan;

  // 4. Log numbering: parts of every posed object, "object/part", in object order.
  std::int32_t parts = 0;
  std::int64_t vertices = 0, triangles = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    if (!plan.objects[i].checked) continue;
    loaded[i].part_offset = parts;
    const auto& mesh = loaded[i].motion->mesh();
    for (const auto& n : mesh.part_names)
      result.part_names.push_back(scene.objects[i].name + "/" + n);
    parts += mesh.num_parts();
    vertices += mesh.num_vertices();
    triangles += mesh.num_triangles();
  }
  if (options.on_loaded) options.on_loaded(triangles);

  // 5. Self-check runners, built now so that everything they refuse is refused before the log
  //    exists. Segmentation only where the plan says so.
  std::vector<std::unique_ptr<ClipRunner>> runners(plan.checks.size());
  std::vector<std::unique_ptr<EventTracker>> trackers(plan.checks.size());
  std::string baselines;  // "object: baseline; …" for the log header
  std::vector<RunOptions> run_options(plan.checks.size());
  std::optional<double> gamma;
  std::optional<std::int64_t> seed;
  std::string segmentation_sources;  // "object: source; …" for the log header
  for (std::size_t k = 0; k < plan.checks.size(); ++k) {
    const CheckPlan& c = plan.checks[k];
    if (c.kind != CheckKind::self) continue;
    const SceneObject& so = scene.objects[at(c.object_a)];
    LoadedObject& lo = loaded[at(c.object_a)];
    RunOptions& ro = run_options[k];
    ro.clip = so.clip;
    ro.fps = so.rate_hz;
    ro.frames = FrameRange{c.first_sample, c.last_sample};
    ro.method = c.method;
    ro.accuracy = c.accuracy;
    ro.query = c.query;
    ro.min_separation = scene.min_separation;
    ro.threads = options.threads;
    try {
      // The object's weld, copied: the runner keeps it (FeatureTopology::built_from follows this
      // copy into it), and the segmentation uses it instead of welding the mesh again.
      skinning::Topology topology = lo.topology;
      // Methods that need a segmentation get one (none for DCD only: they answer as `bvh`).
      if (plan.objects[at(c.object_a)].segmentation ||
          culling::method_needs(c.method).segmentation) {
        const auto setup =
            setup_radial_view(RadialViewArguments{}, *lo.model, *lo.motion, ro, &topology);
        if (setup.gamma) gamma = setup.gamma;
        if (setup.seed) seed = setup.seed;
        if (!setup.segmentation_source.empty()) {
          segmentation_sources += (segmentation_sources.empty() ? "" : "; ") + so.name + ": " +
                                  setup.segmentation_source;
        }
      }
      // The baseline's DCD (its own `bvh`, freed on return) before the runner builds its method,
      // so that the two do not hold memory at once (as check_model); one FeatureTopology for both.
      auto features = std::make_shared<const culling::FeatureTopology>(lo.motion->mesh(), topology);
      const auto baseline = baseline_findings(so.baseline, *lo.motion, topology, features);
      runners[k] = std::make_unique<ClipRunner>(
          *lo.motion, ro, std::move(topology), MethodFactory{}, std::move(features));
      // The labels and events of this self check (docs/events.md).
      const auto& mesh = lo.motion->mesh();
      const skinning::Rig* rig =
          lo.model && lo.model->rig && lo.model->rig->mesh.num_vertices() == mesh.num_vertices()
              ? lo.model->rig.get()
              : nullptr;
      const skinning::Motion* motion = lo.motion;
      trackers[k] = std::make_unique<EventTracker>(
          mesh,
          runners[k]->topology(),
          rig,
          baseline,
          so.allow,
          so.baseline_slack,
          [motion](std::int32_t sample, skinning::Positions& out) {
            motion->positions(sample, out);
          },
          c.query == QuerySet::ccd ? EventTracker::DcdRows::none : EventTracker::DcdRows::expected);
      baselines += (baselines.empty() ? "" : "; ") + so.name + ": " + describe(so.baseline);
    } catch (const std::exception& e) {
      throw InvalidInput(scene.where(c.line, "object '" + so.name + "': " + e.what()));
    }
  }
  if (options.on_plan) options.on_plan(plan);

  // 6. The log, once nothing more can be refused.
  std::unique_ptr<LogWriter> writer;
  if (!options.log.empty()) {
    std::int32_t first_sample = std::numeric_limits<std::int32_t>::max();
    std::int32_t last_sample = 0;
    for (const auto& c : plan.checks) {
      first_sample = std::min(first_sample, c.first_sample);
      last_sample = std::max(last_sample, c.last_sample);
    }
    if (plan.checks.empty()) first_sample = 0;
    LogHeader header = log_header_base({
        .input_path = scene.path.string(),
        .input_hash = file_content_hash(scene.path),
        .command_line = options.command_line,
        .first_sample = first_sample,
        .last_sample = last_sample,
        .planned_rows = plan.rows,
        .num_vertices = vertices,
        .num_triangles = triangles,
        .part_names = result.part_names,
    });
    std::vector<std::string> clips, methods, accuracies;
    bool dcd = false, ccd = false;
    for (const auto& c : plan.checks) {
      header.checks.push_back(LogCheck{
          .name = c.name(plan.objects),
          .object_a = plan.objects[at(c.object_a)].name,
          .object_b = c.kind == CheckKind::pair ? plan.objects[at(c.object_b)].name : "",
          .query = std::string(to_string(c.query)),
          .method = c.method,
          .accuracy = std::string(ccd::to_string(c.accuracy))});
      methods.push_back(c.method);
      accuracies.push_back(std::string(ccd::to_string(c.accuracy)));
      dcd = dcd || c.query != QuerySet::ccd;
      ccd = ccd || c.query != QuerySet::dcd;
    }
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (plan.objects[i].checked) clips.push_back(scene.objects[i].name + ": " + facts[i].motion);
    }
    std::string clip;
    for (const auto& c : clips) clip += (clip.empty() ? "" : "; ") + c;
    header.clip = clip;
    header.method = distinct_joined(methods);
    header.accuracy = distinct_joined(accuracies);
    header.query = dcd && ccd ? "both" : (dcd ? "dcd" : "ccd");
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (plan.objects[i].checked) {
        header.fps = facts[i].rate_hz;
        break;
      }
    }
    header.min_separation = scene.min_separation;
    header.gamma = gamma;
    header.seed = seed;
    header.segmentation = segmentation_sources;
    // Self checks are labelled against their objects' baselines; pair checks are not (yet).
    header.baseline =
        baselines.empty() ? std::string("none (pair checks are not labelled)") : baselines;
    // Where `auto` sent each component of each object it checks (parts numbered as in /parts,
    // so a route's part says which object it belongs to; components count within an object).
    for (std::size_t k = 0; k < plan.checks.size(); ++k) {
      const CheckPlan& c = plan.checks[k];
      if (c.kind != CheckKind::self || !runners[k]) continue;
      const auto routes = runners[k]->routes(loaded[at(c.object_a)].part_offset);
      header.routes.insert(header.routes.end(), routes.begin(), routes.end());
    }
    writer = std::make_unique<LogWriter>(options.log, header);
  }

  // 7. Run the checks in plan order.
  std::vector<EventRecord> all_events;
  for (std::size_t k = 0; k < plan.checks.size(); ++k) {
    const CheckPlan& c = plan.checks[k];
    SceneCheckResult check;
    check.name = c.name(plan.objects);
    check.rows.reserve(static_cast<std::size_t>(c.rows));
    const auto record = [&](const FrameReport& report) {
      if (writer) writer->append(report, static_cast<std::int32_t>(k));
      check.rows.push_back(report.row);
      check.contacts.insert(check.contacts.end(), report.contacts.begin(), report.contacts.end());
      check.dcd_pairs.insert(
          check.dcd_pairs.end(), report.dcd_pairs.begin(), report.dcd_pairs.end());
    };
    std::function<void(std::int64_t)> progress;
    if (options.on_check) progress = options.on_check("check " + check.name, c.rows);
    if (c.kind == CheckKind::self) {
      const std::int32_t offset = loaded[at(c.object_a)].part_offset;
      const auto first_event = static_cast<std::int32_t>(all_events.size());
      // Parts and event ids numbered as in the log (object offsets; events of earlier checks).
      const auto shifted = [&](FrameReport& report) {
        for (auto& r : report.contacts) {
          r.a.part += offset;
          r.b.part += offset;
          if (r.label >= 0) r.label += first_event;
        }
        for (auto& r : report.dcd_pairs) {
          r.a.part += offset;
          r.b.part += offset;
          if (r.label >= 0) r.label += first_event;
        }
        record(report);
        if (progress) progress(static_cast<std::int64_t>(check.rows.size()));
      };
      // The tracker takes each row whole, not a copy (runner.hpp, FrameCallback).
      runners[k]->run([&](FrameReport& report) {
        for (auto& labelled : trackers[k]->push(std::move(report))) shifted(labelled);
      });
      for (auto& labelled : trackers[k]->flush()) shifted(labelled);
      for (auto e : trackers[k]->events()) {
        e.id += first_event;
        if (e.merged_into >= 0) e.merged_into += first_event;
        for (auto& part : e.parts) part += offset;
        check.events.push_back(e);
        all_events.push_back(std::move(e));
      }
      check.baseline = describe(scene.objects[at(c.object_a)].baseline);
      runners[k].reset();  // frees the method's buffers before the next check
      trackers[k].reset();
    } else {
      run_pair(
          c,
          plan,
          loaded[at(c.object_a)],
          loaded[at(c.object_b)],
          scene.min_separation,
          [&](const FrameReport& report) {
            record(report);
            if (progress) progress(static_cast<std::int64_t>(check.rows.size()));
          });
    }
    progress = nullptr;  // the check is over: its progress line goes
    check.summary = summarize(check.rows);
    result.checks.push_back(std::move(check));
  }
  if (writer) {
    writer->write_events(all_events);
    writer->finish();
  }
  result.total_ms = micros(started, Clock::now()) / 1000.0;
  return result;
}

}  // namespace skelcd::tools
