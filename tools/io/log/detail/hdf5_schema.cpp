#include "tools/io/log/detail/hdf5_schema.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "culling/frame_result.hpp"
#include "skinning/errors.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools::detail {
namespace {

// libhdf5 closes whatever is still open from an atexit handler. After a close that failed on a
// full disk (the file's metadata could not be flushed), that handler dereferences the half-closed
// file and the process dies with SIGSEGV after printing its one-line error. Every file we open
// is closed explicitly, so the handler is not installed: this runs before main, before the
// library is initialised (H5dont_atexit has no effect later).
[[maybe_unused]] const herr_t kNoHdf5Atexit = H5dont_atexit();

herr_t keep_innermost(unsigned n, const H5E_error2_t* error, void* client) {
  // Walked upward: entry 0 is the innermost (most specific) error.
  if (n == 0 && error != nullptr && error->desc != nullptr) {
    *static_cast<std::string*>(client) = error->desc;
  }
  return 0;
}

void check(herr_t status, const char* what) {
  if (status < 0) throw IoError(std::string("HDF5: cannot build type (") + what + ")");
}

H5Handle make_enum(std::initializer_list<std::pair<const char*, std::uint8_t>> values) {
  H5Handle type(H5Tenum_create(H5T_NATIVE_UINT8), H5Tclose);
  if (!type.valid()) throw IoError("HDF5: cannot create enum type");
  for (const auto& [name, value] : values) {
    check(H5Tenum_insert(type.get(), name, &value), name);
  }
  return type;
}

H5Handle kind_enum() {
  return make_enum(
      {{"dcd", static_cast<std::uint8_t>(QueryKind::dcd)},
       {"ccd", static_cast<std::uint8_t>(QueryKind::ccd)}});
}

H5Handle contact_kind_enum() {
  return make_enum(
      {{"vf", static_cast<std::uint8_t>(culling::CcdContact::Kind::vf)},
       {"ee", static_cast<std::uint8_t>(culling::CcdContact::Kind::ee)}});
}

H5Handle compound(std::size_t size) {
  H5Handle type(H5Tcreate(H5T_COMPOUND, size), H5Tclose);
  if (!type.valid()) throw IoError("HDF5: cannot create compound type");
  return type;
}

void insert(const H5Handle& type, const char* name, std::size_t offset, hid_t member) {
  check(H5Tinsert(type.get(), name, offset, member), name);
}

}  // namespace

void silence_hdf5_errors() {
  // A thread-safe HDF5 keeps one error stack, and one printing setting, per thread.
  thread_local bool silenced = false;
  if (!silenced) H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  silenced = true;
}

std::string take_hdf5_error() {
  std::string message;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keep_innermost, &message);
  H5Eclear2(H5E_DEFAULT);
  // The system's reason when HDF5 quotes one ("…, errno = 28, error message = 'No space left on
  // device', …"): HDF5's own text spans lines and quotes buffer addresses.
  if (const auto at = message.find("errno = "); at != std::string::npos) {
    const int err = std::atoi(message.c_str() + at + 8);
    if (err > 0) return std::string(std::strerror(err)) + " (errno " + std::to_string(err) + ")";
  }
  std::replace(message.begin(), message.end(), '\n', ' ');
  return message;
}

int hdf5_errno(const std::string& message) {
  const auto at = message.find("(errno ");
  return at == std::string::npos ? 0 : std::atoi(message.c_str() + at + 7);
}

void clear_hdf5_error() { H5Eclear2(H5E_DEFAULT); }

