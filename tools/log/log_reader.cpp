#include "tools/log/log_reader.hpp"

#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

#include "skinning/detail/import_guard.hpp"
#include "skinning/errors.hpp"
#include "tools/log/detail/hdf5_schema.hpp"

namespace skelcd::tools {

using detail::H5Handle;

namespace {

/// Drops the rows at the end of a table that no flush reached: the fill value's first field is -1
/// (`sample` of /frames, `frame` of the findings, the check of /frame_check), which no written
/// row has. Only the log of a killed run has such rows (docs/log-format.md, crash safety).
template <class Row>
void drop_unwritten(std::vector<Row>& rows) {
  const auto first = [](const Row& r) {
    if constexpr (std::is_same_v<Row, std::int32_t>) {
      return r;
    } else if constexpr (requires { r.sample; }) {
      return r.sample;
    } else if constexpr (requires { r.frames_end; }) {
      return r.frames_end;
    } else {
      return r.frame;
    }
  };
  while (!rows.empty() && first(rows.back()) == -1) rows.pop_back();
}

/// Bytes of the log file being read: no table can hold more rows than its bytes (plus one chunk
/// of unwritten rows, which take no space), so a damaged extent is refused instead of allocated.
thread_local std::uintmax_t tl_file_bytes = 0;

void check_extent(const std::string& where, hsize_t count, std::size_t min_row_bytes) {
  const std::uintmax_t most = tl_file_bytes / std::max<std::size_t>(min_row_bytes, 1) + 1024;
  if (count > most) {
    throw IoError(
        where + " claims " + std::to_string(count) + " rows, more than the file's " +
        std::to_string(tl_file_bytes) + " bytes can hold (damaged)");
  }
}

/// Reads the whole 1-D compound dataset `name` into `rows` through `memory_type` (fields matched
/// by name).
template <class Row>
void read_table(hid_t file, const char* name, const H5Handle& memory_type, std::vector<Row>& rows) {
  const std::string where = std::string("/") + name;
  const htri_t exists = H5Lexists(file, name, H5P_DEFAULT);
  if (exists <= 0) throw IoError("missing table " + where);
  H5Handle dataset(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!dataset.valid()) throw IoError("cannot open " + where + " (" + detail::take_hdf5_error() + ")");
  H5Handle type(H5Dget_type(dataset.get()), H5Tclose);
  H5Handle space(H5Dget_space(dataset.get()), H5Sclose);
  if (!type.valid() || !space.valid() || H5Tget_class(type.get()) != H5T_COMPOUND ||
      H5Sget_simple_extent_ndims(space.get()) != 1) {
    detail::clear_hdf5_error();
    throw IoError(where + " is not a one-dimensional table");
  }
  hsize_t count = 0;
  H5Sget_simple_extent_dims(space.get(), &count, nullptr);
  check_extent(where, count, H5Tget_size(type.get()));
  rows.resize(count);
  if (count == 0) return;
  if (H5Dread(dataset.get(), memory_type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data()) < 0) {
    throw IoError("cannot read " + where + " (" + detail::take_hdf5_error() + ")");
  }
  drop_unwritten(rows);
}

std::vector<std::string> read_parts(hid_t file) {
  std::vector<std::string> names;
  if (H5Lexists(file, detail::kPartsPath, H5P_DEFAULT) <= 0) {
    detail::clear_hdf5_error();
    return names;  // optional: contacts then carry part ids without names
  }
  H5Handle dataset(H5Dopen2(file, detail::kPartsPath, H5P_DEFAULT), H5Dclose);
  H5Handle space(H5Dget_space(dataset.get()), H5Sclose);
  H5Handle stored(H5Dget_type(dataset.get()), H5Tclose);
  if (!dataset.valid() || !space.valid() || !stored.valid() ||
      H5Tget_class(stored.get()) != H5T_STRING || H5Tis_variable_str(stored.get()) <= 0 ||
      H5Sget_simple_extent_ndims(space.get()) != 1) {
    detail::clear_hdf5_error();
    throw IoError("/parts is not a list of strings");
  }
  hsize_t count = 0;
  H5Sget_simple_extent_dims(space.get(), &count, nullptr);
  check_extent("/parts", count, 16);  // a variable-length string takes a 16-byte reference
  if (count == 0) return names;
  const auto type = detail::vlen_string_type();
  std::vector<char*> pointers(count, nullptr);
  if (H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, pointers.data()) < 0) {
    throw IoError("cannot read /parts (" + detail::take_hdf5_error() + ")");
  }
  names.reserve(count);
  for (const char* p : pointers) names.emplace_back(p != nullptr ? p : "");
  H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, pointers.data());
  return names;
}

