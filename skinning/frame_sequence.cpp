#include "skinning/frame_sequence.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string_view>
#include <type_traits>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"

namespace skelcd::skinning {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// The file's bytes into `bytes` (its capacity reused: a sequence's frames are read one after
/// another into one buffer).
void read_bytes(const fs::path& file, std::string& bytes) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) throw IoError(file.string() + ": cannot open frame file");
  // A file of known size is read into a string of that size (one copy, not a stream's two: a
  // long sequence's frames are read again for each sample).
  const std::streamoff size = in.tellg();
  if (size >= 0) {
    bytes.resize(static_cast<std::size_t>(size));
    in.seekg(0);
    in.read(bytes.data(), size);
    if (!in || in.gcount() != size) throw IoError(file.string() + ": cannot read frame file");
    return;
  }
  in.clear();
  in.seekg(0);
  std::ostringstream stream;
  stream << in.rdbuf();
  if (in.bad()) throw IoError(file.string() + ": cannot read frame file");
  bytes = stream.str();
}

std::string read_bytes(const fs::path& file) {
  std::string bytes;
  read_bytes(file, bytes);
  return bytes;
}

/// What a reader collects before finish() checks it: coordinates, face corners, face sizes.
/// Held by the caller, so that a sequence's frames reuse its storage (a cloth-ball frame's is
/// about 4 MB: fresh pages for each frame cost more than decoding it).
struct FrameScratch {
  std::vector<double> xyz;
  std::vector<std::int64_t> corners;
  std::vector<std::size_t> face_sizes;

  void clear() {
    xyz.clear();
    corners.clear();
    face_sizes.clear();
  }
};

/// Builds the frame from what a reader collected — polygons split into fans, indices and
/// finiteness checked — into `m` (its storage reused when the sizes are the same).
void finish(const fs::path& file, const FrameScratch& scratch, FrameMesh& m) {
  const std::vector<double>& xyz = scratch.xyz;
  const std::vector<std::int64_t>& corners = scratch.corners;
  const std::vector<std::size_t>& face_sizes = scratch.face_sizes;
  const auto nv = static_cast<Eigen::Index>(xyz.size() / 3);
  m.positions.resize(nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double c = xyz[static_cast<std::size_t>(3 * v + k)];
      if (!std::isfinite(c)) {
        throw InvalidInput(file.string() + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
      }
      m.positions(v, k) = c;
    }
  }
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < face_sizes.size(); ++f) {
    if (face_sizes[f] < 3) {
      throw InvalidInput(file.string() + ": face " + std::to_string(f) + " has " +
                         std::to_string(face_sizes[f]) + " corners (at least 3 needed)");
    }
    triangles += face_sizes[f] - 2;
  }
  m.triangles.resize(static_cast<Eigen::Index>(triangles), 3);
  std::size_t at = 0;
  Eigen::Index t = 0;
  for (std::size_t f = 0; f < face_sizes.size(); ++f) {
    for (std::size_t k = 0; k < face_sizes[f]; ++k) {
      const std::int64_t i = corners[at + k];
      if (i < 0 || i >= nv) {
        throw InvalidInput(file.string() + ": face " + std::to_string(f) + " has vertex index " +
                           std::to_string(i) + " out of range [0, " + std::to_string(nv) + ")");
      }
    }
    // Fan (0, k, k + 1), the way a convex polygon is usually split.
    for (std::size_t k = 1; k + 1 < face_sizes[f]; ++k, ++t) {
      m.triangles(t, 0) = static_cast<std::int32_t>(corners[at]);
      m.triangles(t, 1) = static_cast<std::int32_t>(corners[at + k]);
      m.triangles(t, 2) = static_cast<std::int32_t>(corners[at + k + 1]);
    }
    at += face_sizes[f];
  }
}

