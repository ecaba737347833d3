// Scene files: TOML → Scene, validated key by key with the line of every fault (docs/scenes.md).
#include "tools/engine/scene.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "culling/method.hpp"
#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"

namespace skelcd::tools {
namespace {

int line_of(const toml::node& node) { return static_cast<int>(node.source().begin.line); }
int line_of(const toml::key& key) { return static_cast<int>(key.source().begin.line); }

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

/// Reads one table's keys, refusing any key not in `known`.
class Reader {
 public:
  Reader(
      const Scene& scene,
      const toml::table& table,
      std::string context,
      std::vector<std::string> known)
      : scene_(scene), table_(table), context_(std::move(context)) {
    for (auto&& [key, node] : table) {
      if (std::find(known.begin(), known.end(), key.str()) == known.end()) {
        fail(
            line_of(key),
            "unknown key '" + std::string(key.str()) + "' (known: " + joined(known) + ")");
      }
    }
  }

  [[noreturn]] void fail(int line, const std::string& message) const {
    throw InvalidInput(scene_.where(line, context_ + (context_.empty() ? "" : ": ") + message));
  }

  [[nodiscard]] const toml::node* get(std::string_view key) const { return table_.get(key); }
  [[nodiscard]] int line(std::string_view key) const {
    const auto* n = get(key);
    return n ? line_of(*n) : line_of(table_);
  }

  std::optional<std::string> string(std::string_view key) const {
    const auto* n = get(key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_string()) fail(line_of(*n), "'" + std::string(key) + "' must be a string");
    return *n->value<std::string>();
  }

  std::optional<double> number(std::string_view key) const {
    const auto* n = get(key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_number()) fail(line_of(*n), "'" + std::string(key) + "' must be a number");
    const double v = *n->value<double>();
    if (!std::isfinite(v)) fail(line_of(*n), "'" + std::string(key) + "' must be finite");
    return v;
  }

  std::optional<std::vector<std::string>> strings(std::string_view key) const {
    const auto* n = get(key);
    if (n == nullptr) return std::nullopt;
    const auto* array = n->as_array();
    if (array == nullptr) {
      fail(line_of(*n), "'" + std::string(key) + "' must be an array of strings");
    }
    std::vector<std::string> out;
    for (const auto& item : *array) {
      if (!item.is_string()) {
        fail(line_of(item), "'" + std::string(key) + "' must be an array of strings");
      }
      out.push_back(*item.value<std::string>());
    }
    return out;
  }

  std::optional<Eigen::Vector3d> vector3(std::string_view key) const {
    const auto* n = get(key);
    if (n == nullptr) return std::nullopt;
    const auto* array = n->as_array();
    if (array == nullptr || array->size() != 3 ||
        !std::all_of(
            array->begin(), array->end(), [](const toml::node& x) { return x.is_number(); })) {
      fail(line_of(*n), "'" + std::string(key) + "' must be an array of 3 numbers");
    }
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) v[k] = *(*array)[static_cast<std::size_t>(k)].value<double>();
    if (!v.allFinite()) fail(line_of(*n), "'" + std::string(key) + "' must be finite");
    return v;
  }

 private:
  const Scene& scene_;
  const toml::table& table_;
  std::string context_;
};

std::filesystem::path resolve(const Scene& scene, const std::string& text) {
  const std::filesystem::path p(text);
  if (p.is_absolute()) return p;
  return (scene.path.parent_path() / p).lexically_normal();
}

bool has_glob(const std::string& text) { return text.find_first_of("*?[") != std::string::npos; }

void require_file(const Reader& r, std::string_view key, const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    r.fail(r.line(key), "'" + std::string(key) + "' " + path.string() + ": no such file");
  }
}

ccd::Accuracy parse_accuracy_at(const Reader& r, std::string_view key, const std::string& text) {
  const auto a = ccd::parse_accuracy(text);
  if (!a) {
    r.fail(r.line(key), "unknown accuracy '" + text + "' (known: exact, conservative, fast)");
  }
  return *a;
}