#define SKELCD_FIELD(type, Struct, field, member) \
  insert(type, #field, offsetof(Struct, field), member)

H5Handle frame_memory_type() {
  auto type = compound(sizeof(FrameDisk));
  const auto kind = kind_enum();
  SKELCD_FIELD(type, FrameDisk, sample, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, FrameDisk, t0, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, FrameDisk, t1, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, FrameDisk, kind, kind.get());
#define SKELCD_COUNTER_FIELD(name, meaning) SKELCD_FIELD(type, FrameDisk, name, H5T_NATIVE_INT64);
  SKELCD_COUNTERS(SKELCD_COUNTER_FIELD)
#undef SKELCD_COUNTER_FIELD
#define SKELCD_STAGE_FIELD(name, meaning) SKELCD_FIELD(type, FrameDisk, name, H5T_NATIVE_DOUBLE);
  SKELCD_STAGE_TIMES(SKELCD_STAGE_FIELD)
#undef SKELCD_STAGE_FIELD
  SKELCD_FIELD(type, FrameDisk, total_us, H5T_NATIVE_DOUBLE);
  return type;
}

H5Handle contact_memory_type() {
  auto type = compound(sizeof(ContactDisk));
  const auto kind = contact_kind_enum();
  SKELCD_FIELD(type, ContactDisk, frame, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, ContactDisk, kind, kind.get());
  SKELCD_FIELD(type, ContactDisk, a_part, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, ContactDisk, a_index, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, ContactDisk, a_side, H5T_NATIVE_INT8);
  SKELCD_FIELD(type, ContactDisk, b_part, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, ContactDisk, b_index, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, ContactDisk, b_side, H5T_NATIVE_INT8);
  SKELCD_FIELD(type, ContactDisk, toi_lower, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, ContactDisk, toi_upper, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, ContactDisk, label, H5T_NATIVE_INT32);
  return type;
}

H5Handle dcd_pair_memory_type() {
  auto type = compound(sizeof(DcdPairDisk));
  SKELCD_FIELD(type, DcdPairDisk, frame, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, DcdPairDisk, a_part, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, DcdPairDisk, a_index, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, DcdPairDisk, b_part, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, DcdPairDisk, b_index, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, DcdPairDisk, label, H5T_NATIVE_INT32);
  return type;
}

H5Handle checksum_memory_type() {
  auto type = compound(sizeof(ChecksumDisk));
  SKELCD_FIELD(type, ChecksumDisk, frames_end, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, ChecksumDisk, contacts_end, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, ChecksumDisk, dcd_pairs_end, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, ChecksumDisk, frame_check_end, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, ChecksumDisk, events_end, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, ChecksumDisk, frames_crc, H5T_NATIVE_UINT32);
  SKELCD_FIELD(type, ChecksumDisk, contacts_crc, H5T_NATIVE_UINT32);
  SKELCD_FIELD(type, ChecksumDisk, dcd_pairs_crc, H5T_NATIVE_UINT32);
  SKELCD_FIELD(type, ChecksumDisk, frame_check_crc, H5T_NATIVE_UINT32);
  SKELCD_FIELD(type, ChecksumDisk, events_crc, H5T_NATIVE_UINT32);
  SKELCD_FIELD(type, ChecksumDisk, self_crc, H5T_NATIVE_UINT32);
  return type;
}

H5Handle event_memory_type() {
  auto type = compound(sizeof(EventDisk));
  SKELCD_FIELD(type, EventDisk, id, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventDisk, first_sample, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventDisk, last_sample, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventDisk, t_first, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, EventDisk, t_last, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, EventDisk, t_first_contact, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, EventDisk, peak_pairs, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, EventDisk, peak_sample, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventDisk, dcd_pairs, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, EventDisk, ccd_contacts, H5T_NATIVE_INT64);
  SKELCD_FIELD(type, EventDisk, depth, H5T_NATIVE_DOUBLE);
  SKELCD_FIELD(type, EventDisk, merged_into, H5T_NATIVE_INT32);
  return type;
}

H5Handle event_part_memory_type() {
  auto type = compound(sizeof(EventPartDisk));
  SKELCD_FIELD(type, EventPartDisk, event, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventPartDisk, part, H5T_NATIVE_INT32);
  return type;
}

H5Handle event_bone_memory_type() {
  auto type = compound(sizeof(EventBoneDisk));
  const auto text = vlen_string_type();
  SKELCD_FIELD(type, EventBoneDisk, event, H5T_NATIVE_INT32);
  SKELCD_FIELD(type, EventBoneDisk, bone, text.get());
  return type;
}

#undef SKELCD_FIELD

std::uint32_t rows_crc(
    std::uint32_t crc,
    hid_t memory_type,
    const void* rows,
    std::size_t count,
    std::size_t row_size) {
  // (offset, size) of every field; a scalar type is one field of its own size.
  std::vector<std::pair<std::size_t, std::size_t>> fields;
  if (H5Tget_class(memory_type) == H5T_COMPOUND) {
    const int members = H5Tget_nmembers(memory_type);
    for (int m = 0; m < members; ++m) {
      H5Handle member(H5Tget_member_type(memory_type, static_cast<unsigned>(m)), H5Tclose);
      fields.emplace_back(
          H5Tget_member_offset(memory_type, static_cast<unsigned>(m)), H5Tget_size(member.get()));
    }
  } else {
    fields.emplace_back(0, H5Tget_size(memory_type));
  }
  // By offset: HDF5 reorders a compound type's members in place once it has converted through it,
  // so member indices differ between a type that has been used and a fresh one.
  std::sort(fields.begin(), fields.end());
  const auto* bytes = static_cast<const unsigned char*>(rows);
  uLong value = crc;
  for (std::size_t r = 0; r < count; ++r) {
    for (const auto& [offset, size] : fields)
      value = crc32(value, bytes + r * row_size + offset, static_cast<uInt>(size));
  }
  return static_cast<std::uint32_t>(value);
}

std::uint32_t bytes_crc(std::uint32_t crc, const void* bytes, std::size_t size) {
  return static_cast<std::uint32_t>(
      crc32(crc, static_cast<const unsigned char*>(bytes), static_cast<uInt>(size)));
}

std::uint32_t events_crc(
    const std::vector<EventDisk>& events,
    const std::vector<EventPartDisk>& parts,
    const std::vector<EventBoneDisk>& bones) {
  const auto event_type = event_memory_type();
  const auto part_type = event_part_memory_type();
  std::uint32_t crc =
      rows_crc(0, event_type.get(), events.data(), events.size(), sizeof(EventDisk));
  crc = rows_crc(crc, part_type.get(), parts.data(), parts.size(), sizeof(EventPartDisk));
  return bone_rows_crc(crc, bones);
}

std::uint32_t bone_rows_crc(std::uint32_t crc, const std::vector<EventBoneDisk>& bones) {
  for (const auto& b : bones) {
    const std::uint32_t v = static_cast<std::uint32_t>(b.event);
    const unsigned char le[4] = {
        static_cast<unsigned char>(v),
        static_cast<unsigned char>(v >> 8),
        static_cast<unsigned char>(v >> 16),
        static_cast<unsigned char>(v >> 24)};
    crc = bytes_crc(crc, le, sizeof le);
    if (b.bone != nullptr) crc = bytes_crc(crc, b.bone, std::strlen(b.bone));
  }
  return crc;
}

H5Handle common_members(hid_t memory_type, hid_t file_type, std::vector<std::string>* missing) {
  auto type = compound(H5Tget_size(memory_type));
  const int members = H5Tget_nmembers(memory_type);
  for (int m = 0; m < members; ++m) {
    const auto index = static_cast<unsigned>(m);
    char* name = H5Tget_member_name(memory_type, index);
    if (name == nullptr) throw IoError("HDF5: cannot read a member name");
    const std::string text = name;
    H5free_memory(name);
    if (H5Tget_member_index(file_type, text.c_str()) < 0) {
      clear_hdf5_error();  // an absent name pushes an error
      if (missing != nullptr) missing->push_back(text);
      continue;
    }
    H5Handle member(H5Tget_member_type(memory_type, index), H5Tclose);
    insert(type, text.c_str(), H5Tget_member_offset(memory_type, index), member.get());
  }
  return type;
}

std::uint32_t checksum_row_crc(const ChecksumDisk& row) {
  ChecksumDisk copy = row;
  copy.self_crc = 0;
  const auto type = checksum_memory_type();
  return rows_crc(0, type.get(), &copy, 1, sizeof copy);
}

H5Handle packed_copy(hid_t memory_type) {
  H5Handle type(H5Tcopy(memory_type), H5Tclose);
  if (!type.valid()) throw IoError("HDF5: cannot copy type");
  check(H5Tpack(type.get()), "pack");
  return type;
}

H5Handle vlen_string_type() {
  H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.valid()) throw IoError("HDF5: cannot copy string type");
  check(H5Tset_size(type.get(), H5T_VARIABLE), "string size");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
  return type;
}