// ---------------------------------------------------------------------------------------------
// OBJ: `v x y z [w | r g b]` and `f a b c ...` with `a`, `a/t`, `a//n`, `a/t/n`; negative indices
// count back from the last vertex read.
void read_obj(
    const fs::path& file, const std::string& text, FrameScratch& scratch, FrameMesh& out) {
  scratch.clear();
  std::vector<double>& xyz = scratch.xyz;
  std::vector<std::int64_t>& corners = scratch.corners;
  std::vector<std::size_t>& face_sizes = scratch.face_sizes;
  std::size_t line_number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_number;
    const auto where = [&] { return file.string() + ":" + std::to_string(line_number) + ": "; };
    std::size_t i = 0;
    const auto skip_space = [&] {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    };
    const auto token = [&] {
      skip_space();
      const std::size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
      return line.substr(start, i - start);
    };
    const std::string_view keyword = token();
    if (keyword == "v") {
      for (int k = 0; k < 3; ++k) {
        const std::string_view t = token();
        double value = 0.0;
        const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
        if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) {
          throw IoError(where() + "malformed vertex coordinate '" + std::string(t) + "'");
        }
        xyz.push_back(value);
      }
    } else if (keyword == "f") {
      std::size_t n = 0;
      const auto vertices_so_far = static_cast<std::int64_t>(xyz.size() / 3);
      for (std::string_view t = token(); !t.empty(); t = token()) {
        const std::string_view first = t.substr(0, t.find('/'));
        std::int64_t index = 0;
        const auto [ptr, ec] = std::from_chars(first.data(), first.data() + first.size(), index);
        if (first.empty() || ec != std::errc() || ptr != first.data() + first.size() || index == 0) {
          throw IoError(where() + "malformed face corner '" + std::string(t) + "'");
        }
        corners.push_back(index > 0 ? index - 1 : vertices_so_far + index);
        ++n;
      }
      face_sizes.push_back(n);
    }
  }
  finish(file, scratch, out);
}

// ---------------------------------------------------------------------------------------------
// PLY.
enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };
enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8: return 1;
    case PlyType::kInt16:
    case PlyType::kUint16: return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 0;
}

bool parse_type(const std::string& s, PlyType& t) {
  static const std::pair<const char*, PlyType> kTypes[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},   {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16}, {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [name, type] : kTypes) {
    if (s == name) {
      t = type;
      return true;
    }
  }
  return false;
}

// Reads binary or ASCII values of the body, one at a time.
class PlyReader {
 public:
  PlyReader(const fs::path& file, const std::string& bytes, std::size_t offset, PlyFormat format)
      : file_(file), bytes_(bytes), pos_(offset), format_(format) {}

  double read(PlyType type) {
    if (format_ == PlyFormat::kAscii) return read_ascii();
    const std::size_t n = type_size(type);
    if (pos_ + n > bytes_.size()) throw IoError(file_.string() + ": PLY body ends early (truncated file)");
    const double v = decode(type, bytes_.data() + pos_, swapped(format_));
    pos_ += n;
    return v;
  }

  /// Where the body's next value starts; skip() moves past n bytes of it (n fits: checked by the
  /// caller).
  [[nodiscard]] std::size_t pos() const { return pos_; }
  void skip(std::size_t n) { pos_ += n; }

  /// A binary body whose byte order is not this machine's.
  [[nodiscard]] static bool swapped(PlyFormat format) {
    return (format == PlyFormat::kBinaryBig) != (std::endian::native == std::endian::big);
  }

  /// An integer type (every value a whole number well inside int64).
  [[nodiscard]] static bool integral(PlyType type) {
    return type != PlyType::kFloat32 && type != PlyType::kFloat64;
  }

  /// decode() of an integral type, as the integer itself.
  [[nodiscard]] static std::int64_t decode_integer(PlyType type, const char* at, bool swap) {
    switch (type) {
      case PlyType::kInt8:
        return load<std::int8_t>(at, swap);
      case PlyType::kUint8:
        return load<std::uint8_t>(at, swap);
      case PlyType::kInt16:
        return load<std::int16_t>(at, swap);
      case PlyType::kUint16:
        return load<std::uint16_t>(at, swap);
      case PlyType::kInt32:
        return load<std::int32_t>(at, swap);
      case PlyType::kUint32:
        return load<std::uint32_t>(at, swap);
      case PlyType::kFloat32:
      case PlyType::kFloat64:
        break;
    }
    return 0;
  }

  /// The binary value of `type` at `at` (type_size(type) bytes), in the file's byte order.
  [[nodiscard]] static double decode(PlyType type, const char* at, bool swap) {
    if (type == PlyType::kFloat32) return static_cast<double>(load<float>(at, swap));
    if (type == PlyType::kFloat64) return load<double>(at, swap);
    // Every integer of these types converts to double exactly.
    return static_cast<double>(decode_integer(type, at, swap));
  }