std::string parse_method_at(const Reader& r, std::string_view key, const std::string& text) {
  const auto names = scene_method_names();
  if (std::find(names.begin(), names.end(), text) == names.end()) {
    r.fail(r.line(key), "unknown method '" + text + "' (known: " + joined(names) + ")");
  }
  return text;
}

SceneSheet parse_sheet(const Scene& scene, const toml::node& node, const std::string& context) {
  const auto* table = node.as_table();
  if (table == nullptr) {
    throw InvalidInput(scene.where(line_of(node), context + ": 'sheet' must be a table"));
  }
  const Reader r(scene, *table, context + ": sheet", {"corner", "u", "v", "cells"});
  SceneSheet sheet;
  if (auto c = r.vector3("corner"))
    sheet.corner = *c;
  else
    r.fail(r.line("corner"), "'corner' is required");
  if (auto u = r.vector3("u"))
    sheet.u = *u;
  else
    r.fail(r.line("u"), "'u' is required");
  if (auto v = r.vector3("v"))
    sheet.v = *v;
  else
    r.fail(r.line("v"), "'v' is required");
  if (sheet.u.cross(sheet.v).norm() == 0.0) r.fail(r.line("u"), "'u' and 'v' must span a plane");
  if (const auto* cells = r.get("cells")) {
    const auto* array = cells->as_array();
    if (array == nullptr || array->size() != 2 || !(*array)[0].is_integer() ||
        !(*array)[1].is_integer()) {
      r.fail(line_of(*cells), "'cells' must be [cells along u, cells along v]");
    }
    const auto cu = *(*array)[0].value<std::int64_t>();
    const auto cv = *(*array)[1].value<std::int64_t>();
    if (cu < 1 || cv < 1 || cu > 1000 || cv > 1000) {
      r.fail(line_of(*cells), "'cells' must be in [1, 1000] each");
    }
    sheet.cells_u = static_cast<std::int32_t>(cu);
    sheet.cells_v = static_cast<std::int32_t>(cv);
  }
  return sheet;
}

/// `baseline = "…"`: rest, sample:K, none or a log (resolved against the scene's folder).
BaselineSpec parse_baseline_at(const Scene& scene, const Reader& r, const std::string& text) {
  try {
    auto spec = parse_baseline(text);
    if (spec.kind == BaselineSpec::Kind::log)
      spec.log_path = resolve(scene, spec.log_path).string();
    return spec;
  } catch (const std::exception& e) {
    r.fail(r.line("baseline"), e.what());
  }
}

