// skelcd._skelcd — the extension under the Python package `skelcd` (docs/python.md): loading a
// model, posing it, checking a clip and reading a log, through the library's façade
// (skinning/load.hpp, tools/engine/check_engine.hpp, tools/report/model_report.hpp,
// tools/io/log/log_reader.hpp). Tables leave as dicts of NumPy columns named like the HDF5 log's
// (docs/log-format.md); skelcd/__init__.py assembles them into structured arrays. InvalidInput and
// IoError become the Python exceptions skelcd.InvalidInput (a ValueError) and skelcd.IoError (an
// OSError), same text.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "skelcd_version.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/topology.hpp"
#include "tools/engine/check_engine.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/io/log/log_reader.hpp"
#include "tools/report/model_report.hpp"
#include "tools/report/summary_json.hpp"

namespace py = pybind11;

namespace skelcd::python {
namespace {

/// A loaded model and the motions asked of it so far (one per clip and rate), so that posing
/// sample after sample does not rebuild the motion each time.
class Model {
 public:
  Model(std::string argument, skinning::LoadedModel model)
      : argument_(std::move(argument)), model_(std::move(model)) {
    // A frame sequence is held in a spatial order (skinning::MeshOrder); the arrays shown here are
    // in the files' order, as `skelcd export` writes them and the findings number them.
    to_file_ = skinning::file_order(*model_.mesh);
    if (!to_file_.faces.empty()) file_mesh_ = skinning::reordered(*model_.mesh, to_file_);
  }

  /// The MODEL argument as given to load() (the log's input_path).
  [[nodiscard]] const std::string& argument() const { return argument_; }
  [[nodiscard]] const skinning::LoadedModel& model() const { return model_; }
  /// The mesh in its files' order.
  [[nodiscard]] const skinning::Mesh& file_mesh() const {
    return to_file_.faces.empty() ? *model_.mesh : file_mesh_;
  }
  /// Positions of the held mesh's vertices in the files' order (moved out of `held`).
  [[nodiscard]] skinning::Positions in_file_order(skinning::Positions held) const {
    if (to_file_.vertices.empty()) return held;
    skinning::Positions out;
    skinning::gather_rows(held, to_file_.vertices, out);
    return out;
  }

  /// The motion of (clip, fps). Called with the GIL held, which also guards the cache.
  /// @throws InvalidInput for an unknown clip or a bad rate.
  [[nodiscard]] std::shared_ptr<const skinning::Motion> motion(
      const std::string& clip, double fps) {
    const auto key = std::make_pair(clip, fps);
    if (const auto found = motions_.find(key); found != motions_.end()) return found->second;
    std::shared_ptr<const skinning::Motion> made = model_.motion({.clip = clip, .rate_hz = fps});
    motions_.emplace(key, made);
    return made;
  }