 private:
  /// The T stored at `at`, its bytes reversed first when `swap`: one byte-swap instruction
  /// (a big-endian file's values were reversed byte by byte, most of a cloth-ball frame's read).
  template <typename T>
  static T load(const char* at, bool swap) {
    if constexpr (sizeof(T) == 1) {
      T v;
      std::memcpy(&v, at, 1);
      return v;
    } else {
      using Bits = std::conditional_t<
          sizeof(T) == 2,
          std::uint16_t,
          std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
      Bits bits;
      std::memcpy(&bits, at, sizeof bits);
      if (swap) {
        if constexpr (sizeof(T) == 2) bits = __builtin_bswap16(bits);
        if constexpr (sizeof(T) == 4) bits = __builtin_bswap32(bits);
        if constexpr (sizeof(T) == 8) bits = __builtin_bswap64(bits);
      }
      return std::bit_cast<T>(bits);
    }
  }

  double read_ascii() {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    const std::size_t start = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (start == pos_) throw IoError(file_.string() + ": PLY body ends early (truncated file)");
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(bytes_.data() + start, bytes_.data() + pos_, v);
    if (ec != std::errc() || ptr != bytes_.data() + pos_) {
      throw IoError(file_.string() + ": malformed PLY value '" + bytes_.substr(start, pos_ - start) + "'");
    }
    return v;
  }

  const fs::path& file_;
  const std::string& bytes_;
  std::size_t pos_;
  PlyFormat format_;
};

