#include "tools/io/log/log_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <system_error>
#include <vector>

#include "skinning/errors.hpp"
#include "tools/io/log/detail/hdf5_schema.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {

using detail::H5Handle;

namespace {

/// One extendible table: its dataset, the memory type of its rows, how many rows it holds and the
/// transfer properties its appends use (transfer_properties).
struct Table {
  H5Handle dataset;
  H5Handle memory_type;
  hsize_t rows = 0;
  H5Handle transfer;
};

/// Bytes of HDF5's type-conversion buffer, and of its background buffer, for every dataset write
/// (the header's /parts, /routes and /checks as well as the appends): HDF5 converts rows to the
/// packed file layout, and strings to variable-length ones, through them, in strips of this size.
/// Its default is 1 MiB each, kept in its free lists for the life of the process once used: 2 MiB
/// of every checked clip's peak, whatever its findings (docs/benchmarks.md "Real assets"). The
/// first write with the default (/parts, before this covered the header too) was enough.
constexpr std::size_t kConversionBufferBytes = std::size_t{64} << 10;

/// A property list of ours, or HDF5's defaults where it could not be made (invalid).
hid_t or_default(const H5Handle& properties) {
  return properties.valid() ? properties.get() : H5P_DEFAULT;
}

/// Dataset transfer properties with kConversionBufferBytes buffers (invalid if HDF5 refuses them:
/// the writes then use the defaults).
H5Handle transfer_properties() {
  H5Handle properties(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  if (properties.valid() &&
      H5Pset_buffer(properties.get(), kConversionBufferBytes, nullptr, nullptr) < 0) {
    detail::clear_hdf5_error();
    return {};
  }
  return properties;
}

/// Rows per chunk: small enough that the chunk rewritten at every flush stays cheap.
constexpr hsize_t kFrameChunkRows = 64;
constexpr hsize_t kPairChunkRows = 1024;

/// Slots of each table's chunk cache (HDF5's default: 521): the appends touch one chunk at a time.
constexpr std::size_t kChunkCacheSlots = 11;

/// Dataset access properties whose chunk cache holds one chunk of `chunk_bytes` (an append only
/// ever writes the table's last chunk, and a flush writes it out). HDF5's default is 1 MiB of
/// chunks per open dataset, kept until the file closes: on a run with many findings, up to 1 MiB
/// each of /contacts and /dcd_pairs chunks already on disk. Invalid if HDF5 refuses them (the
/// table then has the default cache).
H5Handle chunk_cache_properties(std::size_t chunk_bytes) {
  H5Handle properties(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
  if (properties.valid() &&
      H5Pset_chunk_cache(
          properties.get(), kChunkCacheSlots, chunk_bytes, H5D_CHUNK_CACHE_W0_DEFAULT) < 0) {
    detail::clear_hdf5_error();
    return {};
  }
  return properties;
}

/// The tables are chunked but not compressed, on purpose: an uncompressed chunk keeps its size
/// and so its place in the file, and every flush rewrites it where it is. A compressed chunk
/// changes size with every row, is written to a new place and its old space freed for reuse; a
/// kill inside a flush can then leave the chunk index pointing at space already holding other
/// data (`inflate() failed` on the next read: 1 kill in ~25 in CmdCheck.KilledRun…). Keeping
/// compression but never reusing space (H5F_FSPACE_STRATEGY_NONE) was tried and rejected: every
/// flush then leaks the chunk's previous copy, and logs came out larger than uncompressed ones.
/// Rows the extent counts but no flush reached read as the fill value, a row whose first field
/// (`sample` or `frame`) is -1; the reader drops such rows at the end of a table.
/// The fill value of a table: all zero but the first field, -1.
template <class Row>
Row unwritten() {
  Row row{};
  if constexpr (requires { row.sample; }) {
    row.sample = -1;
  } else if constexpr (requires { row.frames_end; }) {
    row.frames_end = -1;
  } else {
    row.frame = -1;
  }
  return row;
}

template <class Row>
Table create_table(
    hid_t file,
    const char* name,
    H5Handle memory_type,
    hsize_t chunk_rows,
    const Row& fill,
    const std::string& where) {
  const auto fail = [&](const char* what) {
    throw IoError(
        where + ": cannot create /" + name + " (" + what + ": " + detail::take_hdf5_error() + ")");
  };
  const auto file_type = detail::packed_copy(memory_type.get());
  const hsize_t initial = 0;
  const hsize_t unlimited = H5S_UNLIMITED;
  H5Handle space(H5Screate_simple(1, &initial, &unlimited), H5Sclose);
  H5Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (!space.valid() || !properties.valid()) fail("dataspace");
  if (H5Pset_chunk(properties.get(), 1, &chunk_rows) < 0) fail("chunking");
  if (H5Pset_fill_value(properties.get(), memory_type.get(), &fill) < 0) fail("fill value");
  const H5Handle access = chunk_cache_properties(chunk_rows * H5Tget_size(file_type.get()));
  Table table;
  table.dataset = H5Handle(
      H5Dcreate2(
          file,
          name,
          file_type.get(),
          space.get(),
          H5P_DEFAULT,
          properties.get(),
          or_default(access)),
      H5Dclose);
  if (!table.dataset.valid()) fail("dataset");
  table.memory_type = std::move(memory_type);
  table.transfer = transfer_properties();
  return table;
}

template <class Row>
void append_rows(
    Table& table, std::span<const Row> rows, const char* name, const std::string& where) {
  if (rows.empty()) return;
  const auto fail = [&] {
    throw IoError(where + ": cannot append to /" + name + " (" + detail::take_hdf5_error() + ")");
  };
  const hsize_t start = table.rows;
  const hsize_t count = rows.size();
  const hsize_t size = start + count;
  if (H5Dset_extent(table.dataset.get(), &size) < 0) fail();
  H5Handle file_space(H5Dget_space(table.dataset.get()), H5Sclose);
  H5Handle memory_space(H5Screate_simple(1, &count, nullptr), H5Sclose);
  if (!file_space.valid() || !memory_space.valid() ||
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &start, nullptr, &count, nullptr) < 0 ||
      H5Dwrite(
          table.dataset.get(),
          table.memory_type.get(),
          memory_space.get(),
          file_space.get(),
          or_default(table.transfer),
          rows.data()) < 0) {
    fail();
  }
  table.rows = size;
}

detail::FrameDisk to_disk(const FrameRow& row) {
  detail::FrameDisk d{};
  d.sample = row.sample;
  d.kind = static_cast<std::uint8_t>(row.kind);
  d.t0 = row.t0;
  d.t1 = row.t1;
#define SKELCD_COPY_COUNTER(name, meaning) d.name = row.counters.name;
  SKELCD_COUNTERS(SKELCD_COPY_COUNTER)
#undef SKELCD_COPY_COUNTER
#define SKELCD_COPY_STAGE(name, meaning) d.name = row.times.name;
  SKELCD_STAGE_TIMES(SKELCD_COPY_STAGE)
#undef SKELCD_COPY_STAGE
  d.total_us = row.total_us;
  return d;
}

void write_parts(hid_t file, const std::vector<std::string>& names, const std::string& where) {
  const auto type = detail::vlen_string_type();
  const hsize_t count = names.size();
  H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
  H5Handle dataset(
      H5Dcreate2(
          file, detail::kPartsPath, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose);
  std::vector<const char*> pointers;
  pointers.reserve(names.size());
  for (const auto& name : names) pointers.push_back(name.c_str());
  const H5Handle transfer = transfer_properties();
  if (!space.valid() || !dataset.valid() ||
      (count > 0 &&
       H5Dwrite(
           dataset.get(), type.get(), H5S_ALL, H5S_ALL, or_default(transfer), pointers.data()) <
           0)) {
    throw IoError(where + ": cannot write /parts (" + detail::take_hdf5_error() + ")");
  }
}

template <class T>
void write_column(
    hid_t group,
    const char* name,
    hid_t type,
    const std::vector<T>& values,
    const std::string& where) {
  const hsize_t count = values.size();
  H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
  H5Handle dataset(
      H5Dcreate2(group, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  const H5Handle transfer = transfer_properties();
  if (!space.valid() || !dataset.valid() ||
      (count > 0 &&
       H5Dwrite(dataset.get(), type, H5S_ALL, H5S_ALL, or_default(transfer), values.data()) < 0)) {
    throw IoError(
        where + ": cannot write /routes/" + name + " (" + detail::take_hdf5_error() + ")");
  }
}

// /routes: one row per connected component, as columns (component, part, closed, triangles,
// method), written only when there are routes.
void write_routes(hid_t file, const std::vector<LogRoute>& routes, const std::string& where) {
  if (routes.empty()) return;
  H5Handle group(
      H5Gcreate2(file, detail::kRoutesPath, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!group.valid()) {
    throw IoError(where + ": cannot create /routes (" + detail::take_hdf5_error() + ")");
  }
  std::vector<std::int32_t> component, part, triangles;
  std::vector<std::uint8_t> closed;
  std::vector<const char*> method;
  for (const auto& r : routes) {
    component.push_back(r.component);
    part.push_back(r.part);
    closed.push_back(r.closed ? 1 : 0);
    triangles.push_back(r.triangles);
    method.push_back(r.method.c_str());
  }
  write_column(group.get(), "component", H5T_NATIVE_INT32, component, where);
  write_column(group.get(), "part", H5T_NATIVE_INT32, part, where);
  write_column(group.get(), "closed", H5T_NATIVE_UINT8, closed, where);
  write_column(group.get(), "triangles", H5T_NATIVE_INT32, triangles, where);
  const auto type = detail::vlen_string_type();
  write_column(group.get(), "method", type.get(), method, where);
}

// /checks (scene logs): one row per check, as string columns. /frame_check: one int32 per /frames
// row, extendible like /frames.
void write_checks(hid_t file, const std::vector<LogCheck>& checks, const std::string& where) {
  if (checks.empty()) return;
  H5Handle group(H5Gcreate2(file, "checks", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!group.valid()) {
    throw IoError(where + ": cannot create /checks (" + detail::take_hdf5_error() + ")");
  }
  const auto type = detail::vlen_string_type();
  const auto column = [&](const char* name, auto member) {
    std::vector<const char*> values;
    for (const auto& c : checks) values.push_back((c.*member).c_str());
    const hsize_t count = values.size();
    H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
    H5Handle dataset(
        H5Dcreate2(
            group.get(), name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
        H5Dclose);
    const H5Handle transfer = transfer_properties();
    if (!space.valid() || !dataset.valid() ||
        H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, or_default(transfer), values.data()) <
            0) {
      throw IoError(
          where + ": cannot write /checks/" + name + " (" + detail::take_hdf5_error() + ")");
    }
  };
  column("name", &LogCheck::name);
  column("object_a", &LogCheck::object_a);
  column("object_b", &LogCheck::object_b);
  column("query", &LogCheck::query);
  column("method", &LogCheck::method);
  column("accuracy", &LogCheck::accuracy);
}

Table create_frame_check_table(hid_t file, const std::string& where) {
  const hsize_t initial = 0;
  const hsize_t unlimited = H5S_UNLIMITED;
  const hsize_t chunk = kFrameChunkRows;
  H5Handle space(H5Screate_simple(1, &initial, &unlimited), H5Sclose);
  H5Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const H5Handle access = chunk_cache_properties(chunk * sizeof(std::int32_t));
  Table table;
  const std::int32_t fill = -1;  // as create_table: an unwritten row reads as -1
  if (space.valid() && properties.valid() && H5Pset_chunk(properties.get(), 1, &chunk) >= 0 &&
      H5Pset_fill_value(properties.get(), H5T_NATIVE_INT32, &fill) >= 0) {
    table.dataset = H5Handle(
        H5Dcreate2(
            file,
            detail::kFrameCheckPath,
            H5T_STD_I32LE,
            space.get(),
            H5P_DEFAULT,
            properties.get(),
            or_default(access)),
        H5Dclose);
  }
  if (!table.dataset.valid()) {
    throw IoError(where + ": cannot create /frame_check (" + detail::take_hdf5_error() + ")");
  }
  table.memory_type = H5Handle(H5Tcopy(H5T_NATIVE_INT32), H5Tclose);
  table.transfer = transfer_properties();
  return table;
}

void write_header(hid_t file, const LogHeader& h) {
  using detail::write_attribute;
  write_attribute(file, "format", std::string(kLogFormatName));
  write_attribute(file, "format_version", static_cast<std::int64_t>(h.format_version));
  write_attribute(file, "skelcd_version", h.skelcd_version);
  write_attribute(file, "command_line", h.command_line);
  write_attribute(file, "input_path", h.input_path);
  write_attribute(file, "input_hash", h.input_hash);
  write_attribute(file, "clip", h.clip);
  write_attribute(file, "method", h.method);
  write_attribute(file, "accuracy", h.accuracy);
  write_attribute(file, "query", h.query);
  write_attribute(file, "fps", h.fps);
  write_attribute(file, "min_separation", h.min_separation);
  if (h.gamma) write_attribute(file, "gamma", *h.gamma);
  if (h.theta) write_attribute(file, "theta", *h.theta);
  if (h.seed) write_attribute(file, "seed", *h.seed);
  if (!h.segmentation.empty()) write_attribute(file, "segmentation", h.segmentation);
  write_attribute(file, "start_time", h.start_time);
  write_attribute(file, "first_sample", static_cast<std::int64_t>(h.first_sample));
  write_attribute(file, "last_sample", static_cast<std::int64_t>(h.last_sample));
  write_attribute(file, "planned_rows", h.planned_rows);
  write_attribute(file, "num_vertices", h.num_vertices);
  write_attribute(file, "num_triangles", h.num_triangles);
  // Events (docs/events.md): present exactly when the findings are labelled.
  if (!h.baseline.empty()) {
    write_attribute(file, "baseline", h.baseline);
    write_attribute(file, "baseline_slack", static_cast<std::int64_t>(h.baseline_slack));
    if (!h.allow.empty()) write_attribute(file, "allow", h.allow);
    write_attribute(
        file, "allow_adjacent_bones", static_cast<std::int64_t>(h.allow_adjacent_bones));
  }
  write_attribute(file, "complete", static_cast<std::int64_t>(0));
}

void refuse_to_clobber(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) return;
  if (!std::filesystem::is_regular_file(status)) {
    throw IoError(path.string() + ": exists and is not a regular file; refusing to overwrite it");
  }
  if (std::filesystem::file_size(path, ec) == 0 && !ec) return;
  if (!is_skelcd_log(path)) {
    throw IoError(path.string() + ": exists and is not a skelcd log; refusing to overwrite it");
  }
}

}  // namespace

struct LogWriter::Impl {
  std::filesystem::path path;
  std::string where;  // path as text, for messages
  H5Handle file;
  Table frames;
  Table contacts;
  Table dcd_pairs;
  Table frame_checks;  // scene logs only
  Table checksums;
  /// A row's findings are converted for the file and appended this many at a time, so that the
  /// writer never holds a copy of them all (the cloth-ball step's 113,854 contacts: 6.4 MB, at
  /// the moment the check's memory peaked; 0.46 MB now).
  static constexpr std::size_t kRowsPerAppend = 8192;
  std::vector<detail::ContactDisk> contact_rows;  // the block being appended
  std::vector<detail::DcdPairDisk> pair_rows;
  std::vector<std::int32_t> pending_checks;  // /frame_check rows since the last checksum row
  std::int64_t events_rows = 0;              // rows of /events (written once, at the end)
  bool events_written = false;
  bool finished = false;

  /// Flushes the rows appended so far, then records their checksums in /checksums and flushes
  /// again: a checksum row on disk always follows the rows it covers, so a run killed between
  /// the two flushes leaves unchecked rows, never a false mismatch.
  /// `contacts_crc` and `pairs_crc`: the CRCs of the frame's /contacts and /dcd_pairs rows.
  void flush_with_checksums(
      const detail::FrameDisk& frame, std::uint32_t contacts_crc, std::uint32_t pairs_crc) {
    flush();
    detail::ChecksumDisk row = checksum_row();
    row.frames_crc = detail::rows_crc(0, frames.memory_type.get(), &frame, 1, sizeof frame);
    row.contacts_crc = contacts_crc;
    row.dcd_pairs_crc = pairs_crc;
    if (frame_checks.dataset.valid()) {
      row.frame_check_crc = detail::rows_crc(
          0,
          frame_checks.memory_type.get(),
          pending_checks.data(),
          pending_checks.size(),
          sizeof(std::int32_t));
    }
    pending_checks.clear();
    append_checksum_row(row);
  }

  /// A checksum row at the tables' current ends, every CRC 0 (no rows since the previous one).
  detail::ChecksumDisk checksum_row() const {
    detail::ChecksumDisk row{};
    row.frames_end = static_cast<std::int64_t>(frames.rows);
    row.contacts_end = static_cast<std::int64_t>(contacts.rows);
    row.dcd_pairs_end = static_cast<std::int64_t>(dcd_pairs.rows);
    row.frame_check_end = static_cast<std::int64_t>(frame_checks.rows);
    row.events_end = events_rows;
    return row;
  }

  void append_checksum_row(detail::ChecksumDisk& row) {
    row.self_crc = detail::checksum_row_crc(row);
    append_rows(
        checksums, std::span<const detail::ChecksumDisk>(&row, 1), detail::kChecksumsPath, where);
    flush();
  }

  /// /events, /event_parts and /event_bones, written once, then their checksum row.
  void write_events(const std::vector<EventRecord>& records) {
    std::vector<detail::EventDisk> events;
    std::vector<detail::EventPartDisk> parts;
    std::vector<detail::EventBoneDisk> bones;
    for (const auto& e : records) {
      events.push_back(detail::EventDisk{
          .id = e.id,
          .first_sample = e.first_sample,
          .last_sample = e.last_sample,
          .t_first = e.t_first,
          .t_last = e.t_last,
          .t_first_contact = e.t_first_contact.value_or(std::numeric_limits<double>::quiet_NaN()),
          .peak_pairs = e.peak_pairs,
          .peak_sample = e.peak_sample,
          .dcd_pairs = e.dcd_pairs,
          .ccd_contacts = e.ccd_contacts,
          .depth = e.depth,
          .merged_into = e.merged_into,
      });
      for (const auto part : e.parts) parts.push_back({e.id, part});
      // The names stay owned by `records`; HDF5 only reads them.
      for (const auto& bone : e.bones) bones.push_back({e.id, const_cast<char*>(bone.c_str())});
    }
    write_fixed_table(detail::kEventsPath, detail::event_memory_type(), events);
    write_fixed_table(detail::kEventPartsPath, detail::event_part_memory_type(), parts);
    write_fixed_table(detail::kEventBonesPath, detail::event_bone_memory_type(), bones);
    flush();
    events_rows = static_cast<std::int64_t>(events.size());
    detail::ChecksumDisk row = checksum_row();
    row.events_crc = detail::events_crc(events, parts, bones);
    append_checksum_row(row);
  }

  /// A table of fixed length (not extendible): written once.
  template <class Row>
  void write_fixed_table(
      const char* name, const H5Handle& memory_type, const std::vector<Row>& rows) {
    const auto file_type = detail::packed_copy(memory_type.get());
    const hsize_t count = rows.size();
    H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
    H5Handle dataset(
        space.valid() ? H5Dcreate2(
                            file.get(),
                            name,
                            file_type.get(),
                            space.get(),
                            H5P_DEFAULT,
                            H5P_DEFAULT,
                            H5P_DEFAULT)
                      : H5I_INVALID_HID,
        H5Dclose);
    const H5Handle transfer = transfer_properties();
    if (!dataset.valid() || (count > 0 && H5Dwrite(
                                              dataset.get(),
                                              memory_type.get(),
                                              H5S_ALL,
                                              H5S_ALL,
                                              or_default(transfer),
                                              rows.data()) < 0)) {
      throw IoError(where + ": cannot write /" + name + " (" + detail::take_hdf5_error() + ")");
    }
  }

  /// Appends `rows` to `table` kRowsPerAppend at a time, each converted by `to_disk` into
  /// `buffer`; returns their CRC (rows_crc, from 0).
  template <class Disk, class Row, class ToDisk>
  std::uint32_t append_in_blocks(
      Table& table,
      const std::vector<Row>& rows,
      std::vector<Disk>& buffer,
      const char* name,
      const ToDisk& to_disk) {
    std::uint32_t crc = 0;
    for (std::size_t first = 0; first < rows.size(); first += kRowsPerAppend) {
      const std::size_t end = std::min(rows.size(), first + kRowsPerAppend);
      buffer.clear();
      for (std::size_t i = first; i < end; ++i) buffer.push_back(to_disk(rows[i]));
      append_rows(table, std::span<const Disk>(buffer), name, where);
      crc = detail::rows_crc(
          crc, table.memory_type.get(), buffer.data(), buffer.size(), sizeof(Disk));
    }
    return crc;
  }

  /// Appends the report's contacts, DCD pairs and /frames row, then flushes with checksums.
  void write(const FrameReport& report) {
    // Contacts and pairs first, the /frames row last: a row on disk implies its findings are too.
    const std::uint32_t contacts_crc = append_in_blocks(
        contacts, report.contacts, contact_rows, detail::kContactsPath, [](const ContactRow& c) {
          return detail::ContactDisk{
              .frame = c.frame,
              .kind = static_cast<std::uint8_t>(c.kind),
              .a_part = c.a.part,
              .a_index = c.a.index,
              .a_side = c.a.side,
              .b_part = c.b.part,
              .b_index = c.b.index,
              .b_side = c.b.side,
              .toi_lower = c.toi_lower,
              .toi_upper = c.toi_upper,
              .label = c.label,
          };
        });
    const std::uint32_t pairs_crc = append_in_blocks(
        dcd_pairs, report.dcd_pairs, pair_rows, detail::kDcdPairsPath, [](const DcdPairRow& p) {
          return detail::DcdPairDisk{
              .frame = p.frame,
              .a_part = p.a.part,
              .a_index = p.a.index,
              .b_part = p.b.part,
              .b_index = p.b.index,
              .label = p.label,
          };
        });
    const detail::FrameDisk row = to_disk(report.row);
    append_rows(frames, std::span<const detail::FrameDisk>(&row, 1), detail::kFramesPath, where);
    flush_with_checksums(row, contacts_crc, pairs_crc);
  }

  /// After a failed write: nothing more is written; the file is closed and read back, and one
  /// line says why it failed and what it holds.
  [[noreturn]] void fail(const std::string& error) {
    finished = true;
    close();
    detail::clear_hdf5_error();
    const int err = detail::hdf5_errno(error);
    std::string message = where + ": ";
    if (err == ENOSPC || err == EDQUOT) {
      message += std::string(err == ENOSPC ? "the disk is full" : "the disk quota is exceeded") +
                 " (" + std::strerror(err) + ")";
    } else {
      message += "cannot write the log (" +
                 (error.rfind(where + ": ", 0) == 0 ? error.substr(where.size() + 2) : error) + ")";
    }
    try {
      const auto log = read_log(path, ReadLogOptions{.findings = false});
      if (log.frames.empty()) {
        message += "; no row was written";
      } else {
        message += "; its first " + std::to_string(log.frames.size()) + " rows (samples " +
                   std::to_string(log.frames.front().sample) + " to " +
                   std::to_string(log.frames.back().sample) + ") were written and are readable";
      }
    } catch (const std::exception&) {
      message += "; what was written cannot be read back";
    }
    throw IoError(message);
  }

  void flush() {
    if (H5Fflush(file.get(), H5F_SCOPE_LOCAL) < 0) {
      throw IoError(where + ": cannot flush (" + detail::take_hdf5_error() + ")");
    }
  }

  /// Closes every dataset, then the file; false if any close failed.
  bool close() {
    bool ok = frames.dataset.reset();
    ok = contacts.dataset.reset() && ok;
    ok = dcd_pairs.dataset.reset() && ok;
    ok = checksums.dataset.reset() && ok;
    if (frame_checks.dataset.valid()) ok = frame_checks.dataset.reset() && ok;
    return file.reset() && ok;
  }
};

LogWriter::LogWriter(const std::filesystem::path& path, const LogHeader& header)
    : impl_(std::make_unique<Impl>()) {
  detail::silence_hdf5_errors();
  impl_->path = path;
  impl_->where = path.string();
  refuse_to_clobber(path);
  // The default (oldest compatible) file format: a file left open by a killed process carries no
  // "open for writing" flag, so h5dump and h5py read it as it is. No file lock either, so that
  // `skelcd inspect` can look at the rows flushed so far while the run goes on.
  H5Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!access.valid() || H5Pset_file_locking(access.get(), false, true) < 0) {
    throw IoError(impl_->where + ": cannot set up file access (" + detail::take_hdf5_error() + ")");
  }
  impl_->file =
      H5Handle(H5Fcreate(impl_->where.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()), H5Fclose);
  if (!impl_->file.valid()) {
    throw IoError(impl_->where + ": cannot create log (" + detail::take_hdf5_error() + ")");
  }
  // A log that cannot be set up completely is removed rather than left half-made.
  try {
    const hid_t file = impl_->file.get();
    try {
      write_header(file, header);
    } catch (const IoError& e) {
      throw IoError(impl_->where + ": " + e.what());
    }
    write_parts(file, header.part_names, impl_->where);
    write_routes(file, header.routes, impl_->where);
    write_checks(file, header.checks, impl_->where);
    if (!header.checks.empty()) impl_->frame_checks = create_frame_check_table(file, impl_->where);
    impl_->frames = create_table(
        file,
        detail::kFramesPath,
        detail::frame_memory_type(),
        kFrameChunkRows,
        unwritten<detail::FrameDisk>(),
        impl_->where);
    impl_->contacts = create_table(
        file,
        detail::kContactsPath,
        detail::contact_memory_type(),
        kPairChunkRows,
        unwritten<detail::ContactDisk>(),
        impl_->where);
    impl_->dcd_pairs = create_table(
        file,
        detail::kDcdPairsPath,
        detail::dcd_pair_memory_type(),
        kPairChunkRows,
        unwritten<detail::DcdPairDisk>(),
        impl_->where);
    impl_->checksums = create_table(
        file,
        detail::kChecksumsPath,
        detail::checksum_memory_type(),
        kFrameChunkRows,
        unwritten<detail::ChecksumDisk>(),
        impl_->where);
    if (H5Fflush(file, H5F_SCOPE_LOCAL) < 0) {
      throw IoError(impl_->where + ": cannot flush (" + detail::take_hdf5_error() + ")");
    }
  } catch (...) {
    impl_->close();
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    throw;
  }
}

LogWriter::~LogWriter() {
  if (impl_ && !impl_->finished) impl_->close();
}

void LogWriter::append(const FrameReport& report) {
  if (impl_->finished) throw IoError(impl_->where + ": log already finished");
  try {
    impl_->write(report);
  } catch (const IoError& e) {
    impl_->fail(e.what());
  }
}

void LogWriter::append(const FrameReport& report, std::int32_t check) {
  if (impl_->finished) throw IoError(impl_->where + ": log already finished");
  if (!impl_->frame_checks.dataset.valid()) {
    throw IoError(impl_->where + ": append with a check to a log without /checks");
  }
  // The row's check first: a /frames row on disk implies its /frame_check entry is too.
  try {
    append_rows(
        impl_->frame_checks,
        std::span<const std::int32_t>(&check, 1),
        detail::kFrameCheckPath,
        impl_->where);
    impl_->pending_checks.push_back(check);
    impl_->write(report);
  } catch (const IoError& e) {
    impl_->fail(e.what());
  }
}

void LogWriter::write_events(const std::vector<EventRecord>& events) {
  if (impl_->finished) throw IoError(impl_->where + ": log already finished");
  if (impl_->events_written) throw IoError(impl_->where + ": events already written");
  impl_->events_written = true;
  try {
    impl_->write_events(events);
  } catch (const IoError& e) {
    impl_->fail(e.what());
  }
}

void LogWriter::finish() {
  if (impl_->finished) return;
  impl_->finished = true;
  const std::int64_t one = 1;
  H5Handle attribute(H5Aopen(impl_->file.get(), "complete", H5P_DEFAULT), H5Aclose);
  const bool marked = attribute.valid() && H5Awrite(attribute.get(), H5T_NATIVE_INT64, &one) >= 0;
  attribute.reset();
  const bool closed = impl_->close();
  if (!marked || !closed) {
    throw IoError(impl_->where + ": cannot finish log (" + detail::take_hdf5_error() + ")");
  }
}

const std::filesystem::path& LogWriter::path() const { return impl_->path; }

std::int64_t LogWriter::rows_written() const {
  return static_cast<std::int64_t>(impl_->frames.rows);
}

bool is_skelcd_log(const std::filesystem::path& path) {
  detail::silence_hdf5_errors();
  const std::string name = path.string();
  if (H5Fis_hdf5(name.c_str()) <= 0) {
    detail::clear_hdf5_error();
    return false;
  }
  H5Handle file(H5Fopen(name.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.valid()) {
    detail::clear_hdf5_error();
    return false;
  }
  try {
    const auto format = detail::read_string_attribute(file.get(), "format");
    return format && *format == kLogFormatName;
  } catch (const IoError&) {
    return false;
  }
}

}  // namespace skelcd::tools
