#pragma once
// Internal to tools/io/log/: RAII handles over the HDF5 C API and the on-disk layout of the log's
// tables. Included only by tools/io/log/*.cpp — HDF5 stays out of every public header.

#include <hdf5.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "culling/frame_result.hpp"  // SKELCD_COUNTERS, SKELCD_STAGE_TIMES

namespace skelcd::tools::detail {

/// Owns one HDF5 identifier and closes it with the matching H5?close.
class H5Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Handle() = default;
  H5Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~H5Handle() { reset(); }
  H5Handle(H5Handle&& other) noexcept
      : id_(std::exchange(other.id_, H5I_INVALID_HID)), closer_(other.closer_) {}
  H5Handle& operator=(H5Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      closer_ = other.closer_;
    }
    return *this;
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;

  [[nodiscard]] hid_t get() const { return id_; }
  [[nodiscard]] bool valid() const { return id_ >= 0; }
  /// Closes now; returns false when the close itself failed.
  bool reset() {
    bool ok = true;
    if (id_ >= 0 && closer_ != nullptr) ok = closer_(id_) >= 0;
    id_ = H5I_INVALID_HID;
    return ok;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

/// Turns HDF5's automatic error-stack printing off for this process (our messages replace it).
void silence_hdf5_errors();

/// The most specific message on HDF5's error stack ("" when empty), on one line; clears the stack.
/// A system error HDF5 quotes becomes its text and number: "No space left on device (errno 28)".
[[nodiscard]] std::string take_hdf5_error();
/// The errno that take_hdf5_error() quoted in `message`, 0 when none.
[[nodiscard]] int hdf5_errno(const std::string& message);
/// Clears HDF5's error stack (after an expected failure).
void clear_hdf5_error();

/// On-disk rows, flat so that h5py and h5dump show one named column per field.
struct FrameDisk {
  std::int32_t sample;
  std::uint8_t kind;  // QueryKind
  double t0;
  double t1;
#define SKELCD_DISK_COUNTER(name, meaning) std::int64_t name;
  SKELCD_COUNTERS(SKELCD_DISK_COUNTER)
#undef SKELCD_DISK_COUNTER
#define SKELCD_DISK_STAGE(name, meaning) double name;
  SKELCD_STAGE_TIMES(SKELCD_DISK_STAGE)
#undef SKELCD_DISK_STAGE
  double total_us;
};

struct ContactDisk {
  std::int32_t frame;
  std::uint8_t kind;  // CcdContact::Kind
  std::int32_t a_part;
  std::int32_t a_index;
  std::int8_t a_side;
  std::int32_t b_part;
  std::int32_t b_index;
  std::int8_t b_side;
  double toi_lower;
  double toi_upper;
  std::int32_t label;  // event id, kLabelBaseline, kLabelAllowed or kLabelNone (frame_report.hpp)
};

struct DcdPairDisk {
  std::int32_t frame;
  std::int32_t a_part;
  std::int32_t a_index;
  std::int32_t b_part;
  std::int32_t b_index;
  std::int32_t label;
};

/// One row of /events (EventRecord without its lists: those are /event_parts and /event_bones).
struct EventDisk {
  std::int32_t id;
  std::int32_t first_sample;
  std::int32_t last_sample;
  double t_first;
  double t_last;
  double t_first_contact;  // NaN when absent
  std::int64_t peak_pairs;
  std::int32_t peak_sample;
  std::int64_t dcd_pairs;
  std::int64_t ccd_contacts;
  double depth;
  std::int32_t merged_into;
};

/// One row of /event_parts: part `part` (index into /parts) takes part in event `event` (its id).
struct EventPartDisk {
  std::int32_t event;
  std::int32_t part;
};

/// One row of /event_bones: bone `bone` drives triangles of event `event`, rows of one event in
/// its order (most triangles first).
struct EventBoneDisk {
  std::int32_t event;
  char* bone;  // variable-length UTF-8 string
};

/// One row of /checksums: CRC-32 (zlib) of the rows each table gained since the previous row, up to
/// the row counts `*_end` (exclusive), written after those rows were flushed. `self_crc` covers
/// the other fields, so a damaged checksum row is told from a damaged table.
struct ChecksumDisk {
  std::int64_t frames_end;
  std::int64_t contacts_end;
  std::int64_t dcd_pairs_end;
  std::int64_t frame_check_end;
  std::int64_t events_end;  // rows of /events (0 until the events are written, at the end)
  std::uint32_t frames_crc;
  std::uint32_t contacts_crc;
  std::uint32_t dcd_pairs_crc;
  std::uint32_t frame_check_crc;
  std::uint32_t events_crc;  // /events, /event_parts and /event_bones, see events_crc()
  std::uint32_t self_crc;
};

/// CRC-32 of `count` rows at `rows` (laid out as `memory_type` says, `row_size` bytes apart),
/// continuing from `crc`. Only the bytes of the type's fields count, never the padding between
/// them, so the writer's rows and the reader's (read through the same memory type) agree.
[[nodiscard]] std::uint32_t rows_crc(
    std::uint32_t crc,
    hid_t memory_type,
    const void* rows,
    std::size_t count,
    std::size_t row_size);
/// `self_crc` of a checksum row: the CRC of its other fields.
[[nodiscard]] std::uint32_t checksum_row_crc(const ChecksumDisk& row);
/// CRC-32 of bytes as they are (a row read in the file's own packed type, whose fields are in
/// offset order without padding: the same CRC rows_crc() gives the row in memory).
[[nodiscard]] std::uint32_t bytes_crc(std::uint32_t crc, const void* bytes, std::size_t size);
/// Continues `crc` over /event_bones rows: each row's `event` (4 bytes, little-endian), then the
/// bone name's UTF-8 bytes (no terminator).
[[nodiscard]] std::uint32_t bone_rows_crc(
    std::uint32_t crc, const std::vector<EventBoneDisk>& bones);
/// The events' CRC: /events rows, then /event_parts rows (as rows_crc), then bone_rows_crc().
[[nodiscard]] std::uint32_t events_crc(
    const std::vector<EventDisk>& events,
    const std::vector<EventPartDisk>& parts,
    const std::vector<EventBoneDisk>& bones);

/// Compound types describing the structs above in memory (fields matched by name on read, so a
/// reader of this version reads files that carry extra columns).
[[nodiscard]] H5Handle frame_memory_type();
[[nodiscard]] H5Handle contact_memory_type();
[[nodiscard]] H5Handle dcd_pair_memory_type();
[[nodiscard]] H5Handle checksum_memory_type();
[[nodiscard]] H5Handle event_memory_type();
[[nodiscard]] H5Handle event_part_memory_type();
[[nodiscard]] H5Handle event_bone_memory_type();
/// The members of `memory_type` that the stored type `file_type` also has (matched by name), at
/// their memory offsets: reading through it leaves a column the file lacks as it was in the
/// buffer. `missing` (optional) receives the names of the members left out.
[[nodiscard]] H5Handle common_members(
    hid_t memory_type, hid_t file_type, std::vector<std::string>* missing = nullptr);
/// The same, packed (no padding), as stored in the file.
[[nodiscard]] H5Handle packed_copy(hid_t memory_type);
/// Variable-length UTF-8 string type.
[[nodiscard]] H5Handle vlen_string_type();

/// Scalar attributes on `location` (a file or object). Writers replace nothing: the attribute
/// must not exist yet. @throws IoError naming the attribute.
void write_attribute(hid_t location, const char* name, const std::string& value);
void write_attribute(hid_t location, const char* name, double value);
void write_attribute(hid_t location, const char* name, std::int64_t value);
/// A 1-D attribute of variable-length UTF-8 strings (`values` must not be empty).
void write_attribute(hid_t location, const char* name, const std::vector<std::string>& values);

/// Reads a scalar string attribute (variable or fixed length); std::nullopt when it is absent.
/// @throws IoError naming the attribute when it exists but is not a scalar string.
[[nodiscard]] std::optional<std::string> read_string_attribute(hid_t location, const char* name);
/// Reads a scalar numeric attribute converted to double / int64; std::nullopt when absent.
/// @throws IoError naming the attribute when it exists but is not a scalar number.
[[nodiscard]] std::optional<double> read_double_attribute(hid_t location, const char* name);
[[nodiscard]] std::optional<std::int64_t> read_int_attribute(hid_t location, const char* name);
/// Reads a 1-D (or scalar) string attribute; std::nullopt when absent.
/// @throws IoError naming the attribute when it exists but does not hold strings.
[[nodiscard]] std::optional<std::vector<std::string>> read_string_list_attribute(
    hid_t location, const char* name);

inline constexpr const char* kFramesPath = "frames";
inline constexpr const char* kContactsPath = "contacts";
inline constexpr const char* kDcdPairsPath = "dcd_pairs";
inline constexpr const char* kPartsPath = "parts";
inline constexpr const char* kRoutesPath = "routes";
inline constexpr const char* kChecksumsPath = "checksums";
inline constexpr const char* kFrameCheckPath = "frame_check";
inline constexpr const char* kEventsPath = "events";
inline constexpr const char* kEventPartsPath = "event_parts";
inline constexpr const char* kEventBonesPath = "event_bones";

}  // namespace skelcd::tools::detail