void read_ply(
    const fs::path& file, const std::string& bytes, FrameScratch& scratch, FrameMesh& out) {
  // Header: lines up to and including "end_header".
  std::size_t pos = 0;
  std::vector<PlyElement> elements;
  PlyFormat format = PlyFormat::kAscii;
  bool have_format = false;
  bool first = true;
  while (true) {
    const std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) throw IoError(file.string() + ": PLY header has no end_header");
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (first) {
      if (keyword != "ply") throw IoError(file.string() + ": not a PLY file (no 'ply' magic)");
      first = false;
      continue;
    }
    if (keyword == "format") {
      std::string f;
      words >> f;
      if (f == "ascii") format = PlyFormat::kAscii;
      else if (f == "binary_little_endian") format = PlyFormat::kBinaryLittle;
      else if (f == "binary_big_endian") format = PlyFormat::kBinaryBig;
      else throw IoError(file.string() + ": unknown PLY format '" + f + "'");
      have_format = true;
    } else if (keyword == "element") {
      PlyElement e;
      long long count = -1;
      words >> e.name >> count;
      if (!words || count < 0) throw IoError(file.string() + ": malformed PLY element line '" + line + "'");
      e.count = static_cast<std::size_t>(count);
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) throw IoError(file.string() + ": PLY property before any element");
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type;
        std::string item_type;
        words >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!parse_type(count_type, p.count_type) || !parse_type(item_type, p.type)) {
          throw IoError(file.string() + ": unknown PLY type in '" + line + "'");
        }
      } else {
        words >> p.name;
        if (!parse_type(type, p.type)) throw IoError(file.string() + ": unknown PLY type in '" + line + "'");
      }
      if (p.name.empty()) throw IoError(file.string() + ": malformed PLY property line '" + line + "'");
      elements.back().properties.push_back(p);
    } else if (keyword == "end_header") {
      break;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      throw IoError(file.string() + ": unexpected PLY header line '" + line + "'");
    }
  }
  if (!have_format) throw IoError(file.string() + ": PLY header has no format line");

  // Body: every element in header order; keep vertex x, y, z and the face index lists.
  PlyReader reader(file, bytes, pos, format);
  // A list's length as read: a list item takes at least one byte, so a longer list is damage (and
  // beyond 2^64 the conversion would be undefined).
  const auto list_length = [&](double n) {
    if (!(n >= 0) || n != std::floor(n) || n > static_cast<double>(bytes.size())) {
      throw IoError(file.string() + ": malformed PLY list length");
    }
    return static_cast<std::size_t>(n);
  };
  // A face index as read: whole, and inside int64 (beyond it the conversion is undefined;
  // finish() reports the index as out of range).
  const auto face_index = [&](double index) {
    if (index != std::floor(index))
      throw IoError(file.string() + ": PLY face index is not an integer");
    if (!(std::abs(index) < 0x1p62)) {
      throw InvalidInput(
          file.string() + ": PLY face index " + std::to_string(index) + " out of range");
    }
    return static_cast<std::int64_t>(index);
  };
  scratch.clear();
  std::vector<double>& xyz = scratch.xyz;
  std::vector<std::int64_t>& corners = scratch.corners;
  std::vector<std::size_t>& face_sizes = scratch.face_sizes;
  bool have_vertices = false;
  for (const PlyElement& e : elements) {
    int ix = -1, iy = -1, iz = -1, ilist = -1;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      const int kk = static_cast<int>(k);
      if (e.name == "vertex" && !p.is_list) {
        if (p.name == "x") ix = kk;
        if (p.name == "y") iy = kk;
        if (p.name == "z") iz = kk;
      }
      if (e.name == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) ilist = kk;
    }
    if (e.name == "vertex") {
      if (ix < 0 || iy < 0 || iz < 0) throw IoError(file.string() + ": PLY vertex element lacks x, y or z");
      have_vertices = true;
    }
    if (e.name == "face" && ilist < 0) throw IoError(file.string() + ": PLY face element lacks vertex_indices");
    // Every item of an element with properties takes at least one byte of the body, so a count
    // beyond the bytes after the header is a damaged header: refused before reserving or looping
    // for it (found by fuzz/fuzz_frame_mesh). Items without properties hold nothing to read.
    if (e.properties.empty()) continue;
    if (e.count > bytes.size() - pos) {
      throw IoError(
          file.string() + ": PLY element '" + e.name + "' declares " + std::to_string(e.count) +
          " items, more than the " + std::to_string(bytes.size() - pos) +
          " bytes after the header hold (truncated or damaged file)");
    }
    if (e.name == "vertex") xyz.reserve(3 * e.count);
    // Binary elements whose items have one size (scalar properties only: a vertex record) are
    // decoded at their offsets when the whole element fits in the bytes left — the values the
    // loop below reads, without asking each one's type and place again (with the face lists
    // below, a cloth-ball frame read 1.3x faster); otherwise the loop reads them and reports where
    // the bytes end.
    if (format != PlyFormat::kAscii) {
      std::size_t record = 0;
      bool scalars = true;
      std::size_t offset[3] = {0, 0, 0};
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        scalars = scalars && !p.is_list;
        const int kk = static_cast<int>(k);
        if (kk == ix) offset[0] = record;
        if (kk == iy) offset[1] = record;
        if (kk == iz) offset[2] = record;
        record += type_size(p.type);
      }
      const std::size_t left = bytes.size() - reader.pos();
      if (scalars && e.count <= left / record) {
        if (e.name == "vertex") {
          const bool swap = PlyReader::swapped(format);
          const PlyType types[3] = {
              e.properties[static_cast<std::size_t>(ix)].type,
              e.properties[static_cast<std::size_t>(iy)].type,
              e.properties[static_cast<std::size_t>(iz)].type};
          const char* item = bytes.data() + reader.pos();
          const std::size_t start = xyz.size();
          xyz.resize(start + 3 * e.count);
          for (std::size_t i = 0; i < e.count; ++i, item += record) {
            for (std::size_t c = 0; c < 3; ++c) {
              xyz[start + 3 * i + c] = PlyReader::decode(types[c], item + offset[c], swap);
            }
          }
        }
        reader.skip(e.count * record);  // another element of scalars: read and dropped
        continue;
      }
      // A face element of the index list alone: each item's count and indices decoded in place,
      // with the loop's checks in the loop's order (the same values and the same errors).
      if (ilist == 0 && e.properties.size() == 1) {
        const PlyProperty& p = e.properties[0];
        const bool swap = PlyReader::swapped(format);
        const std::size_t count_size = type_size(p.count_type);
        const std::size_t index_size = type_size(p.type);
        const std::size_t end = bytes.size();
        std::size_t at = reader.pos();
        const auto truncated = [&] {
          return IoError(file.string() + ": PLY body ends early (truncated file)");
        };
        // Integer counts and indices are whole and far inside int64: the checks for those hold.
        const bool integer_count = PlyReader::integral(p.count_type);
        const bool integer_index = PlyReader::integral(p.type);
        for (std::size_t item = 0; item < e.count; ++item) {
          if (at + count_size > end) throw truncated();
          // An integer below 2^53 converts to double exactly: list_length's checks on it.
          const std::size_t count =
              integer_count ? list_length(static_cast<double>(
                                  PlyReader::decode_integer(p.count_type, bytes.data() + at, swap)))
                            : list_length(PlyReader::decode(p.count_type, bytes.data() + at, swap));
          at += count_size;
          for (std::size_t c = 0; c < count; ++c) {
            if (at + index_size > end) throw truncated();
            corners.push_back(
                integer_index ? PlyReader::decode_integer(p.type, bytes.data() + at, swap)
                              : face_index(PlyReader::decode(p.type, bytes.data() + at, swap)));
            at += index_size;
          }
          face_sizes.push_back(count);
        }
        reader.skip(at - reader.pos());
        continue;
      }
    }
    for (std::size_t item = 0; item < e.count; ++item) {
      double v[3] = {0, 0, 0};
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        const int kk = static_cast<int>(k);
        if (p.is_list) {
          const std::size_t count = list_length(reader.read(p.count_type));
          for (std::size_t c = 0; c < count; ++c) {
            const double index = reader.read(p.type);
            if (kk == ilist) corners.push_back(face_index(index));
          }
          if (kk == ilist) face_sizes.push_back(count);
        } else {
          const double value = reader.read(p.type);
          if (kk == ix) v[0] = value;
          if (kk == iy) v[1] = value;
          if (kk == iz) v[2] = value;
        }
      }
      if (e.name == "vertex") xyz.insert(xyz.end(), v, v + 3);
    }
  }
  if (!have_vertices) throw IoError(file.string() + ": PLY file has no vertex element");
  finish(file, scratch, out);
}

}  // namespace