SceneObject parse_object(const Scene& scene, const std::string& name, const toml::node& node) {
  const auto* table = node.as_table();
  const std::string context = "object '" + name + "'";
  if (table == nullptr) {
    throw InvalidInput(
        scene.where(line_of(node), context + ": must be a table ([objects." + name + "])"));
  }
  const Reader r(
      scene,
      *table,
      context,
      {"model",
       "sheet",
       "attach_to",
       "clip",
       "rate",
       "trajectory",
       "srdf",
       "package_path",
       "parts",
       "offset",
       "checks",
       "method",
       "accuracy",
       "baseline",
       "baseline_slack",
       "allow",
       "allow_adjacent_bones"});
  SceneObject o;
  o.name = name;
  o.line = line_of(*table);
  const auto model = r.string("model");
  const auto* sheet = r.get("sheet");
  if (model.has_value() == (sheet != nullptr)) {
    r.fail(o.line, "give exactly one of 'model' (a file, folder, glob or gen: spec) and 'sheet'");
  }
  if (model) {
    if (model->empty()) r.fail(r.line("model"), "'model' is empty");
    if (skinning::is_generator_spec(*model)) {
      try {
        o.model = skinning::to_string(skinning::parse_generator_spec(*model));
      } catch (const std::exception& e) {
        r.fail(r.line("model"), e.what());
      }
    } else {
      const auto path = resolve(scene, *model);
      o.model = path.string();
      if (has_glob(path.filename().string())) {
        std::error_code ec;
        if (!std::filesystem::is_directory(path.parent_path(), ec)) {
          r.fail(
              r.line("model"),
              "'model' " + o.model + ": no such folder " + path.parent_path().string());
        }
      } else {
        require_file(r, "model", path);
      }
    }
  } else {
    o.sheet = parse_sheet(scene, *sheet, context);
  }
  if (auto attach = r.string("attach_to")) {
    if (!o.sheet) r.fail(r.line("attach_to"), "'attach_to' is only for a 'sheet'");
    o.attach_to = *attach;
    o.attach_line = r.line("attach_to");
  } else if (o.sheet) {
    r.fail(r.line("sheet"), "a 'sheet' needs 'attach_to' (the object whose skeleton moves it)");
  }
  if (o.sheet && (r.get("clip") != nullptr || r.get("rate") != nullptr)) {
    r.fail(
        r.line(r.get("clip") != nullptr ? "clip" : "rate"),
        "a 'sheet' plays the clip and rate of the object it is attached to");
  }
  if (auto clip = r.string("clip")) o.clip = *clip;
  if (auto rate = r.number("rate")) {
    if (*rate <= 0) r.fail(r.line("rate"), "'rate' must be > 0 (samples per second)");
    o.rate_hz = *rate;
  }
  const bool urdf = !o.model.empty() && std::filesystem::path(o.model).extension() == ".urdf";
  for (const char* key : {"trajectory", "srdf", "package_path"}) {
    if (r.get(key) != nullptr && !urdf) {
      r.fail(r.line(key), "'" + std::string(key) + "' is only for a URDF model (.urdf)");
    }
  }
  if (auto t = r.string("trajectory")) {
    o.load.trajectory = resolve(scene, *t);
    require_file(r, "trajectory", o.load.trajectory);
  }
  if (auto s = r.string("srdf")) {
    o.load.srdf = resolve(scene, *s);
    require_file(r, "srdf", o.load.srdf);
  }
  if (auto folders = r.strings("package_path")) {
    for (const auto& f : *folders) {
      o.load.package_path.push_back(resolve(scene, f));
      require_file(r, "package_path", o.load.package_path.back());
    }
  }
  if (auto parts = r.strings("parts")) {
    if (parts->empty())
      r.fail(r.line("parts"), "'parts' is empty (leave it out to keep every part)");
    o.parts = *parts;
    o.parts_line = r.line("parts");
  }
  if (auto offset = r.vector3("offset")) o.offset = *offset;
  if (auto checks = r.strings("checks")) {
    o.checks_line = r.line("checks");
    for (const auto& c : *checks) {
      if (c == "self-dcd") {
        o.self_dcd = true;
      } else if (c == "self-ccd") {
        o.self_ccd = true;
      } else {
        r.fail(o.checks_line, "unknown check '" + c + "' (known: self-dcd, self-ccd)");
      }
    }
  }
  o.method = scene.method;
  if (auto m = r.string("method")) {
    o.method = parse_method_at(r, "method", *m);
    o.method_line = r.line("method");
  }
  o.accuracy = scene.accuracy;
  if (auto a = r.string("accuracy")) o.accuracy = parse_accuracy_at(r, "accuracy", *a);
  o.baseline = scene.baseline;
  if (auto b = r.string("baseline")) {
    o.baseline = parse_baseline_at(scene, r, *b);
    o.baseline_line = r.line("baseline");
  }
  if (auto slack = r.number("baseline_slack")) {
    if (*slack < 0 || *slack != std::floor(*slack) || *slack > 1000) {
      r.fail(r.line("baseline_slack"), "'baseline_slack' must be a whole number of rings >= 0");
    }
    o.baseline_slack = static_cast<std::int32_t>(*slack);
  }
  if (auto allow = r.strings("allow")) {
    o.allow.rules = *allow;
    o.allow_line = r.line("allow");
    for (const auto& rule : o.allow.rules) {
      const auto colon = rule.find(':');
      if (colon == std::string::npos || colon == 0 || colon + 1 == rule.size()) {
        r.fail(
            o.allow_line,
            "'allow' entry '" + rule + "': expected \"PART_A:PART_B\" (part or bone names)");
      }
    }
  }
  if (const auto* adjacent = r.get("allow_adjacent_bones")) {
    if (!adjacent->is_boolean()) {
      r.fail(line_of(*adjacent), "'allow_adjacent_bones' must be true or false");
    }
    o.allow.adjacent_bones = *adjacent->value<bool>();
  }
  if (culling::method_needs(o.method).bone_poses && (!o.parts.empty() || !o.offset.isZero())) {
    r.fail(
        o.method_line != 0 ? o.method_line : o.line,
        "method '" + o.method + "' needs the rig's own motion: not with 'parts' or 'offset'");
  }
  return o;
}