 private:
  std::string argument_;
  skinning::LoadedModel model_;
  skinning::MeshPermutation to_file_;  ///< empty: the mesh is in its files' order
  skinning::Mesh file_mesh_;           ///< the mesh in its files' order, when to_file_ is not empty
  std::map<std::pair<std::string, double>, std::shared_ptr<const skinning::Motion>> motions_;
};

/// Converts a JSON value to Python through json.loads (the report is small).
py::object to_python(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
}

/// A 1-D NumPy column of `get(row)` over `rows`.
template <class T, class Row, class Get>
py::array_t<T> column(const std::vector<Row>& rows, Get get) {
  py::array_t<T> out(static_cast<py::ssize_t>(rows.size()));
  auto view = out.template mutable_unchecked<1>();
  for (std::size_t i = 0; i < rows.size(); ++i)
    view(static_cast<py::ssize_t>(i)) = static_cast<T>(get(rows[i]));
  return out;
}

/// /frames columns, as docs/log-format.md names them.
py::dict frame_columns(const std::vector<tools::FrameRow>& rows) {
  using R = tools::FrameRow;
  py::dict c;
  c["sample"] = column<std::int32_t>(rows, [](const R& r) { return r.sample; });
  c["t0"] = column<double>(rows, [](const R& r) { return r.t0; });
  c["t1"] = column<double>(rows, [](const R& r) { return r.t1; });
  c["kind"] = column<std::uint8_t>(rows, [](const R& r) { return r.kind; });
  // Every counter and stage of the one table of them (culling/frame_result.hpp).
#define SKELCD_COUNTER_COLUMN(name, meaning) \
  c[#name] = column<std::int64_t>(rows, [](const R& r) { return r.counters.name; });
  SKELCD_COUNTERS(SKELCD_COUNTER_COLUMN)
#undef SKELCD_COUNTER_COLUMN
#define SKELCD_STAGE_COLUMN(name, meaning) \
  c[#name] = column<double>(rows, [](const R& r) { return r.times.name; });
  SKELCD_STAGE_TIMES(SKELCD_STAGE_COLUMN)
#undef SKELCD_STAGE_COLUMN
  c["total_us"] = column<double>(rows, [](const R& r) { return r.total_us; });
  return c;
}

/// /contacts columns.
py::dict contact_columns(const std::vector<tools::ContactRow>& rows) {
  using R = tools::ContactRow;
  py::dict c;
  c["frame"] = column<std::int32_t>(rows, [](const R& r) { return r.frame; });
  c["kind"] = column<std::uint8_t>(rows, [](const R& r) { return r.kind; });
  c["a_part"] = column<std::int32_t>(rows, [](const R& r) { return r.a.part; });
  c["a_index"] = column<std::int32_t>(rows, [](const R& r) { return r.a.index; });
  c["a_side"] = column<std::int8_t>(rows, [](const R& r) { return r.a.side; });
  c["b_part"] = column<std::int32_t>(rows, [](const R& r) { return r.b.part; });
  c["b_index"] = column<std::int32_t>(rows, [](const R& r) { return r.b.index; });
  c["b_side"] = column<std::int8_t>(rows, [](const R& r) { return r.b.side; });
  c["toi_lower"] = column<double>(rows, [](const R& r) { return r.toi_lower; });
  c["toi_upper"] = column<double>(rows, [](const R& r) { return r.toi_upper; });
  c["label"] = column<std::int32_t>(rows, [](const R& r) { return r.label; });
  return c;
}

/// /dcd_pairs columns.
py::dict dcd_pair_columns(const std::vector<tools::DcdPairRow>& rows) {
  using R = tools::DcdPairRow;
  py::dict c;
  c["frame"] = column<std::int32_t>(rows, [](const R& r) { return r.frame; });
  c["a_part"] = column<std::int32_t>(rows, [](const R& r) { return r.a.part; });
  c["a_index"] = column<std::int32_t>(rows, [](const R& r) { return r.a.index; });
  c["b_part"] = column<std::int32_t>(rows, [](const R& r) { return r.b.part; });
  c["b_index"] = column<std::int32_t>(rows, [](const R& r) { return r.b.index; });
  c["label"] = column<std::int32_t>(rows, [](const R& r) { return r.label; });
  return c;
}

/// /events with their parts and bones: one dict per event, keys as the log's columns.
py::list event_dicts(const std::vector<tools::EventRecord>& events) {
  py::list out;
  for (const auto& e : events) {
    py::dict d;
    d["id"] = e.id;
    d["first_sample"] = e.first_sample;
    d["last_sample"] = e.last_sample;
    d["t_first"] = e.t_first;
    d["t_last"] = e.t_last;
    d["t_first_contact"] =
        e.t_first_contact ? py::object(py::float_(*e.t_first_contact)) : py::object(py::none());
    d["parts"] = e.parts;
    d["bones"] = e.bones;
    d["peak_pairs"] = e.peak_pairs;
    d["peak_sample"] = e.peak_sample;
    d["dcd_pairs"] = e.dcd_pairs;
    d["ccd_contacts"] = e.ccd_contacts;
    d["depth"] = e.depth;
    d["merged_into"] = e.merged_into;
    out.append(d);
  }
  return out;
}

/// The object `skelcd check --json` prints (tools/report/summary_json.hpp), same keys.
py::dict summary_dict(
    const tools::RunIdentity& id, const tools::RunSummary& s, const tools::RunLabels& labels) {
  return to_python(tools::summary_json(id, s, labels));
}

py::dict header_dict(const tools::LogHeader& h) {
  const auto optional = [](const auto& value) -> py::object {
    return value ? py::cast(*value) : py::object(py::none());
  };
  py::list routes;
  for (const auto& r : h.routes) {
    py::dict route;
    route["component"] = r.component;
    route["part"] = r.part;
    route["closed"] = r.closed;
    route["triangles"] = r.triangles;
    route["method"] = r.method;
    routes.append(route);
  }
  py::list checks;
  for (const auto& c : h.checks) {
    py::dict check;
    check["name"] = c.name;
    check["object_a"] = c.object_a;
    check["object_b"] = c.object_b;
    check["query"] = c.query;
    check["method"] = c.method;
    check["accuracy"] = c.accuracy;
    checks.append(check);
  }
  py::dict d;
  d["format_version"] = h.format_version;
  d["skelcd_version"] = h.skelcd_version;
  d["command_line"] = h.command_line;
  d["input_path"] = h.input_path;
  d["input_hash"] = h.input_hash;
  d["clip"] = h.clip;
  d["method"] = h.method;
  d["accuracy"] = h.accuracy;
  d["query"] = h.query;
  d["fps"] = h.fps;
  d["min_separation"] = h.min_separation;
  d["gamma"] = optional(h.gamma);
  d["theta"] = optional(h.theta);
  d["seed"] = optional(h.seed);
  d["segmentation"] = h.segmentation;
  d["start_time"] = h.start_time;
  d["first_sample"] = h.first_sample;
  d["last_sample"] = h.last_sample;
  d["planned_rows"] = h.planned_rows;
  d["num_vertices"] = h.num_vertices;
  d["num_triangles"] = h.num_triangles;
  d["parts"] = h.part_names;
  d["routes"] = routes;
  d["checks"] = checks;
  d["baseline"] = h.baseline;
  d["baseline_slack"] = h.baseline_slack;
  d["allow"] = h.allow;
  d["allow_adjacent_bones"] = h.allow_adjacent_bones;
  d["complete"] = h.complete;
  return d;
}

// --- the functions the module exports ------------------------------------------------------------

std::shared_ptr<Model> load(
    const std::string& path,
    const std::string& trajectory,
    const std::string& srdf,
    const std::vector<std::string>& package_path) {
  skinning::LoadOptions options;
  options.trajectory = trajectory;
  options.srdf = srdf;
  for (const auto& p : package_path) options.package_path.emplace_back(p);
  std::optional<skinning::LoadedModel> loaded;
  {
    py::gil_scoped_release release;  // an import can take seconds; it never calls into Python
    loaded.emplace(skinning::load_model(path, options));
  }
  return std::make_shared<Model>(path, std::move(*loaded));
}

py::dict info(const Model& model) {
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    const auto topology = skinning::build_topology(*model.model().mesh);
    report = tools::model_report(model.model(), topology);
  }
  return to_python(report);
}

py::list clips(const Model& model) {
  py::list out;
  for (const auto& c : model.model().clips) out.append(c.name);
  return out;
}

py::array_t<std::int32_t> triangles(const Model& model) {
  const auto& F = model.file_mesh().triangles;
  py::array_t<std::int32_t> out({static_cast<py::ssize_t>(F.rows()), py::ssize_t{3}});
  std::memcpy(
      out.mutable_data(), F.data(), static_cast<std::size_t>(F.size()) * sizeof(std::int32_t));
  return out;
}

py::array_t<double> to_array(const skinning::Positions& V) {
  py::array_t<double> out({static_cast<py::ssize_t>(V.rows()), py::ssize_t{3}});
  std::memcpy(out.mutable_data(), V.data(), static_cast<std::size_t>(V.size()) * sizeof(double));
  return out;
}

int num_samples(Model& model, const std::optional<std::string>& clip, double fps) {
  return model.motion(clip.value_or(""), fps)->num_samples();
}

py::array_t<double> sample_times(Model& model, const std::optional<std::string>& clip, double fps) {
  const auto motion = model.motion(clip.value_or(""), fps);
  py::array_t<double> out(motion->num_samples());
  auto view = out.mutable_unchecked<1>();
  for (int i = 0; i < motion->num_samples(); ++i) view(i) = motion->sample_time(i);
  return out;
}

/// The posed positions at `sample`, refused like `skelcd export --frame K`.
py::array_t<double> positions(
    Model& model, int sample, const std::optional<std::string>& clip, double fps) {
  const auto motion = model.motion(clip.value_or(""), fps);
  const int n = motion->num_samples();
  if (sample < 0 || sample >= n) {
    throw InvalidInput(
        model.argument() + ": frame " + std::to_string(sample) + " out of range: '" +
        motion->name() + "' has " + std::to_string(n) + " samples (0 to " + std::to_string(n - 1) +
        ")");
  }
  skinning::Positions V;
  {
    py::gil_scoped_release release;
    motion->positions(sample, V);
    V = model.in_file_order(std::move(V));
  }
  return to_array(V);
}

/// Thrown out of a row callback when Python has a pending signal (Ctrl-C): stops the check.
struct Interrupted {};

py::dict check(
    const std::shared_ptr<Model>& model,
    const std::string& clip,
    double fps,
    const std::string& frames,
    const std::string& method,
    const std::string& accuracy,
    const std::string& query,
    double min_separation,
    std::int32_t threads,
    const std::string& log,
    double gamma,
    std::uint64_t seed,
    const std::string& segmentation,
    const std::string& command_line,
    const std::string& baseline,
    std::int32_t baseline_slack,
    const std::vector<std::string>& allow,
    bool allow_adjacent_bones,
    bool full_dcd,
    bool reuse,
    bool rigid_rows) {
  // Options refused with the CLI's own messages (tools/cli/cmd_check.cpp).
  const auto parsed_accuracy = ccd::parse_accuracy(accuracy);
  if (!parsed_accuracy)
    throw InvalidInput("--accuracy '" + accuracy + "': expected exact, conservative or fast");
  const auto parsed_query = tools::parse_query_set(query);
  if (!parsed_query) throw InvalidInput("--query '" + query + "': expected ccd, dcd or both");
  if (threads < 0) {
    throw InvalidInput(
        "--threads " + std::to_string(threads) + ": expected a worker count >= 1 (0: all cores)");
  }
  tools::CheckRequest request;
  request.clip = clip;
  request.fps = fps;
  if (!frames.empty()) request.frames = tools::parse_frame_range(frames);
  request.method = method;
  request.accuracy = *parsed_accuracy;
  request.query = *parsed_query;
  request.min_separation = min_separation;
  request.threads = threads;
  request.incremental_dcd = !full_dcd;
  request.reuse_static_intervals = reuse;
  request.rigid_rows = rigid_rows;
  request.radial_view =
      tools::RadialViewArguments{.gamma = gamma, .seed = seed, .segmentation = segmentation};
  request.baseline = tools::parse_baseline(baseline);
  request.baseline_slack = baseline_slack;
  request.allow = tools::Allowances{.rules = allow, .adjacent_bones = allow_adjacent_bones};
  request.log_path = log;
  request.input_path = model->argument();
  request.command_line = command_line;

  // The check runs without the GIL: rows are collected in C++. A row finished on the calling
  // thread takes the GIL for a moment to let Ctrl-C stop the check.
  std::vector<tools::ContactRow> contacts;
  std::vector<tools::DcdPairRow> dcd_pairs;
  const auto caller = std::this_thread::get_id();
  bool interrupted = false;
  std::optional<tools::CheckOutcome> outcome;
  {
    py::gil_scoped_release release;
    try {
      outcome.emplace(
          tools::check_model(model->model(), request, [&](const tools::FrameReport& report) {
            contacts.insert(contacts.end(), report.contacts.begin(), report.contacts.end());
            dcd_pairs.insert(dcd_pairs.end(), report.dcd_pairs.begin(), report.dcd_pairs.end());
            if (std::this_thread::get_id() == caller) {
              py::gil_scoped_acquire acquire;
              if (PyErr_CheckSignals() != 0) throw Interrupted{};
            }
          }));
    } catch (const Interrupted&) {
      interrupted = true;
    }
  }
  if (interrupted) throw py::error_already_set();  // the KeyboardInterrupt PyErr_CheckSignals set

  py::dict summary = summary_dict(
      tools::check_identity(model->model(), request, *outcome),
      outcome->summary,
      tools::check_labels(model->model(), request, *outcome));
  if (!outcome->radial_view.segmentation_source.empty()) {
    summary["segmentation"] = outcome->radial_view.segmentation_source;
  }
  summary["setup_ms"] = to_python(tools::setup_json(outcome->setup));
  py::dict plan;
  plan["first_sample"] = outcome->plan.first_sample;
  plan["last_sample"] = outcome->plan.last_sample;
  plan["samples"] = outcome->plan.samples;
  plan["intervals"] = outcome->plan.intervals;
  plan["rows"] = outcome->plan.rows;
  plan["threads"] = outcome->plan.threads;
  plan["serial_reason"] = outcome->plan.serial_reason;

  py::dict result;
  result["summary"] = summary;
  result["plan"] = plan;
  result["rows"] = frame_columns(outcome->rows);
  result["contacts"] = contact_columns(contacts);
  result["dcd_pairs"] = dcd_pair_columns(dcd_pairs);
  result["events"] = event_dicts(outcome->events);
  return result;
}

py::dict read_log(const std::string& path) {
  std::optional<tools::LogData> data;
  {
    py::gil_scoped_release release;
    data.emplace(tools::read_log(path));
  }
  const auto& h = data->header;
  const tools::RunIdentity id{
      .model = h.input_path,
      .clip = h.clip,
      .fps = h.fps,
      .first_sample = h.first_sample,
      .last_sample = h.last_sample,
      .method = h.method,
      .accuracy = h.accuracy,
      .query = h.query,
      .log = path,
  };
  const tools::RunLabels labels{
      .baseline = h.baseline,
      .baseline_slack = h.baseline_slack,
      .allow = h.allow,
      .allow_adjacent_bones = h.allow_adjacent_bones,
      .events = data->events,
      .events_recorded = data->events_recorded,
      .part_names = h.part_names,
  };
  py::dict summary = summary_dict(id, tools::summarize(data->frames), labels);
  if (!h.segmentation.empty()) summary["segmentation"] = h.segmentation;

  py::dict result;
  result["summary"] = summary;
  result["header"] = header_dict(h);
  result["rows"] = frame_columns(data->frames);
  result["contacts"] = contact_columns(data->contacts);
  result["dcd_pairs"] = dcd_pair_columns(data->dcd_pairs);
  result["frame_checks"] =
      column<std::int32_t>(data->frame_checks, [](std::int32_t k) { return k; });
  result["verified"] = data->verified;
  result["damage"] = data->damage;
  // None, not [], when the log holds no events (written before events, or cut short).
  result["events"] =
      data->events_recorded ? py::object(event_dicts(data->events)) : py::object(py::none());
  return result;
}

}  // namespace
}  // namespace skelcd::python

PYBIND11_MODULE(_skelcd, m) {
  using namespace skelcd::python;
  m.doc() = "skelcd's C++ core; use the package `skelcd` (docs/python.md), not this module.";
  m.attr("__version__") = skelcd::kVersion;

  // Most recently registered translators are tried first; both derive from std::exception.
  py::register_exception<skelcd::InvalidInput>(m, "InvalidInput", PyExc_ValueError);
  py::register_exception<skelcd::IoError>(m, "IoError", PyExc_OSError);

  py::class_<Model, std::shared_ptr<Model>>(m, "Model", "A loaded model; made by skelcd.load().")
      .def_property_readonly(
          "argument", &Model::argument, "the path (or spec) it was loaded from, as given")
      .def_property_readonly("path", [](const Model& model) { return model.model().path.string(); })
      .def_property_readonly(
          "kind",
          [](const Model& model) {
            return std::string(skelcd::skinning::to_string(model.model().kind));
          })
      .def_property_readonly("clips", &clips, "names of the usable clips, in file order")
      .def_property_readonly(
          "refused_clips",
          [](const Model& model) {
            py::list out;
            for (const auto& r : model.model().refused_clips)
              out.append(py::make_tuple(r.name, r.reason));
            return out;
          },
          "(name, reason) of each clip of the file that cannot be used")
      .def_property_readonly("problems", [](const Model& model) { return model.model().problems; })
      .def_property_readonly("triangles", &triangles, "#F x 3 int32 vertex indices")
      .def_property_readonly(
          "rest_positions",
          [](const Model& model) { return to_array(model.file_mesh().rest_positions); },
          "#V x 3 float64 rest positions")
      .def_property_readonly(
          "part_names", [](const Model& model) { return model.model().mesh->part_names; })
      .def("info", &info, "the report of `skelcd info --json`, as a dict")
      .def(
          "num_samples",
          &num_samples,
          py::arg("clip") = py::none(),
          py::arg("fps") = 0.0,
          "samples of `clip` (None: the first clip, else the bind pose) at `fps` (0: its frame "
          "rate, else 30)")
      .def(
          "sample_times",
          &sample_times,
          py::arg("clip") = py::none(),
          py::arg("fps") = 0.0,
          "seconds of each sample, a float64 array")
      .def(
          "positions",
          &positions,
          py::arg("sample"),
          py::arg("clip") = py::none(),
          py::arg("fps") = 0.0,
          "#V x 3 float64 posed positions at `sample`")
      .def("__repr__", [](const Model& model) {
        return "<skelcd.Model " + model.argument() + " (" +
               skelcd::skinning::to_string(model.model().kind) + ", " +
               std::to_string(model.model().mesh->num_triangles()) + " triangles, " +
               std::to_string(model.model().clips.size()) + " clips)>";
      });

  m.def(
      "load",
      &load,
      py::arg("path"),
      py::arg("trajectory") = "",
      py::arg("srdf") = "",
      py::arg("package_path") = std::vector<std::string>{});
  m.def(
      "check",
      &check,
      py::arg("model"),
      py::arg("clip"),
      py::arg("fps"),
      py::arg("frames"),
      py::arg("method"),
      py::arg("accuracy"),
      py::arg("query"),
      py::arg("min_separation"),
      py::arg("threads"),
      py::arg("log"),
      py::arg("gamma"),
      py::arg("seed"),
      py::arg("segmentation"),
      py::arg("command_line"),
      py::arg("baseline"),
      py::arg("baseline_slack"),
      py::arg("allow"),
      py::arg("allow_adjacent_bones"),
      py::arg("full_dcd") = false,
      py::arg("reuse") = true,
      py::arg("rigid_rows") = true);
  m.def("read_log", &read_log, py::arg("path"));
  m.def("method_names", &skelcd::tools::check_method_names);
  // The /frames columns' counters and stages, in the log's order (FRAME_DTYPE is built from them).
  m.def("counter_names", [] {
    return std::vector<std::string>{
#define SKELCD_NAME(name, meaning) #name,
        SKELCD_COUNTERS(SKELCD_NAME)
#undef SKELCD_NAME
    };
  });
  m.def("stage_names", [] {
    return std::vector<std::string>{
#define SKELCD_NAME(name, meaning) #name,
        SKELCD_STAGE_TIMES(SKELCD_NAME)
#undef SKELCD_NAME
    };
  });
  m.def("log_name", &skelcd::tools::batch_log_name, py::arg("model"), py::arg("clip"));
  m.def("file_name_part", &skelcd::tools::file_name_part, py::arg("text"));
}