namespace {

/// True for an OBJ frame file, false for a PLY one; refuses any other (before its bytes are read).
bool is_obj(const fs::path& file) {
  const std::string ext = lower(file.extension().string());
  if (ext != ".obj" && ext != ".ply") {
    throw IoError(file.string() + ": a frame file must be .obj or .ply");
  }
  return ext == ".obj";
}

/// read_frame_mesh of the file's bytes, read already, into `out` with `scratch`'s storage.
void parse_frame_mesh(
    const fs::path& file, const std::string& bytes, FrameScratch& scratch, FrameMesh& out) {
  if (is_obj(file)) {
    read_obj(file, bytes, scratch, out);
  } else {
    read_ply(file, bytes, scratch, out);
  }
}

/// read_frame_mesh of the file's bytes, read already.
FrameMesh parse_frame_mesh(const fs::path& file, const std::string& bytes) {
  FrameScratch scratch;
  FrameMesh out;
  parse_frame_mesh(file, bytes, scratch, out);
  return out;
}

/// What tells a frame file's bytes from other bytes (within one process).
std::size_t checksum(const std::string& bytes) { return std::hash<std::string_view>{}(bytes); }

}  // namespace

FrameMesh read_frame_mesh(const fs::path& file) {
  (void)is_obj(file);  // the extension refused before the file is read
  return parse_frame_mesh(file, read_bytes(file));
}

bool natural_less(std::string_view a, std::string_view b) {
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      // Compare digit runs by value: skip leading zeros, then longer is larger, then lexically.
      std::size_t ei = i;
      std::size_t ej = j;
      while (ei < a.size() && std::isdigit(static_cast<unsigned char>(a[ei]))) ++ei;
      while (ej < b.size() && std::isdigit(static_cast<unsigned char>(b[ej]))) ++ej;
      std::size_t si = i;
      std::size_t sj = j;
      while (si + 1 < ei && a[si] == '0') ++si;
      while (sj + 1 < ej && b[sj] == '0') ++sj;
      const std::string_view ra = a.substr(si, ei - si);
      const std::string_view rb = b.substr(sj, ej - sj);
      if (ra.size() != rb.size()) return ra.size() < rb.size();
      if (ra != rb) return ra < rb;
      i = ei;
      j = ej;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;  // equal by value ("007" vs "7"): plain order decides
}