// One column of /routes, checked to hold `count` rows (count < 0: take its length).
template <class T>
std::vector<T> read_route_column(hid_t group, const char* name, hid_t type, hsize_t count) {
  H5Handle dataset(H5Dopen2(group, name, H5P_DEFAULT), H5Dclose);
  H5Handle space(dataset.valid() ? H5Dget_space(dataset.get()) : -1, H5Sclose);
  hsize_t rows = 0;
  if (!dataset.valid() || !space.valid() || H5Sget_simple_extent_ndims(space.get()) != 1 ||
      H5Sget_simple_extent_dims(space.get(), &rows, nullptr) < 0 || rows != count) {
    detail::clear_hdf5_error();
    throw IoError(std::string("/routes/") + name + " is missing or not " + std::to_string(count) +
                  " rows");
  }
  check_extent(std::string("/routes/") + name, rows, 1);
  std::vector<T> values(rows);
  if (rows > 0 && H5Dread(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
    throw IoError(std::string("cannot read /routes/") + name + " (" + detail::take_hdf5_error() + ")");
  }
  return values;
}

std::vector<LogRoute> read_routes(hid_t file) {
  std::vector<LogRoute> routes;
  if (H5Lexists(file, detail::kRoutesPath, H5P_DEFAULT) <= 0) {
    detail::clear_hdf5_error();
    return routes;  // optional: written only by `auto`
  }
  H5Handle group(H5Gopen2(file, detail::kRoutesPath, H5P_DEFAULT), H5Gclose);
  H5Handle first(group.valid() ? H5Dopen2(group.get(), "component", H5P_DEFAULT) : -1, H5Dclose);
  H5Handle space(first.valid() ? H5Dget_space(first.get()) : -1, H5Sclose);
  hsize_t count = 0;
  if (!space.valid() || H5Sget_simple_extent_dims(space.get(), &count, nullptr) < 0) {
    detail::clear_hdf5_error();
    throw IoError("/routes has no readable component column");
  }
  const auto component = read_route_column<std::int32_t>(group.get(), "component", H5T_NATIVE_INT32, count);
  const auto part = read_route_column<std::int32_t>(group.get(), "part", H5T_NATIVE_INT32, count);
  const auto closed = read_route_column<std::uint8_t>(group.get(), "closed", H5T_NATIVE_UINT8, count);
  const auto triangles = read_route_column<std::int32_t>(group.get(), "triangles", H5T_NATIVE_INT32, count);
  const auto type = detail::vlen_string_type();
  auto method = read_route_column<char*>(group.get(), "method", type.get(), count);
  for (hsize_t i = 0; i < count; ++i) {
    routes.push_back(LogRoute{.component = component[i], .part = part[i], .closed = closed[i] != 0,
                              .triangles = triangles[i],
                              .method = method[i] != nullptr ? method[i] : ""});
  }
  if (count > 0) {
    H5Handle method_set(H5Dopen2(group.get(), "method", H5P_DEFAULT), H5Dclose);
    H5Handle method_space(H5Dget_space(method_set.get()), H5Sclose);
    H5Dvlen_reclaim(type.get(), method_space.get(), H5P_DEFAULT, method.data());
  }
  return routes;
}

// /checks of a scene log (optional): string columns of equal length.
std::vector<LogCheck> read_checks(hid_t file) {
  std::vector<LogCheck> checks;
  if (H5Lexists(file, "checks", H5P_DEFAULT) <= 0) {
    detail::clear_hdf5_error();
    return checks;  // optional: written only for scenes
  }
  H5Handle group(H5Gopen2(file, "checks", H5P_DEFAULT), H5Gclose);
  const auto type = detail::vlen_string_type();
  const auto column = [&](const char* name) {
    H5Handle dataset(group.valid() ? H5Dopen2(group.get(), name, H5P_DEFAULT) : -1, H5Dclose);
    H5Handle space(dataset.valid() ? H5Dget_space(dataset.get()) : -1, H5Sclose);
    hsize_t rows = 0;
    if (!space.valid() || H5Sget_simple_extent_dims(space.get(), &rows, nullptr) < 0) {
      detail::clear_hdf5_error();
      throw IoError(std::string("/checks/") + name + " is missing");
    }
    check_extent(std::string("/checks/") + name, rows, 16);
    std::vector<char*> raw(rows, nullptr);
    if (rows > 0 && H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()) < 0) {
      throw IoError(std::string("cannot read /checks/") + name + " (" + detail::take_hdf5_error() + ")");
    }
    std::vector<std::string> values;
    for (const char* r : raw) values.emplace_back(r != nullptr ? r : "");
    if (rows > 0) H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, raw.data());
    return values;
  };
  const auto name = column("name");
  const auto object_a = column("object_a");
  const auto object_b = column("object_b");
  const auto query = column("query");
  const auto method = column("method");
  const auto accuracy = column("accuracy");
  for (const auto* c : {&object_a, &object_b, &query, &method, &accuracy}) {
    if (c->size() != name.size()) throw IoError("/checks columns differ in length");
  }
  for (std::size_t i = 0; i < name.size(); ++i) {
    checks.push_back(LogCheck{name[i], object_a[i], object_b[i], query[i], method[i], accuracy[i]});
  }
  return checks;
}

