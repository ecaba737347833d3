#include "tools/io/segmentation_file.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>

#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "tools/io/file_hash.hpp"

namespace skelcd::tools {

namespace {

namespace seg = skelcd::segmentation;

// ---------------------------------------------------------------------------------------------
// Small RAII and error helpers for the HDF5 C API.

class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }
  void reset() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  [[nodiscard]] hid_t get() const { return id_; }
  [[nodiscard]] bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

void silence_hdf5() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

// All I/O faults carry the file name; `what` says which object.
struct Context {
  std::string file;
  [[noreturn]] void fail(const std::string& what) const {
    H5Eclear2(H5E_DEFAULT);
    throw IoError(file + ": " + what);
  }
  void check(herr_t status, const std::string& what) const {
    if (status < 0) fail(what);
  }
  Handle check(Handle h, const std::string& what) const {
    if (!h.valid()) fail(what);
    return h;
  }
};

Handle vlen_string_type() {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

Handle observer_kind_enum() {
  Handle type(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose);
  const std::int8_t point = 0, line = 1;
  H5Tenum_insert(type.get(), "point", &point);
  H5Tenum_insert(type.get(), "line", &line);
  return type;
}

void write_scalar(
    const Context& cx,
    hid_t where,
    const char* name,
    hid_t file_type,
    hid_t mem_type,
    const void* value) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  auto attr = cx.check(
      Handle(H5Acreate2(where, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose),
      std::string("cannot create attribute ") + name);
  cx.check(H5Awrite(attr.get(), mem_type, value), std::string("cannot write attribute ") + name);
}

void attr(const Context& cx, hid_t where, const char* name, const std::string& value) {
  const auto type = vlen_string_type();
  const char* text = value.c_str();
  write_scalar(cx, where, name, type.get(), type.get(), &text);
}
void attr(const Context& cx, hid_t where, const char* name, double value) {
  write_scalar(cx, where, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}
void attr(const Context& cx, hid_t where, const char* name, std::int64_t value) {
  write_scalar(cx, where, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

bool has_attr(hid_t where, const char* name) { return H5Aexists(where, name) > 0; }

Handle open_attr(const Context& cx, hid_t where, const char* name) {
  if (!has_attr(where, name)) cx.fail(std::string("attribute '") + name + "' is missing");
  return cx.check(
      Handle(H5Aopen(where, name, H5P_DEFAULT), H5Aclose),
      std::string("cannot open attribute ") + name);
}

std::string read_string(const Context& cx, hid_t where, const char* name) {
  auto a = open_attr(cx, where, name);
  Handle stored(H5Aget_type(a.get()), H5Tclose);
  if (H5Tget_class(stored.get()) != H5T_STRING || H5Tis_variable_str(stored.get()) <= 0) {
    cx.fail(std::string("attribute '") + name + "' is not a variable-length string");
  }
  const auto type = vlen_string_type();
  char* text = nullptr;
  cx.check(H5Aread(a.get(), type.get(), &text), std::string("cannot read attribute ") + name);
  std::string value = text != nullptr ? text : "";
  H5free_memory(text);
  return value;
}

template <class T>
T read_number(const Context& cx, hid_t where, const char* name) {
  auto a = open_attr(cx, where, name);
  Handle stored(H5Aget_type(a.get()), H5Tclose);
  const auto cls = H5Tget_class(stored.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) {
    cx.fail(std::string("attribute '") + name + "' is not a number");
  }
  T value{};
  const hid_t mem = std::is_floating_point_v<T> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
  cx.check(H5Aread(a.get(), mem, &value), std::string("cannot read attribute ") + name);
  return value;
}

// A 1-D (cols == 0) or 2-D (rows × cols) dataset; a zero-length one is written too.
void dataset(
    const Context& cx,
    hid_t where,
    const char* name,
    hid_t file_type,
    hid_t mem_type,
    const void* data,
    std::size_t rows,
    std::size_t cols = 0) {
  const std::array<hsize_t, 2> dims = {rows, cols};
  Handle space(H5Screate_simple(cols == 0 ? 1 : 2, dims.data(), nullptr), H5Sclose);
  auto set = cx.check(
      Handle(
          H5Dcreate2(where, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
          H5Dclose),
      std::string("cannot create dataset ") + name);
  if (rows > 0) {
    cx.check(
        H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
        std::string("cannot write dataset ") + name);
  }
}

Handle group(const Context& cx, hid_t where, const char* name) {
  return cx.check(
      Handle(H5Gcreate2(where, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose),
      std::string("cannot create group ") + name);
}

Handle open_group(const Context& cx, hid_t where, const char* name) {
  if (H5Lexists(where, name, H5P_DEFAULT) <= 0)
    cx.fail(std::string("group '") + name + "' is missing");
  return cx.check(
      Handle(H5Gopen2(where, name, H5P_DEFAULT), H5Gclose),
      std::string("cannot open group ") + name);
}

// Reads a dataset of `cols` columns (0: 1-D) into `out`; returns the number of rows.
template <class T>
std::size_t read_dataset(
    const Context& cx,
    hid_t where,
    const char* name,
    hid_t mem_type,
    std::vector<T>& out,
    std::size_t cols = 0) {
  if (H5Lexists(where, name, H5P_DEFAULT) <= 0)
    cx.fail(std::string("dataset '") + name + "' is missing");
  auto set = cx.check(
      Handle(H5Dopen2(where, name, H5P_DEFAULT), H5Dclose),
      std::string("cannot open dataset ") + name);
  Handle space(H5Dget_space(set.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::array<hsize_t, 2> dims = {0, 0};
  if (rank != (cols == 0 ? 1 : 2) ||
      H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0 ||
      (cols != 0 && dims[1] != cols)) {
    cx.fail(std::string("dataset '") + name + "' has an unexpected shape");
  }
  const std::size_t rows = dims[0];
  out.resize(rows * (cols == 0 ? 1 : cols));
  if (rows > 0) {
    cx.check(
        H5Dread(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
        std::string("cannot read dataset ") + name);
  }
  return rows;
}

std::vector<double> flatten(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> out;
  out.reserve(points.size() * 3);
  for (const auto& p : points) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

std::string weights_name(seg::WeightSource w) {
  return w == seg::WeightSource::heat ? "heat" : "rig";
}
std::string distance_name(seg::DistanceMode d) {
  return d == seg::DistanceMode::exact ? "exact" : "coarse";
}

// ---------------------------------------------------------------------------------------------

void write_file(
    const Context& cx, hid_t file, const seg::Segmentation& s, const SegmentationRecord& r) {
  const auto& o = s.options;
  const auto& st = s.stats;
  // Root: what this is, where it came from, how it was made.
  attr(cx, file, "format", std::string(kSegmentationFormatName));
  attr(cx, file, "format_version", kSegmentationFormatVersion);
  attr(cx, file, "skelcd_version", r.skelcd_version);
  attr(cx, file, "input_path", r.input_path);
  attr(cx, file, "input_hash", r.input_hash);
  attr(cx, file, "weights", weights_name(o.weights));
  attr(cx, file, "distance", distance_name(o.heat.distance));
  attr(cx, file, "theta_deg", o.theta_deg);
  attr(cx, file, "refine", static_cast<std::int64_t>(o.refine ? 1 : 0));
  attr(cx, file, "heat_constant", o.heat.heat_constant);
  attr(cx, file, "tie_tolerance", o.heat.tie_tolerance);
  attr(cx, file, "min_distance_fraction", o.heat.min_distance_fraction);
  attr(cx, file, "grid_resolution", static_cast<std::int64_t>(o.heat.grid_resolution));
  attr(cx, file, "smoothing_iterations", static_cast<std::int64_t>(o.heat.smoothing_iterations));
  attr(cx, file, "num_triangles", st.triangles);
  attr(cx, file, "num_vertices", st.vertices);
  attr(cx, file, "num_welded_vertices", st.welded_vertices);
  attr(cx, file, "num_bones", static_cast<std::int64_t>(st.bones));

  // Per triangle.
  dataset(
      cx,
      file,
      "triangle_cluster",
      H5T_STD_I32LE,
      H5T_NATIVE_INT32,
      s.triangle_cluster.data(),
      s.triangle_cluster.size());

  // Per cluster: bone, observer, size and the observer-choice averages.
  {
    auto g = group(cx, file, "clusters");
    const auto nc = s.clusters.size();
    std::vector<std::int32_t> bone, count;
    std::vector<std::int8_t> kind;
    std::vector<Eigen::Vector3d> head, tail;
    std::vector<double> mean_point, mean_line;
    for (const auto& c : s.clusters) {
      bone.push_back(c.bone);
      count.push_back(static_cast<std::int32_t>(c.triangles.size()));
      kind.push_back(static_cast<std::int8_t>(c.observer.kind));
      head.push_back(c.observer.segment.head);
      tail.push_back(c.observer.segment.tail);
      mean_point.push_back(c.mean_positive_point);
      mean_line.push_back(c.mean_positive_line);
    }
    const auto kinds = observer_kind_enum();
    dataset(cx, g.get(), "bone", H5T_STD_I32LE, H5T_NATIVE_INT32, bone.data(), nc);
    dataset(cx, g.get(), "observer_kind", kinds.get(), kinds.get(), kind.data(), nc);
    const auto h = flatten(head), t = flatten(tail);
    dataset(cx, g.get(), "observer_head", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, h.data(), nc, 3);
    dataset(cx, g.get(), "observer_tail", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, t.data(), nc, 3);
    dataset(cx, g.get(), "triangle_count", H5T_STD_I32LE, H5T_NATIVE_INT32, count.data(), nc);
    dataset(
        cx,
        g.get(),
        "mean_positive_point",
        H5T_IEEE_F64LE,
        H5T_NATIVE_DOUBLE,
        mean_point.data(),
        nc);
    dataset(
        cx, g.get(), "mean_positive_line", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, mean_line.data(), nc);
  }

  // The cluster graph.
  {
    auto g = group(cx, file, "graph");
    const auto ne = s.graph.size();
    std::vector<std::int32_t> a, b, shared, ancestor;
    std::vector<Eigen::Vector3d> joint;
    for (const auto& e : s.graph) {
      a.push_back(e.a);
      b.push_back(e.b);
      shared.push_back(e.shared_edges);
      ancestor.push_back(e.ancestor_bone);
      joint.push_back(e.joint);
    }
    const auto j = flatten(joint);
    dataset(cx, g.get(), "a", H5T_STD_I32LE, H5T_NATIVE_INT32, a.data(), ne);
    dataset(cx, g.get(), "b", H5T_STD_I32LE, H5T_NATIVE_INT32, b.data(), ne);
    dataset(cx, g.get(), "shared_edges", H5T_STD_I32LE, H5T_NATIVE_INT32, shared.data(), ne);
    dataset(cx, g.get(), "ancestor_bone", H5T_STD_I32LE, H5T_NATIVE_INT32, ancestor.data(), ne);
    dataset(cx, g.get(), "joint", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, j.data(), ne, 3);
  }

  // The bones the clusters refer to.
  {
    auto g = group(cx, file, "bones");
    const auto nb = r.bones.size();
    std::vector<const char*> names;
    std::vector<std::int32_t> parent;
    std::vector<Eigen::Vector3d> head, tail;
    for (std::size_t k = 0; k < nb; ++k) {
      names.push_back(k < r.bone_names.size() ? r.bone_names[k].c_str() : "");
      parent.push_back(r.bones[k].parent);
      head.push_back(r.bones[k].head);
      tail.push_back(r.bones[k].tail);
    }
    const auto str = vlen_string_type();
    dataset(cx, g.get(), "name", str.get(), str.get(), names.data(), nb);
    dataset(cx, g.get(), "parent", H5T_STD_I32LE, H5T_NATIVE_INT32, parent.data(), nb);
    const auto h = flatten(head), t = flatten(tail);
    dataset(cx, g.get(), "head", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, h.data(), nb, 3);
    dataset(cx, g.get(), "tail", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, t.data(), nb, 3);
  }

  // Statistics (paper Table 1 and diagnostics).
  {
    auto g = group(cx, file, "statistics");
    const hid_t w = g.get();
    attr(cx, w, "atomic_clusters", static_cast<std::int64_t>(st.atomic_clusters));
    attr(cx, w, "split_clusters", static_cast<std::int64_t>(st.split_clusters));
    attr(cx, w, "point_observers", static_cast<std::int64_t>(st.point_observers));
    attr(cx, w, "line_observers", static_cast<std::int64_t>(st.line_observers));
    attr(cx, w, "h_minus", st.h_minus);
    attr(cx, w, "h_uncertain", st.h_uncertain);
    attr(cx, w, "non_positive_before_refinement", st.refinement.non_positive_before);
    attr(cx, w, "non_positive_after_refinement", st.refinement.non_positive_after);
    attr(cx, w, "refinement_removed", st.refinement.removed);
    attr(cx, w, "refinement_regrown_positive", st.refinement.regrown_positive);
    attr(cx, w, "refinement_regrown_unconstrained", st.refinement.regrown_unconstrained);
    attr(cx, w, "refinement_restored", st.refinement.restored);
    attr(cx, w, "fallback_vertices", st.heat.fallback_vertices);
    attr(cx, w, "isolated_vertices", st.heat.isolated_vertices);
    attr(cx, w, "degenerate_triangles", st.heat.degenerate_triangles);
    attr(cx, w, "clamped_weights", st.heat.clamped_weights);
    attr(cx, w, "unweighted_vertices", st.unweighted_vertices);
    attr(cx, w, "weights_s", st.weights_s);
    attr(cx, w, "decomposition_ms", st.decomposition_ms);
    dataset(
        cx,
        w,
        "bones_without_cluster",
        H5T_STD_I32LE,
        H5T_NATIVE_INT32,
        st.bones_without_cluster.data(),
        st.bones_without_cluster.size());
    if (r.clip) {
      attr(cx, w, "clip", r.clip->clip);
      attr(cx, w, "clip_intervals", static_cast<std::int64_t>(r.clip->intervals));
      attr(cx, w, "clip_mean_h_minus", r.clip->mean_h_minus);
      attr(cx, w, "clip_mean_h_uncertain", r.clip->mean_h_uncertain);
      attr(cx, w, "clip_max_h_minus", r.clip->max_h_minus);
      attr(cx, w, "clip_max_h_uncertain", r.clip->max_h_uncertain);
    }
  }
}

bool is_segmentation_file(const std::filesystem::path& path) {
  silence_hdf5();
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    return false;
  }
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.valid()) {
    H5Eclear2(H5E_DEFAULT);
    return false;
  }
  try {
    return read_string(Context{path.string()}, file.get(), "format") == kSegmentationFormatName;
  } catch (const IoError&) {
    return false;
  }
}

}  // namespace

void write_segmentation(
    const std::filesystem::path& path,
    const seg::Segmentation& segmentation,
    const SegmentationRecord& record) {
  silence_hdf5();
  const Context cx{path.string()};
  if (std::filesystem::exists(path) && !is_segmentation_file(path)) {
    cx.fail("exists and is not a skelcd segmentation; refusing to overwrite it");
  }
  // Written beside the target, renamed over it when complete.
  auto tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid());
  try {
    {
      Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
      if (!file.valid()) cx.fail("cannot create the file (" + tmp.string() + ")");
      write_file(cx, file.get(), segmentation, record);
      cx.check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "cannot flush");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) cx.fail("cannot move the finished file into place (" + ec.message() + ")");
  } catch (...) {
    std::error_code ignore;
    std::filesystem::remove(tmp, ignore);
    throw;
  }
}

SegmentationFile read_segmentation(const std::filesystem::path& path) {
  silence_hdf5();
  const Context cx{path.string()};
  if (!std::filesystem::exists(path)) cx.fail("no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) cx.fail("not an HDF5 file");
  auto file =
      cx.check(Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose), "cannot open");
  const hid_t f = file.get();
  if (!has_attr(f, "format") || read_string(cx, f, "format") != kSegmentationFormatName) {
    cx.fail(
        std::string("not a skelcd segmentation (no root attribute format = ") +
        kSegmentationFormatName + ")");
  }
  SegmentationFile out;
  auto& r = out.record;
  auto& s = out.segmentation;
  r.format_version = read_number<std::int64_t>(cx, f, "format_version");
  if (r.format_version < 1 || r.format_version > kSegmentationFormatVersion) {
    cx.fail(
        "format version " + std::to_string(r.format_version) +
        " is not supported (this build reads 1.." + std::to_string(kSegmentationFormatVersion) +
        ")");
  }
  r.skelcd_version = read_string(cx, f, "skelcd_version");
  r.input_path = read_string(cx, f, "input_path");
  r.input_hash = read_string(cx, f, "input_hash");
  auto& o = s.options;
  const auto weights = read_string(cx, f, "weights");
  if (weights != "heat" && weights != "rig") cx.fail("attribute 'weights' is '" + weights + "'");
  o.weights = weights == "heat" ? seg::WeightSource::heat : seg::WeightSource::rig;
  const auto distance = read_string(cx, f, "distance");
  if (distance != "exact" && distance != "coarse")
    cx.fail("attribute 'distance' is '" + distance + "'");
  o.heat.distance = distance == "exact" ? seg::DistanceMode::exact : seg::DistanceMode::coarse;
  o.theta_deg = read_number<double>(cx, f, "theta_deg");
  o.refine = read_number<std::int64_t>(cx, f, "refine") != 0;
  o.heat.heat_constant = read_number<double>(cx, f, "heat_constant");
  o.heat.tie_tolerance = read_number<double>(cx, f, "tie_tolerance");
  o.heat.min_distance_fraction = read_number<double>(cx, f, "min_distance_fraction");
  o.heat.grid_resolution = static_cast<int>(read_number<std::int64_t>(cx, f, "grid_resolution"));
  o.heat.smoothing_iterations =
      static_cast<int>(read_number<std::int64_t>(cx, f, "smoothing_iterations"));
  auto& st = s.stats;
  st.triangles = read_number<std::int64_t>(cx, f, "num_triangles");
  st.vertices = read_number<std::int64_t>(cx, f, "num_vertices");
  st.welded_vertices = read_number<std::int64_t>(cx, f, "num_welded_vertices");
  st.bones = static_cast<std::int32_t>(read_number<std::int64_t>(cx, f, "num_bones"));

  // Bones.
  {
    auto g = open_group(cx, f, "bones");
    std::vector<char*> names;
    const auto str = vlen_string_type();
    const auto nb = read_dataset(cx, g.get(), "name", str.get(), names);
    for (auto* n : names) {
      r.bone_names.emplace_back(n != nullptr ? n : "");
      H5free_memory(n);
    }
    std::vector<std::int32_t> parent;
    std::vector<double> head, tail;
    if (read_dataset(cx, g.get(), "parent", H5T_NATIVE_INT32, parent) != nb ||
        read_dataset(cx, g.get(), "head", H5T_NATIVE_DOUBLE, head, 3) != nb ||
        read_dataset(cx, g.get(), "tail", H5T_NATIVE_DOUBLE, tail, 3) != nb ||
        nb != static_cast<std::size_t>(st.bones)) {
      cx.fail("/bones datasets disagree in length");
    }
    for (std::size_t k = 0; k < nb; ++k) {
      if (parent[k] < -1 || parent[k] >= static_cast<std::int32_t>(nb)) {
        cx.fail("/bones/parent[" + std::to_string(k) + "] is out of range");
      }
      r.bones.push_back(
          {Eigen::Vector3d(head[3 * k], head[3 * k + 1], head[3 * k + 2]),
           Eigen::Vector3d(tail[3 * k], tail[3 * k + 1], tail[3 * k + 2]),
           parent[k]});
    }
  }

  // Clusters, and their triangles from the per-triangle table.
  const auto nt = read_dataset(cx, f, "triangle_cluster", H5T_NATIVE_INT32, s.triangle_cluster);
  if (nt != static_cast<std::size_t>(st.triangles))
    cx.fail("triangle_cluster has the wrong length");
  {
    auto g = open_group(cx, f, "clusters");
    std::vector<std::int32_t> bone, count;
    std::vector<std::int8_t> kind;
    std::vector<double> head, tail, mean_point, mean_line;
    const auto kinds = observer_kind_enum();
    const auto nc = read_dataset(cx, g.get(), "bone", H5T_NATIVE_INT32, bone);
    if (read_dataset(cx, g.get(), "observer_kind", kinds.get(), kind) != nc ||
        read_dataset(cx, g.get(), "observer_head", H5T_NATIVE_DOUBLE, head, 3) != nc ||
        read_dataset(cx, g.get(), "observer_tail", H5T_NATIVE_DOUBLE, tail, 3) != nc ||
        read_dataset(cx, g.get(), "triangle_count", H5T_NATIVE_INT32, count) != nc ||
        read_dataset(cx, g.get(), "mean_positive_point", H5T_NATIVE_DOUBLE, mean_point) != nc ||
        read_dataset(cx, g.get(), "mean_positive_line", H5T_NATIVE_DOUBLE, mean_line) != nc) {
      cx.fail("/clusters datasets disagree in length");
    }
    s.clusters.resize(nc);
    for (std::size_t c = 0; c < nc; ++c) {
      auto& cl = s.clusters[c];
      if (bone[c] < 0 || bone[c] >= st.bones) {
        cx.fail("/clusters/bone[" + std::to_string(c) + "] is out of range");
      }
      cl.bone = bone[c];
      cl.observer.kind = kind[c] == 1 ? seg::ObserverKind::line : seg::ObserverKind::point;
      cl.observer.segment = {
          Eigen::Vector3d(head[3 * c], head[3 * c + 1], head[3 * c + 2]),
          Eigen::Vector3d(tail[3 * c], tail[3 * c + 1], tail[3 * c + 2]),
          r.bones[static_cast<std::size_t>(bone[c])].parent};
      cl.mean_positive_point = mean_point[c];
      cl.mean_positive_line = mean_line[c];
      cl.triangles.reserve(static_cast<std::size_t>(std::max(0, count[c])));
    }
    for (std::size_t t = 0; t < nt; ++t) {
      const auto c = s.triangle_cluster[t];
      if (c < 0 || static_cast<std::size_t>(c) >= nc) {
        cx.fail(
            "triangle_cluster[" + std::to_string(t) + "] = " + std::to_string(c) +
            " is out of range");
      }
      s.clusters[static_cast<std::size_t>(c)].triangles.push_back(static_cast<std::int32_t>(t));
    }
    for (std::size_t c = 0; c < nc; ++c) {
      if (static_cast<std::int64_t>(s.clusters[c].triangles.size()) != count[c]) {
        cx.fail(
            "/clusters/triangle_count[" + std::to_string(c) + "] disagrees with triangle_cluster");
      }
      (s.clusters[c].observer.kind == seg::ObserverKind::point ? st.point_observers
                                                               : st.line_observers)++;
    }
    st.atomic_clusters = static_cast<std::int32_t>(nc);
  }

  // Graph.
  {
    auto g = open_group(cx, f, "graph");
    std::vector<std::int32_t> a, b, shared, ancestor;
    std::vector<double> joint;
    const auto ne = read_dataset(cx, g.get(), "a", H5T_NATIVE_INT32, a);
    if (read_dataset(cx, g.get(), "b", H5T_NATIVE_INT32, b) != ne ||
        read_dataset(cx, g.get(), "shared_edges", H5T_NATIVE_INT32, shared) != ne ||
        read_dataset(cx, g.get(), "ancestor_bone", H5T_NATIVE_INT32, ancestor) != ne ||
        read_dataset(cx, g.get(), "joint", H5T_NATIVE_DOUBLE, joint, 3) != ne) {
      cx.fail("/graph datasets disagree in length");
    }
    for (std::size_t e = 0; e < ne; ++e) {
      if (a[e] < 0 || b[e] <= a[e] || b[e] >= st.atomic_clusters) {
        cx.fail("/graph edge " + std::to_string(e) + " names clusters out of range");
      }
      s.graph.push_back(
          {a[e],
           b[e],
           shared[e],
           ancestor[e],
           Eigen::Vector3d(joint[3 * e], joint[3 * e + 1], joint[3 * e + 2])});
    }
  }

  // Statistics.
  {
    auto g = open_group(cx, f, "statistics");
    const hid_t w = g.get();
    st.split_clusters =
        static_cast<std::int32_t>(read_number<std::int64_t>(cx, w, "split_clusters"));
    st.h_minus = read_number<std::int64_t>(cx, w, "h_minus");
    st.h_uncertain = read_number<std::int64_t>(cx, w, "h_uncertain");
    st.refinement.non_positive_before =
        read_number<std::int64_t>(cx, w, "non_positive_before_refinement");
    st.refinement.non_positive_after =
        read_number<std::int64_t>(cx, w, "non_positive_after_refinement");
    st.refinement.removed = read_number<std::int64_t>(cx, w, "refinement_removed");
    st.refinement.regrown_positive =
        read_number<std::int64_t>(cx, w, "refinement_regrown_positive");
    st.refinement.regrown_unconstrained =
        read_number<std::int64_t>(cx, w, "refinement_regrown_unconstrained");
    st.refinement.restored = read_number<std::int64_t>(cx, w, "refinement_restored");
    st.heat.fallback_vertices = read_number<std::int64_t>(cx, w, "fallback_vertices");
    st.heat.isolated_vertices = read_number<std::int64_t>(cx, w, "isolated_vertices");
    st.heat.degenerate_triangles = read_number<std::int64_t>(cx, w, "degenerate_triangles");
    st.heat.clamped_weights = read_number<std::int64_t>(cx, w, "clamped_weights");
    st.unweighted_vertices = read_number<std::int64_t>(cx, w, "unweighted_vertices");
    st.weights_s = read_number<double>(cx, w, "weights_s");
    st.decomposition_ms = read_number<double>(cx, w, "decomposition_ms");
    read_dataset(cx, w, "bones_without_cluster", H5T_NATIVE_INT32, st.bones_without_cluster);
    if (has_attr(w, "clip")) {
      seg::ClipOrientationStats clip;
      clip.clip = read_string(cx, w, "clip");
      clip.intervals =
          static_cast<std::int32_t>(read_number<std::int64_t>(cx, w, "clip_intervals"));
      clip.mean_h_minus = read_number<double>(cx, w, "clip_mean_h_minus");
      clip.mean_h_uncertain = read_number<double>(cx, w, "clip_mean_h_uncertain");
      clip.max_h_minus = read_number<std::int64_t>(cx, w, "clip_max_h_minus");
      clip.max_h_uncertain = read_number<std::int64_t>(cx, w, "clip_max_h_uncertain");
      r.clip = clip;
    }
  }
  return out;
}

SegmentationFile read_segmentation(const std::filesystem::path& path, const std::string& model) {
  auto out = read_segmentation(path);
  const auto identity = model_identity(model);
  if (out.record.input_hash != identity) {
    throw InvalidInput(
        path.string() + ": made from a different file (" + out.record.input_hash + " of " +
        out.record.input_path + "), not from " + model + " (" + identity + ")");
  }
  return out;
}

bool segmentation_matches(const std::filesystem::path& path, const std::string& model) {
  try {
    return is_segmentation_file(path) &&
           read_segmentation(path).record.input_hash == model_identity(model);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace skelcd::tools