std::vector<fs::path> list_frame_files(const fs::path& spec) {
  std::vector<fs::path> files;
  const std::string text = spec.string();
  std::error_code ec;
  if (text.find_first_of("*?[") == std::string::npos) {
    if (!fs::is_directory(spec, ec)) throw IoError(text + ": no such folder");
    for (const auto& entry : fs::directory_iterator(spec, ec)) {
      const std::string ext = lower(entry.path().extension().string());
      if (entry.is_regular_file() && (ext == ".obj" || ext == ".ply")) files.push_back(entry.path());
    }
    if (ec) throw IoError(text + ": cannot list folder: " + ec.message());
  } else {
    const fs::path dir = spec.has_parent_path() ? spec.parent_path() : fs::path(".");
    const std::string pattern = spec.filename().string();
    if (dir.string().find_first_of("*?[") != std::string::npos) {
      throw InvalidInput(text + ": glob characters are allowed in the file name only");
    }
    if (!fs::is_directory(dir, ec)) throw IoError(text + ": no such folder " + dir.string());
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (entry.is_regular_file() && fnmatch(pattern.c_str(), entry.path().filename().c_str(), 0) == 0) {
        files.push_back(entry.path());
      }
    }
    if (ec) throw IoError(text + ": cannot list folder: " + ec.message());
  }
  if (files.empty()) throw InvalidInput(text + ": no OBJ or PLY frame files");
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
    return natural_less(a.filename().string(), b.filename().string());
  });
  return files;
}

FrameSequenceMotion::FrameSequenceMotion(
    std::vector<fs::path> files,
    const FrameSequenceOptions& options,
    std::string name)
    : rate_hz_(options.rate_hz) {
  if (!(std::isfinite(options.rate_hz) && options.rate_hz > 0)) {
    throw InvalidInput("frame sequence: rate " + std::to_string(options.rate_hz) + " Hz is not positive and finite");
  }
  if (files.empty()) throw InvalidInput("frame sequence: no frame files");
  auto data = std::make_shared<Data>();
  data->name = name.empty() ? files.front().parent_path().filename().string() : std::move(name);
  data->checksums.reserve(files.size());
  Triangles triangles;
  Positions first;
  bool keep = true;  // decided once the first frame's size is known
  // The bytes, the reader's scratch and the frame are reused from file to file: a frame that is
  // not kept leaves its storage to the next.
  std::string bytes;
  FrameScratch scratch;
  FrameMesh frame;
  for (std::size_t i = 0; i < files.size(); ++i) {
    read_bytes(files[i], bytes);
    data->checksums.push_back(checksum(bytes));
    parse_frame_mesh(files[i], bytes, scratch, frame);
    if (i == 0) {
      triangles = std::move(frame.triangles);
      const double frame_bytes = 24.0 * static_cast<double>(frame.positions.rows());
      keep = frame_bytes * static_cast<double>(files.size()) <=
             static_cast<double>(options.kept_bytes_per_triangle) *
                 static_cast<double>(triangles.rows());
      if (keep) {
        data->frames.reserve(files.size());
        first = frame.positions;  // also kept as frame 0, below
      } else {
        first = std::move(frame.positions);
      }
    } else {
      // Identical topology: the same vertex count and the same triangles, index for index.
      const std::string where = files[i].string() + ": frame " + std::to_string(i);
      if (frame.positions.rows() != first.rows()) {
        throw InvalidInput(
            where + " has " + std::to_string(frame.positions.rows()) + " vertices, frame 0 (" +
            files[0].string() + ") has " + std::to_string(first.rows()));
      }
      if (frame.triangles.rows() != triangles.rows()) {
        throw InvalidInput(where + " has " + std::to_string(frame.triangles.rows()) + " triangles, frame 0 (" +
                           files[0].string() + ") has " + std::to_string(triangles.rows()));
      }
      for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
        if (frame.triangles.row(f) != triangles.row(f)) {
          throw InvalidInput(where + ": triangle " + std::to_string(f) + " differs from frame 0's (" +
                             files[0].string() + ")");
        }
      }
    }
    if (keep) data->frames.push_back(std::move(frame.positions));
  }
  Mesh& mesh = data->mesh;
  mesh.rest_positions = std::move(first);
  mesh.triangles = std::move(triangles);
  label_one_part_in_file_order(mesh, data->name);
  if (options.order == MeshOrder::spatial) {
    const MeshPermutation order = spatial_order(mesh.rest_positions, mesh.triangles);
    if (!order.faces.empty()) {
      // The mesh renumbered (its file indices moved with each element), the kept frames gathered.
      mesh = reordered(mesh, order);
      Positions gathered;
      for (Positions& kept : data->frames) {
        gather_rows(kept, order.vertices, gathered);
        std::swap(kept, gathered);
      }
      data->reordered = true;
    }
  }
  validate_mesh(mesh, files[0].string());
  data->files = std::move(files);
  data_ = std::move(data);
}