// /frame_check of a scene log (optional): the check of each /frames row.
std::vector<std::int32_t> read_frame_checks(hid_t file) {
  std::vector<std::int32_t> values;
  if (H5Lexists(file, detail::kFrameCheckPath, H5P_DEFAULT) <= 0) {
    detail::clear_hdf5_error();
    return values;
  }
  H5Handle dataset(H5Dopen2(file, detail::kFrameCheckPath, H5P_DEFAULT), H5Dclose);
  H5Handle space(dataset.valid() ? H5Dget_space(dataset.get()) : -1, H5Sclose);
  hsize_t rows = 0;
  if (!space.valid() || H5Sget_simple_extent_dims(space.get(), &rows, nullptr) < 0) {
    detail::clear_hdf5_error();
    throw IoError("/frame_check is not readable");
  }
  check_extent("/frame_check", rows, 4);
  values.resize(rows);
  if (rows > 0 && H5Dread(dataset.get(), H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                          values.data()) < 0) {
    throw IoError("cannot read /frame_check (" + detail::take_hdf5_error() + ")");
  }
  drop_unwritten(values);
  return values;
}

LogHeader read_header(hid_t file) {
  using detail::read_double_attribute;
  using detail::read_int_attribute;
  using detail::read_string_attribute;
  const auto format = read_string_attribute(file, "format");
  if (!format || *format != kLogFormatName) {
    throw IoError("not a skelcd log (no root attribute format = \"skelcd-log\")");
  }
  LogHeader h;
  const auto version = read_int_attribute(file, "format_version");
  if (!version) throw IoError("missing root attribute format_version");
  if (*version < 1 || *version > kLogFormatVersion) {
    throw IoError("log format version " + std::to_string(*version) +
                  " is not supported (this build reads 1.." + std::to_string(kLogFormatVersion) + ")");
  }
  h.format_version = static_cast<std::int32_t>(*version);
  const auto text = [&](const char* name) { return read_string_attribute(file, name).value_or(""); };
  h.skelcd_version = text("skelcd_version");
  h.command_line = text("command_line");
  h.input_path = text("input_path");
  h.input_hash = text("input_hash");
  h.clip = text("clip");
  h.method = text("method");
  h.accuracy = text("accuracy");
  h.query = text("query");
  h.start_time = text("start_time");
  h.fps = read_double_attribute(file, "fps").value_or(0.0);
  h.min_separation = read_double_attribute(file, "min_separation").value_or(0.0);
  h.gamma = read_double_attribute(file, "gamma");
  h.theta = read_double_attribute(file, "theta");
  h.seed = read_int_attribute(file, "seed");
  h.segmentation = text("segmentation");
  h.first_sample = static_cast<std::int32_t>(read_int_attribute(file, "first_sample").value_or(0));
  h.last_sample = static_cast<std::int32_t>(read_int_attribute(file, "last_sample").value_or(0));
  h.planned_rows = read_int_attribute(file, "planned_rows").value_or(0);
  h.num_vertices = read_int_attribute(file, "num_vertices").value_or(0);
  h.num_triangles = read_int_attribute(file, "num_triangles").value_or(0);
  h.complete = read_int_attribute(file, "complete").value_or(0) != 0;
  h.part_names = read_parts(file);
  h.routes = read_routes(file);
  h.checks = read_checks(file);
  return h;
}