ScenePair parse_pair(const Scene& scene, const toml::node& node, std::size_t index) {
  const auto* table = node.as_table();
  const std::string context = "pair " + std::to_string(index + 1);
  if (table == nullptr) {
    throw InvalidInput(scene.where(line_of(node), context + ": must be a table ([[pairs]])"));
  }
  const Reader r(scene, *table, context, {"objects", "checks", "accuracy"});
  ScenePair p;
  p.line = line_of(*table);
  const auto objects = r.strings("objects");
  if (!objects || objects->size() != 2) {
    r.fail(r.line("objects"), "'objects' must name two objects: objects = [\"a\", \"b\"]");
  }
  p.a = (*objects)[0];
  p.b = (*objects)[1];
  const int objects_line = r.line("objects");
  for (const auto& name : *objects) {
    if (scene.find(name) == nullptr) {
      std::vector<std::string> known;
      for (const auto& o : scene.objects) known.push_back(o.name);
      r.fail(objects_line, "unknown object '" + name + "' (objects: " + joined(known) + ")");
    }
  }
  if (p.a == p.b) {
    r.fail(objects_line, "'" + p.a + "' against itself is a self check: use its 'checks'");
  }
  const auto checks = r.strings("checks");
  if (!checks || checks->empty()) r.fail(r.line("checks"), "'checks' must list dcd and/or ccd");
  for (const auto& c : *checks) {
    if (c == "dcd") {
      p.dcd = true;
    } else if (c == "ccd") {
      p.ccd = true;
    } else {
      r.fail(r.line("checks"), "unknown pair check '" + c + "' (known: dcd, ccd)");
    }
  }
  p.accuracy = scene.accuracy;
  if (auto a = r.string("accuracy")) p.accuracy = parse_accuracy_at(r, "accuracy", *a);
  return p;
}

}  // namespace

const SceneObject* Scene::find(std::string_view name) const {
  for (const auto& o : objects) {
    if (o.name == name) return &o;
  }
  return nullptr;
}

bool Scene::is_checked(std::string_view name) const {
  const auto* o = find(name);
  if (o != nullptr && o->has_self_check()) return true;
  return std::any_of(
      pairs.begin(), pairs.end(), [&](const ScenePair& p) { return p.a == name || p.b == name; });
}

std::string Scene::where(int line, std::string_view message) const {
  return path.string() + ":" + std::to_string(line) + ": " + std::string(message);
}

std::vector<std::string> scene_method_names() { return culling::method_names(); }

Scene parse_scene(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InvalidInput(path.string() + ": no such scene file");
  }
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) throw IoError(path.string() + ": cannot read the scene file");
  return parse_scene_text(text.str(), path);
}