FrameSequenceMotion::FrameSequenceMotion(std::shared_ptr<const Data> data, double rate_hz)
    : data_(std::move(data)), rate_hz_(rate_hz) {
  if (!(std::isfinite(rate_hz) && rate_hz > 0)) {
    throw InvalidInput(data_->name + ": rate " + std::to_string(rate_hz) + " Hz is not positive and finite");
  }
}

std::unique_ptr<FrameSequenceMotion> FrameSequenceMotion::with_rate(double rate_hz) const {
  return std::unique_ptr<FrameSequenceMotion>(new FrameSequenceMotion(data_, rate_hz));
}

void FrameSequenceMotion::positions(int i, Positions& out) const {
  assert(i >= 0 && i < num_samples());
  const auto k = static_cast<std::size_t>(i);
  if (!data_->frames.empty()) {
    out = data_->frames[k];
    return;
  }
  if (k == 0) {
    out = data_->mesh.rest_positions;
    return;
  }
  // Read again: the same bytes give the same positions (the parse is deterministic); other bytes
  // would give a frame nobody checked.
  const fs::path& file = data_->files[k];
  const std::string bytes = read_bytes(file);
  if (checksum(bytes) != data_->checksums[k]) {
    throw IoError(
        file.string() + ": frame " + std::to_string(i) +
        " changed since the sequence was read (its bytes differ)");
  }
  if (data_->reordered) {
    gather_rows(parse_frame_mesh(file, bytes).positions, data_->mesh.vertex_index_in_part, out);
  } else {
    out = parse_frame_mesh(file, bytes).positions;
  }
}

const Positions* FrameSequenceMotion::held_positions(int i) const {
  assert(i >= 0 && i < num_samples());
  return data_->frames.empty() ? nullptr : &data_->frames[static_cast<std::size_t>(i)];
}

FrameSequenceMotion load_frame_sequence(const fs::path& spec, const FrameSequenceOptions& options) {
  const bool is_glob = spec.string().find_first_of("*?[") != std::string::npos;
  const std::string name = is_glob ? spec.filename().string() : fs::absolute(spec).lexically_normal().filename().string();
  return FrameSequenceMotion(list_frame_files(spec), options, name.empty() ? spec.string() : name);
}

LoadedModel load_frame_sequence_model(const fs::path& spec, const LoadOptions& options) {
  if (!options.trajectory.empty() || !options.srdf.empty() || !options.package_path.empty()) {
    throw InvalidInput(spec.string() + ": a trajectory, SRDF or package path applies to URDF robots only");
  }
  FrameSequenceOptions sequence;
  sequence.order = options.mesh_order;
  auto motion = std::make_shared<const FrameSequenceMotion>(load_frame_sequence(spec, sequence));
  LoadedModel model;
  model.path = spec;
  model.kind = ModelKind::frame_sequence;
  model.mesh = std::shared_ptr<const Mesh>(motion, &motion->mesh());
  const double duration = (motion->num_samples() - 1) / kDefaultFrameRateHz;
  model.clips.push_back(
      {motion->name(),
       duration,
       motion->num_samples() > 1 ? kDefaultFrameRateHz : 0.0,
       kDefaultFrameRateHz,
       FrameRateSource::frame_sequence});
  model.motion_factory = [motion](const MotionRequest& request) -> std::unique_ptr<Motion> {
    if (!request.clip.empty() && request.clip != motion->name()) {
      throw InvalidInput(motion->frame_file(0).parent_path().string() + ": a frame sequence has one clip, '" +
                         motion->name() + "', not '" + request.clip + "'");
    }
    return motion->with_rate(request.rate_hz > 0 ? request.rate_hz : kDefaultFrameRateHz);
  };
  return model;
}

}  // namespace skelcd::skinning