FrameRow from_disk(const detail::FrameDisk& d) {
  FrameRow row;
  row.sample = d.sample;
  row.t0 = d.t0;
  row.t1 = d.t1;
  row.kind = d.kind == static_cast<std::uint8_t>(QueryKind::ccd) ? QueryKind::ccd : QueryKind::dcd;
#define SKELCD_COPY_COUNTER(name, meaning) row.counters.name = d.name;
  SKELCD_COUNTERS(SKELCD_COPY_COUNTER)
#undef SKELCD_COPY_COUNTER
#define SKELCD_COPY_STAGE(name, meaning) row.times.name = d.name;
  SKELCD_STAGE_TIMES(SKELCD_COPY_STAGE)
#undef SKELCD_COPY_STAGE
  row.total_us = d.total_us;
  return row;
}

/// The rows of every table that a log's /checksums cover, and what failed.
struct Verified {
  std::int64_t frames = 0, contacts = 0, dcd_pairs = 0, frame_checks = 0;
  std::vector<std::string> damage;
};

template <class Row>
bool table_block_matches(
    const std::vector<Row>& rows,
    hid_t memory_type,
    const char* name,
    std::int64_t begin,
    std::int64_t end,
    std::uint32_t expected,
    std::vector<std::string>& damage) {
  const auto count = static_cast<std::int64_t>(rows.size());
  const std::string table = std::string("/") + name;
  if (end < begin || end > count) {
    damage.push_back(
        table + " has " + std::to_string(count) + " rows, but its checksums cover rows " +
        std::to_string(begin) + " to " + std::to_string(end - 1));
    return false;
  }
  const auto crc = detail::rows_crc(
      0, memory_type, rows.data() + begin, static_cast<std::size_t>(end - begin), sizeof(Row));
  if (crc != expected) {
    damage.push_back(
        table + " rows " + std::to_string(begin) + " to " + std::to_string(end - 1) +
        " are damaged (they fail their checksum)");
    return false;
  }
  return true;
}

/// Walks /checksums in order and stops at the first row whose blocks do not match.
Verified verify_rows(
    const std::vector<detail::ChecksumDisk>& checksums,
    const std::vector<detail::FrameDisk>& frames,
    const std::vector<detail::ContactDisk>& contacts,
    const std::vector<detail::DcdPairDisk>& pairs,
    const std::vector<std::int32_t>& frame_checks) {
  Verified v;
  const auto frame_type = detail::frame_memory_type();
  const auto contact_type = detail::contact_memory_type();
  const auto pair_type = detail::dcd_pair_memory_type();
  const H5Handle check_type(H5Tcopy(H5T_NATIVE_INT32), H5Tclose);
  for (std::size_t i = 0; i < checksums.size(); ++i) {
    const auto& c = checksums[i];
    if (detail::checksum_row_crc(c) != c.self_crc) {
      std::string what = "/";
      what += detail::kChecksumsPath;
      what += " row " + std::to_string(i) + " is damaged";
      v.damage.push_back(std::move(what));
      break;
    }
    bool ok = table_block_matches(
        frames,
        frame_type.get(),
        detail::kFramesPath,
        v.frames,
        c.frames_end,
        c.frames_crc,
        v.damage);
    ok = table_block_matches(
             contacts,
             contact_type.get(),
             detail::kContactsPath,
             v.contacts,
             c.contacts_end,
             c.contacts_crc,
             v.damage) &&
         ok;
    ok = table_block_matches(
             pairs,
             pair_type.get(),
             detail::kDcdPairsPath,
             v.dcd_pairs,
             c.dcd_pairs_end,
             c.dcd_pairs_crc,
             v.damage) &&
         ok;
    ok = table_block_matches(
             frame_checks,
             check_type.get(),
             detail::kFrameCheckPath,
             v.frame_checks,
             c.frame_check_end,
             c.frame_check_crc,
             v.damage) &&
         ok;
    if (!ok) break;
    v.frames = c.frames_end;
    v.contacts = c.contacts_end;
    v.dcd_pairs = c.dcd_pairs_end;
    v.frame_checks = c.frame_check_end;
  }
  return v;
}