namespace {

H5Handle scalar_space() {
  H5Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  if (!space.valid()) throw IoError("HDF5: cannot create a scalar dataspace");
  return space;
}

void write_scalar(
    hid_t location, const char* name, hid_t file_type, hid_t memory_type, const void* value) {
  const auto space = scalar_space();
  H5Handle attribute(
      H5Acreate2(location, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attribute.valid() || H5Awrite(attribute.get(), memory_type, value) < 0) {
    throw IoError(std::string("cannot write attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
}

/// Opens attribute `name` if present and checks that it holds one value of class `type_class`.
std::optional<H5Handle> open_scalar(
    hid_t location, const char* name, bool (*accepts)(H5T_class_t)) {
  const htri_t exists = H5Aexists(location, name);
  if (exists < 0) {
    throw IoError(
        std::string("cannot look up attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  if (exists == 0) return std::nullopt;
  H5Handle attribute(H5Aopen(location, name, H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) {
    throw IoError(std::string("cannot open attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  H5Handle space(H5Aget_space(attribute.get()), H5Sclose);
  H5Handle type(H5Aget_type(attribute.get()), H5Tclose);
  if (!space.valid() || !type.valid() || H5Sget_simple_extent_npoints(space.get()) != 1 ||
      !accepts(H5Tget_class(type.get()))) {
    clear_hdf5_error();
    throw IoError(std::string("attribute '") + name + "' has an unexpected type or shape");
  }
  return attribute;
}

bool is_string_class(H5T_class_t c) { return c == H5T_STRING; }
bool is_number_class(H5T_class_t c) { return c == H5T_INTEGER || c == H5T_FLOAT; }

}  // namespace

void write_attribute(hid_t location, const char* name, const std::string& value) {
  const auto type = vlen_string_type();
  const char* text = value.c_str();
  write_scalar(location, name, type.get(), type.get(), &text);
}

void write_attribute(hid_t location, const char* name, double value) {
  write_scalar(location, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void write_attribute(hid_t location, const char* name, std::int64_t value) {
  write_scalar(location, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

void write_attribute(hid_t location, const char* name, const std::vector<std::string>& values) {
  const auto type = vlen_string_type();
  const hsize_t count = values.size();
  H5Handle space(H5Screate_simple(1, &count, nullptr), H5Sclose);
  std::vector<const char*> pointers;
  pointers.reserve(values.size());
  for (const auto& v : values) pointers.push_back(v.c_str());
  H5Handle attribute(
      space.valid() ? H5Acreate2(location, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT)
                    : H5I_INVALID_HID,
      H5Aclose);
  if (!attribute.valid() || H5Awrite(attribute.get(), type.get(), pointers.data()) < 0) {
    throw IoError(std::string("cannot write attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
}

std::optional<std::vector<std::string>> read_string_list_attribute(
    hid_t location, const char* name) {
  const htri_t exists = H5Aexists(location, name);
  if (exists < 0) {
    throw IoError(
        std::string("cannot look up attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  if (exists == 0) return std::nullopt;
  H5Handle attribute(H5Aopen(location, name, H5P_DEFAULT), H5Aclose);
  H5Handle space(attribute.valid() ? H5Aget_space(attribute.get()) : H5I_INVALID_HID, H5Sclose);
  H5Handle stored(attribute.valid() ? H5Aget_type(attribute.get()) : H5I_INVALID_HID, H5Tclose);
  if (!space.valid() || !stored.valid() || H5Tget_class(stored.get()) != H5T_STRING ||
      H5Sget_simple_extent_ndims(space.get()) > 1) {
    clear_hdf5_error();
    throw IoError(std::string("attribute '") + name + "' is not a list of strings");
  }
  if (H5Tis_variable_str(stored.get()) <= 0 || H5Sget_simple_extent_ndims(space.get()) == 0) {
    clear_hdf5_error();
    // A single (or fixed-length) string: read as one.
    if (H5Sget_simple_extent_ndims(space.get()) == 0) {
      return std::vector<std::string>{read_string_attribute(location, name).value_or("")};
    }
    throw IoError(std::string("attribute '") + name + "' is not a list of variable-length strings");
  }
  const hssize_t count = H5Sget_simple_extent_npoints(space.get());
  if (count < 0 || count > (1 << 20)) {
    throw IoError(std::string("attribute '") + name + "' has an unexpected shape");
  }
  const auto type = vlen_string_type();
  std::vector<char*> pointers(static_cast<std::size_t>(count), nullptr);
  if (count > 0 && H5Aread(attribute.get(), type.get(), pointers.data()) < 0) {
    throw IoError(std::string("cannot read attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  std::vector<std::string> values;
  values.reserve(pointers.size());
  for (const char* p : pointers) values.emplace_back(p != nullptr ? p : "");
  if (count > 0) H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, pointers.data());
  return values;
}

std::optional<std::string> read_string_attribute(hid_t location, const char* name) {
  auto attribute = open_scalar(location, name, is_string_class);
  if (!attribute) return std::nullopt;
  H5Handle stored(H5Aget_type(attribute->get()), H5Tclose);
  const htri_t variable = H5Tis_variable_str(stored.get());
  if (variable > 0) {
    const auto type = vlen_string_type();
    char* text = nullptr;
    if (H5Aread(attribute->get(), type.get(), &text) < 0) {
      throw IoError(
          std::string("cannot read attribute '") + name + "' (" + take_hdf5_error() + ")");
    }
    std::string value = text != nullptr ? text : "";
    H5free_memory(text);
    return value;
  }
  // Fixed-length string: read it as stored (size bytes, maybe without a terminator).
  const std::size_t size = H5Tget_size(stored.get());
  std::string value(size, '\0');
  H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), size);
  if (size == 0 || H5Aread(attribute->get(), type.get(), value.data()) < 0) {
    throw IoError(std::string("cannot read attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  value.resize(value.find('\0') == std::string::npos ? size : value.find('\0'));
  return value;
}

std::optional<double> read_double_attribute(hid_t location, const char* name) {
  auto attribute = open_scalar(location, name, is_number_class);
  if (!attribute) return std::nullopt;
  double value = 0;
  if (H5Aread(attribute->get(), H5T_NATIVE_DOUBLE, &value) < 0) {
    throw IoError(std::string("cannot read attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  return value;
}

std::optional<std::int64_t> read_int_attribute(hid_t location, const char* name) {
  auto attribute = open_scalar(location, name, is_number_class);
  if (!attribute) return std::nullopt;
  std::int64_t value = 0;
  if (H5Aread(attribute->get(), H5T_NATIVE_INT64, &value) < 0) {
    throw IoError(std::string("cannot read attribute '") + name + "' (" + take_hdf5_error() + ")");
  }
  return value;
}

}  // namespace skelcd::tools::detail
