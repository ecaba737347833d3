#include "tools/io/log/log_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "skinning/detail/import_guard.hpp"
#include "skinning/errors.hpp"
#include "tools/io/log/detail/hdf5_schema.hpp"
#include "tools/io/log/detail/log_answer.hpp"

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
    } else if constexpr (requires { r.frame; }) {
      return r.frame;
    } else {
      return 0;  // a table written once, in full (/events …): nothing to drop
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

/// A compound table as read: its rows in memory, and the same rows as stored (every column the
/// file has, known to this build or not), which the checksums cover.
template <class Row>
struct StoredTable {
  std::vector<Row> rows;
  std::vector<unsigned char> bytes;  ///< rows as stored, row_size bytes each
  std::size_t row_size = 0;
  H5Handle file_type;  ///< the stored row type (native copy of the file's, same layout)
  bool present = false;

  [[nodiscard]] std::uint32_t crc(std::uint32_t from, std::size_t begin, std::size_t end) const {
    if (end <= begin) return from;
    return detail::rows_crc(
        from, file_type.get(), bytes.data() + begin * row_size, end - begin, row_size);
  }
  void cut(std::size_t end) {
    if (rows.size() > end) rows.resize(end);
    if (bytes.size() > end * row_size) bytes.resize(end * row_size);
  }
};

/// Reads the whole 1-D compound dataset `name` through `memory_type` (fields matched by name).
/// Each row starts as `defaults`, which a column the file lacks (a log written before it existed)
/// keeps. `optional`: a missing table reads as empty (present = false) instead of failing.
template <class Row>
StoredTable<Row> read_table(
    hid_t file,
    const char* name,
    const H5Handle& memory_type,
    const Row& defaults,
    bool optional = false) {
  const std::string where = std::string("/") + name;
  StoredTable<Row> table;
  const htri_t exists = H5Lexists(file, name, H5P_DEFAULT);
  if (exists <= 0) {
    detail::clear_hdf5_error();
    if (optional) return table;
    throw IoError("missing table " + where);
  }
  table.present = true;
  H5Handle dataset(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!dataset.valid())
    throw IoError("cannot open " + where + " (" + detail::take_hdf5_error() + ")");
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
  std::vector<std::string> missing;
  const auto common = detail::common_members(memory_type.get(), type.get(), &missing);
  table.rows.assign(count, defaults);
  if (count == 0) return table;
  if (H5Dread(dataset.get(), common.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, table.rows.data()) < 0) {
    throw IoError("cannot read " + where + " (" + detail::take_hdf5_error() + ")");
  }
  // A column the file lacks: back to its default, whatever the conversion left there.
  for (const auto& column : missing) {
    const int index = H5Tget_member_index(memory_type.get(), column.c_str());
    H5Handle member(H5Tget_member_type(memory_type.get(), static_cast<unsigned>(index)), H5Tclose);
    const std::size_t offset =
        H5Tget_member_offset(memory_type.get(), static_cast<unsigned>(index));
    const std::size_t size = H5Tget_size(member.get());
    for (auto& row : table.rows) {
      std::memcpy(
          reinterpret_cast<unsigned char*>(&row) + offset,
          reinterpret_cast<const unsigned char*>(&defaults) + offset,
          size);
    }
  }
  drop_unwritten(table.rows);
  // The stored bytes, for the checksums: a type holding no variable-length data reads as is.
  if (H5Tdetect_class(type.get(), H5T_VLEN) <= 0 && H5Tdetect_class(type.get(), H5T_STRING) <= 0) {
    table.file_type = H5Handle(H5Tget_native_type(type.get(), H5T_DIR_ASCEND), H5Tclose);
    // A native type may align its members; the stored layout is the file's own, packed.
    if (table.file_type.valid() && H5Tpack(table.file_type.get()) < 0) table.file_type.reset();
    if (!table.file_type.valid()) {
      throw IoError("cannot read " + where + " (" + detail::take_hdf5_error() + ")");
    }
    table.row_size = H5Tget_size(table.file_type.get());
    table.bytes.resize(count * table.row_size);
    if (H5Dread(
            dataset.get(),
            table.file_type.get(),
            H5S_ALL,
            H5S_ALL,
            H5P_DEFAULT,
            table.bytes.data()) < 0) {
      throw IoError("cannot read " + where + " (" + detail::take_hdf5_error() + ")");
    }
    table.bytes.resize(table.rows.size() * table.row_size);
  }
  detail::clear_hdf5_error();
  return table;
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
    throw IoError(
        std::string("/routes/") + name + " is missing or not " + std::to_string(count) + " rows");
  }
  check_extent(std::string("/routes/") + name, rows, 1);
  std::vector<T> values(rows);
  if (rows > 0 && H5Dread(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
    throw IoError(
        std::string("cannot read /routes/") + name + " (" + detail::take_hdf5_error() + ")");
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
  const auto component =
      read_route_column<std::int32_t>(group.get(), "component", H5T_NATIVE_INT32, count);
  const auto part = read_route_column<std::int32_t>(group.get(), "part", H5T_NATIVE_INT32, count);
  const auto closed =
      read_route_column<std::uint8_t>(group.get(), "closed", H5T_NATIVE_UINT8, count);
  const auto triangles =
      read_route_column<std::int32_t>(group.get(), "triangles", H5T_NATIVE_INT32, count);
  const auto type = detail::vlen_string_type();
  auto method = read_route_column<char*>(group.get(), "method", type.get(), count);
  for (hsize_t i = 0; i < count; ++i) {
    routes.push_back(LogRoute{
        .component = component[i],
        .part = part[i],
        .closed = closed[i] != 0,
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
    if (rows > 0 &&
        H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()) < 0) {
      throw IoError(
          std::string("cannot read /checks/") + name + " (" + detail::take_hdf5_error() + ")");
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
  if (rows > 0 &&
      H5Dread(dataset.get(), H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
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
    throw IoError(
        "log format version " + std::to_string(*version) +
        " is not supported (this build reads 1.." + std::to_string(kLogFormatVersion) + ")");
  }
  h.format_version = static_cast<std::int32_t>(*version);
  const auto text = [&](const char* name) {
    return read_string_attribute(file, name).value_or("");
  };
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
  h.baseline = text("baseline");
  h.baseline_slack =
      static_cast<std::int32_t>(read_int_attribute(file, "baseline_slack").value_or(0));
  h.allow = detail::read_string_list_attribute(file, "allow").value_or(std::vector<std::string>{});
  h.allow_adjacent_bones = read_int_attribute(file, "allow_adjacent_bones").value_or(0) != 0;
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
  std::int64_t frames = 0, contacts = 0, dcd_pairs = 0, frame_checks = 0, events = 0;
  std::vector<std::string> damage;
};

void damaged_block(
    std::vector<std::string>& damage, const char* name, std::int64_t begin, std::int64_t end) {
  damage.push_back(
      std::string("/") + name + " rows " + std::to_string(begin) + " to " +
      std::to_string(end - 1) + " are damaged (they fail their checksum)");
}

bool covers(
    std::vector<std::string>& damage,
    const char* name,
    std::int64_t count,
    std::int64_t begin,
    std::int64_t end) {
  if (end < begin || end > count) {
    damage.push_back(
        std::string("/") + name + " has " + std::to_string(count) +
        " rows, but its checksums cover rows " + std::to_string(begin) + " to " +
        std::to_string(end - 1));
    return false;
  }
  return true;
}

template <class Row>
bool table_block_matches(
    const StoredTable<Row>& table,
    const char* name,
    std::int64_t begin,
    std::int64_t end,
    std::uint32_t expected,
    std::vector<std::string>& damage) {
  if (!covers(damage, name, static_cast<std::int64_t>(table.rows.size()), begin, end)) return false;
  if (table.crc(0, static_cast<std::size_t>(begin), static_cast<std::size_t>(end)) != expected) {
    damaged_block(damage, name, begin, end);
    return false;
  }
  return true;
}

bool frame_check_block_matches(
    const std::vector<std::int32_t>& values,
    std::int64_t begin,
    std::int64_t end,
    std::uint32_t expected,
    std::vector<std::string>& damage) {
  if (!covers(
          damage, detail::kFrameCheckPath, static_cast<std::int64_t>(values.size()), begin, end))
    return false;
  const H5Handle type(H5Tcopy(H5T_NATIVE_INT32), H5Tclose);
  const auto crc = detail::rows_crc(
      0,
      type.get(),
      values.data() + begin,
      static_cast<std::size_t>(end - begin),
      sizeof(std::int32_t));
  if (crc != expected) {
    damaged_block(damage, detail::kFrameCheckPath, begin, end);
    return false;
  }
  return true;
}

/// The events as read: /events, /event_parts, /event_bones.
struct EventTables {
  StoredTable<detail::EventDisk> events;
  StoredTable<detail::EventPartDisk> parts;
  StoredTable<detail::EventBoneDisk> bones;
  hid_t bone_type = H5I_INVALID_HID;  // memory type of `bones` (for reclaiming its strings)
  ~EventTables() {
    if (bones.rows.empty()) return;
    const auto type = detail::event_bone_memory_type();
    const hsize_t count = bones.rows.size();
    H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
    H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, bones.rows.data());
  }
};

/// Events are written once, at the end: a checksum row covers none of them or all of them.
bool events_block_matches(
    const EventTables& e,
    std::int64_t begin,
    std::int64_t end,
    std::uint32_t expected,
    std::vector<std::string>& damage) {
  const auto count = static_cast<std::int64_t>(e.events.rows.size());
  if (end == begin) {
    if (expected == 0) return true;
    damaged_block(damage, detail::kEventsPath, begin, begin + 1);
    return false;
  }
  if (begin != 0 || end != count) {
    damage.push_back(
        std::string("/") + detail::kEventsPath + " has " + std::to_string(count) +
        " rows, but its checksums cover rows " + std::to_string(begin) + " to " +
        std::to_string(end - 1));
    return false;
  }
  std::uint32_t crc = e.events.crc(0, 0, e.events.rows.size());
  crc = e.parts.crc(crc, 0, e.parts.rows.size());
  crc = detail::bone_rows_crc(crc, e.bones.rows);
  if (crc != expected) {
    damage.push_back(
        std::string("/") + detail::kEventsPath + " (with /" + detail::kEventPartsPath + " and /" +
        detail::kEventBonesPath + ") is damaged (it fails its checksum)");
    return false;
  }
  return true;
}

/// `self_crc` of a checksum row as stored: the CRC of its bytes with `self_crc` zeroed.
bool checksum_row_matches(const StoredTable<detail::ChecksumDisk>& checksums, std::size_t i) {
  const hid_t type = checksums.file_type.get();
  const int index = H5Tget_member_index(type, "self_crc");
  if (index < 0) {
    detail::clear_hdf5_error();
    return false;
  }
  const std::size_t offset = H5Tget_member_offset(type, static_cast<unsigned>(index));
  std::vector<unsigned char> row(
      checksums.bytes.begin() + static_cast<std::ptrdiff_t>(i * checksums.row_size),
      checksums.bytes.begin() + static_cast<std::ptrdiff_t>((i + 1) * checksums.row_size));
  if (offset + 4 > row.size()) return false;
  std::memset(row.data() + offset, 0, 4);
  return detail::rows_crc(0, type, row.data(), 1, row.size()) == checksums.rows[i].self_crc;
}

/// Walks /checksums in order and stops at the first row whose blocks do not match.
Verified verify_rows(
    const StoredTable<detail::ChecksumDisk>& checksums,
    const StoredTable<detail::FrameDisk>& frames,
    const StoredTable<detail::ContactDisk>& contacts,
    const StoredTable<detail::DcdPairDisk>& pairs,
    const std::vector<std::int32_t>& frame_checks,
    const EventTables& events) {
  Verified v;
  for (std::size_t i = 0; i < checksums.rows.size(); ++i) {
    const auto& c = checksums.rows[i];
    if (!checksum_row_matches(checksums, i)) {
      std::string what = "/";
      what += detail::kChecksumsPath;
      what += " row " + std::to_string(i) + " is damaged";
      v.damage.push_back(std::move(what));
      break;
    }
    bool ok = table_block_matches(
        frames, detail::kFramesPath, v.frames, c.frames_end, c.frames_crc, v.damage);
    ok = table_block_matches(
             contacts,
             detail::kContactsPath,
             v.contacts,
             c.contacts_end,
             c.contacts_crc,
             v.damage) &&
         ok;
    ok = table_block_matches(
             pairs,
             detail::kDcdPairsPath,
             v.dcd_pairs,
             c.dcd_pairs_end,
             c.dcd_pairs_crc,
             v.damage) &&
         ok;
    ok = frame_check_block_matches(
             frame_checks, v.frame_checks, c.frame_check_end, c.frame_check_crc, v.damage) &&
         ok;
    ok = events_block_matches(events, v.events, c.events_end, c.events_crc, v.damage) && ok;
    if (!ok) break;
    v.frames = c.frames_end;
    v.contacts = c.contacts_end;
    v.dcd_pairs = c.dcd_pairs_end;
    v.frame_checks = c.frame_check_end;
    v.events = c.events_end;
  }
  return v;
}

template <class Row>
void cut(std::vector<Row>& rows, std::int64_t end) {
  if (static_cast<std::int64_t>(rows.size()) > end) rows.resize(static_cast<std::size_t>(end));
}

/// What a finding row reads as where the file has no such column: a log written before labels
/// has kLabelNone in every row.
detail::ContactDisk contact_defaults() {
  detail::ContactDisk d{};
  d.label = kLabelNone;
  return d;
}

detail::DcdPairDisk pair_defaults() {
  detail::DcdPairDisk d{};
  d.label = kLabelNone;
  return d;
}

detail::EventDisk event_defaults() {
  detail::EventDisk d{};
  d.t_first_contact = std::numeric_limits<double>::quiet_NaN();
  d.peak_sample = -1;
  d.merged_into = -1;
  return d;
}

/// EventRecords from the three tables; parts and bones attach to the event of their `event` id.
std::vector<EventRecord> assemble_events(const EventTables& t) {
  std::vector<EventRecord> events;
  std::map<std::int32_t, std::size_t> by_id;
  for (const auto& d : t.events.rows) {
    EventRecord e;
    e.id = d.id;
    e.first_sample = d.first_sample;
    e.last_sample = d.last_sample;
    e.t_first = d.t_first;
    e.t_last = d.t_last;
    if (!std::isnan(d.t_first_contact)) e.t_first_contact = d.t_first_contact;
    e.peak_pairs = d.peak_pairs;
    e.peak_sample = d.peak_sample;
    e.dcd_pairs = d.dcd_pairs;
    e.ccd_contacts = d.ccd_contacts;
    e.depth = d.depth;
    e.merged_into = d.merged_into;
    by_id.emplace(e.id, events.size());
    events.push_back(std::move(e));
  }
  const auto event_of = [&](std::int32_t id, const char* table) -> EventRecord& {
    const auto it = by_id.find(id);
    if (it == by_id.end()) {
      throw IoError(
          std::string("/") + table + " names event " + std::to_string(id) +
          ", which /events does not have");
    }
    return events[it->second];
  };
  for (const auto& p : t.parts.rows)
    event_of(p.event, detail::kEventPartsPath).parts.push_back(p.part);
  for (const auto& b : t.bones.rows) {
    event_of(b.event, detail::kEventBonesPath).bones.emplace_back(b.bone != nullptr ? b.bone : "");
  }
  return events;
}

}  // namespace

LogData read_log(const std::filesystem::path& path, const ReadLogOptions& options) {
  if (options.isolate) {
    std::error_code exists_ec;
    if (std::filesystem::is_regular_file(path, exists_ec)) {
      // The child's read is the only one: it sends the log back, and this process never hands
      // the file to libhdf5, whose faults on a malformed file (some only now and then, as a read
      // after free) stay in the child.
      ReadLogOptions inside = options;
      inside.isolate = false;
      const skinning::detail::ImportLimits limits{
          .memory_bytes = std::size_t{4} << 30, .time_s = 120.0, .reader = "HDF5"};
      auto answer = skinning::detail::run_isolated_with_answer(
          path, limits, [&](const skinning::detail::AnswerSink& send) {
            detail::write_log_answer(read_log(path, inside), send);
          });
      return detail::read_log_answer(answer, path.string());
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
    auto frames = read_table(
        file.get(), detail::kFramesPath, detail::frame_memory_type(), detail::FrameDisk{});
    data.frame_checks = read_frame_checks(file.get());
    // Findings are read when asked for, or when the checksums need them.
    const bool has_checksums = H5Lexists(file.get(), detail::kChecksumsPath, H5P_DEFAULT) > 0;
    detail::clear_hdf5_error();
    StoredTable<detail::ContactDisk> contacts;
    StoredTable<detail::DcdPairDisk> pairs;
    if (options.findings || has_checksums) {
      contacts = read_table(
          file.get(), detail::kContactsPath, detail::contact_memory_type(), contact_defaults());
      pairs = read_table(
          file.get(), detail::kDcdPairsPath, detail::dcd_pair_memory_type(), pair_defaults());
    }
    // Events (optional: written at the end of a run, since events exist).
    EventTables events;
    events.events = read_table(
        file.get(),
        detail::kEventsPath,
        detail::event_memory_type(),
        event_defaults(),
        /*optional=*/true);
    if (events.events.present) {
      events.parts = read_table(
          file.get(),
          detail::kEventPartsPath,
          detail::event_part_memory_type(),
          detail::EventPartDisk{},
          true);
      events.bones = read_table(
          file.get(),
          detail::kEventBonesPath,
          detail::event_bone_memory_type(),
          detail::EventBoneDisk{.event = 0, .bone = nullptr},
          true);
    }
    if (has_checksums) {
      detail::ChecksumDisk checksum_defaults{};
      const auto checksums = read_table(
          file.get(), detail::kChecksumsPath, detail::checksum_memory_type(), checksum_defaults);
      auto verified = verify_rows(checksums, frames, contacts, pairs, data.frame_checks, events);
      data.verified = verified.damage.empty();
      if (!verified.damage.empty()) {
        frames.cut(static_cast<std::size_t>(verified.frames));
        contacts.cut(static_cast<std::size_t>(verified.contacts));
        pairs.cut(static_cast<std::size_t>(verified.dcd_pairs));
        cut(data.frame_checks, verified.frame_checks);
        // The events are written last, covered by the last checksum row: past the damage.
        events.events.present = false;
        data.damage = std::move(verified.damage);
      }
    }
    data.frames.reserve(frames.rows.size());
    for (const auto& f : frames.rows) data.frames.push_back(from_disk(f));
    if (options.findings) {
      data.contacts.reserve(contacts.rows.size());
      for (const auto& c : contacts.rows) {
        data.contacts.push_back(ContactRow{
            .frame = c.frame,
            .kind = c.kind == static_cast<std::uint8_t>(culling::CcdContact::Kind::ee)
                        ? culling::CcdContact::Kind::ee
                        : culling::CcdContact::Kind::vf,
            .a = FeatureId{c.a_part, c.a_index, c.a_side},
            .b = FeatureId{c.b_part, c.b_index, c.b_side},
            .toi_lower = c.toi_lower,
            .toi_upper = c.toi_upper,
            .label = c.label,
        });
      }
      data.dcd_pairs.reserve(pairs.rows.size());
      for (const auto& p : pairs.rows) {
        data.dcd_pairs.push_back(DcdPairRow{
            .frame = p.frame,
            .a = FeatureId{p.a_part, p.a_index, -1},
            .b = FeatureId{p.b_part, p.b_index, -1},
            .label = p.label,
        });
      }
    }
    if (events.events.present) {
      data.events = assemble_events(events);
      data.events_recorded = true;
    }
  } catch (const IoError& e) {
    throw IoError(name + ": " + e.what());
  }
  return data;
}

}  // namespace skelcd::tools