template <class Row>
void cut(std::vector<Row>& rows, std::int64_t end) {
  if (static_cast<std::int64_t>(rows.size()) > end) rows.resize(static_cast<std::size_t>(end));
}

}  // namespace

LogData read_log(const std::filesystem::path& path, const ReadLogOptions& options) {
  if (options.isolate) {
    std::error_code exists_ec;
    if (std::filesystem::is_regular_file(path, exists_ec)) {
      ReadLogOptions inside = options;
      inside.isolate = false;
      const skinning::detail::ImportLimits limits{
          .memory_bytes = std::size_t{4} << 30, .time_s = 120.0, .reader = "HDF5"};
      skinning::detail::run_isolated(path, limits, [&] { (void)read_log(path, inside); });
    }
  }
  detail::silence_hdf5_errors();
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(name + ": no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(name + ": not a regular file");
  const htri_t is_hdf5 = H5Fis_hdf5(name.c_str());
  if (is_hdf5 <= 0) {
    detail::clear_hdf5_error();
    throw IoError(name + ": not an HDF5 file");
  }
  H5Handle file(H5Fopen(name.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.valid()) {
    throw IoError(name + ": cannot open HDF5 file (" + detail::take_hdf5_error() + ")");
  }
  tl_file_bytes = std::filesystem::file_size(path, ec);
  LogData data;
  try {
    data.header = read_header(file.get());
    std::vector<detail::FrameDisk> frames;
    read_table(file.get(), detail::kFramesPath, detail::frame_memory_type(), frames);
    data.frame_checks = read_frame_checks(file.get());
    // Findings are read when asked for, or when the checksums need them.
    const bool has_checksums = H5Lexists(file.get(), detail::kChecksumsPath, H5P_DEFAULT) > 0;
    detail::clear_hdf5_error();
    std::vector<detail::ContactDisk> contacts;
    std::vector<detail::DcdPairDisk> pairs;
    if (options.findings || has_checksums) {
      read_table(file.get(), detail::kContactsPath, detail::contact_memory_type(), contacts);
      read_table(file.get(), detail::kDcdPairsPath, detail::dcd_pair_memory_type(), pairs);
    }
    if (has_checksums) {
      std::vector<detail::ChecksumDisk> checksums;
      read_table(file.get(), detail::kChecksumsPath, detail::checksum_memory_type(), checksums);
      auto verified = verify_rows(checksums, frames, contacts, pairs, data.frame_checks);
      data.verified = verified.damage.empty();
      if (!verified.damage.empty()) {
        cut(frames, verified.frames);
        cut(contacts, verified.contacts);
        cut(pairs, verified.dcd_pairs);
        cut(data.frame_checks, verified.frame_checks);
        data.damage = std::move(verified.damage);
      }
    }
    data.frames.reserve(frames.size());
    for (const auto& f : frames) data.frames.push_back(from_disk(f));
    if (options.findings) {
      data.contacts.reserve(contacts.size());
      for (const auto& c : contacts) {
        data.contacts.push_back(ContactRow{
            .frame = c.frame,
            .kind = c.kind == static_cast<std::uint8_t>(culling::CcdContact::Kind::ee)
                        ? culling::CcdContact::Kind::ee
                        : culling::CcdContact::Kind::vf,
            .a = FeatureId{c.a_part, c.a_index, c.a_side},
            .b = FeatureId{c.b_part, c.b_index, c.b_side},
            .toi_lower = c.toi_lower,
            .toi_upper = c.toi_upper,
        });
      }
      data.dcd_pairs.reserve(pairs.size());
      for (const auto& p : pairs) {
        data.dcd_pairs.push_back(DcdPairRow{
            .frame = p.frame,
            .a = FeatureId{p.a_part, p.a_index, -1},
            .b = FeatureId{p.b_part, p.b_index, -1},
        });
      }
    }
  } catch (const IoError& e) {
    throw IoError(name + ": " + e.what());
  }
  return data;
}

}  // namespace skelcd::tools