Scene parse_scene_text(std::string_view text, const std::filesystem::path& path) {
  Scene scene;
  scene.path = path;
  toml::table root;
  try {
    root = toml::parse(text, path.string());
  } catch (const toml::parse_error& e) {
    throw InvalidInput(scene.where(
        static_cast<int>(e.source().begin.line), "TOML syntax: " + std::string(e.description())));
  }
  const Reader r(
      scene,
      root,
      "",
      {"output", "frames", "min_separation", "method", "accuracy", "baseline", "objects", "pairs"});
  if (auto output = r.string("output")) {
    if (output->empty()) r.fail(r.line("output"), "'output' is empty");
    scene.output = resolve(scene, *output);
  }
  if (auto frames = r.string("frames")) {
    scene.frames_line = r.line("frames");
    try {
      scene.frames = parse_frame_range(*frames);
    } catch (const std::exception& e) {
      r.fail(scene.frames_line, e.what());
    }
  }
  if (auto d = r.number("min_separation")) {
    if (*d < 0) r.fail(r.line("min_separation"), "'min_separation' must be >= 0");
    scene.min_separation = *d;
  }
  if (auto m = r.string("method")) scene.method = parse_method_at(r, "method", *m);
  if (auto a = r.string("accuracy")) scene.accuracy = parse_accuracy_at(r, "accuracy", *a);
  if (auto b = r.string("baseline")) scene.baseline = parse_baseline_at(scene, r, *b);
  if (scene.min_separation > 0 && scene.accuracy == ccd::Accuracy::exact) {
    r.fail(r.line("min_separation"), "the exact accuracy supports only min_separation = 0");
  }

  // Objects, in file order (a TOML table keeps its keys sorted, so order them by line).
  const auto* objects_node = r.get("objects");
  if (objects_node == nullptr)
    r.fail(1, "no [objects.NAME] table: a scene needs at least one object");
  const auto* objects = objects_node->as_table();
  if (objects == nullptr)
    r.fail(line_of(*objects_node), "'objects' must be a table of [objects.NAME]");
  for (auto&& [key, node] : *objects) {
    scene.objects.push_back(parse_object(scene, std::string(key.str()), node));
  }
  std::stable_sort(
      scene.objects.begin(), scene.objects.end(), [](const SceneObject& a, const SceneObject& b) {
        return a.line < b.line;
      });
  if (scene.objects.empty()) r.fail(line_of(*objects), "no objects in [objects]");
  // Pairs.
  if (const auto* pairs_node = r.get("pairs")) {
    const auto* pairs = pairs_node->as_array();
    if (pairs == nullptr)
      r.fail(line_of(*pairs_node), "'pairs' must be an array of [[pairs]] tables");
    for (std::size_t i = 0; i < pairs->size(); ++i) {
      scene.pairs.push_back(parse_pair(scene, (*pairs)[i], i));
    }
  }
  // Cross-object references, now that every object is known.
  std::set<std::pair<std::string, std::string>> seen;
  for (const auto& p : scene.pairs) {
    const auto key = std::minmax(p.a, p.b);
    if (!seen.insert({key.first, key.second}).second) {
      throw InvalidInput(scene.where(p.line, "pair " + p.a + " × " + p.b + " is listed twice"));
    }
    if (scene.min_separation > 0 && p.accuracy == ccd::Accuracy::exact) {
      throw InvalidInput(
          scene.where(p.line, "the exact accuracy supports only min_separation = 0"));
    }
  }
  for (const auto& o : scene.objects) {
    if (scene.min_separation > 0 && o.accuracy == ccd::Accuracy::exact) {
      throw InvalidInput(scene.where(
          o.line, "object '" + o.name + "': the exact accuracy supports only min_separation = 0"));
    }
    if (o.attach_to.empty()) continue;
    const auto* target = scene.find(o.attach_to);
    if (target == nullptr) {
      throw InvalidInput(scene.where(
          o.attach_line,
          "object '" + o.name + "': 'attach_to' names unknown object '" + o.attach_to + "'"));
    }
    if (target->sheet) {
      throw InvalidInput(scene.where(
          o.attach_line,
          "object '" + o.name + "': 'attach_to' must name a model object, '" + o.attach_to +
              "' is a sheet"));
    }
  }
  return scene;
}

}  // namespace skelcd::tools
