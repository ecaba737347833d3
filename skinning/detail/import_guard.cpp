#include "skinning/detail/import_guard.hpp"

#include <fcntl.h>
#include <malloc.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "skinning/errors.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define SKELCD_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SKELCD_UNDER_ASAN 1
#endif
#endif

#if defined(SKELCD_UNDER_ASAN)
#include <atomic>

// The sanitizer runtime's allocator hooks (compiler-rt's sanitizer/allocator_interface.h, which
// GCC does not install; its libasan exports the same functions).
extern "C" {
int __sanitizer_install_malloc_and_free_hooks(
    void (*malloc_hook)(const volatile void*, std::size_t),
    void (*free_hook)(const volatile void*));
std::size_t __sanitizer_get_allocated_size(const volatile void* p);
}
#endif

namespace skelcd::skinning::detail {
namespace {

// Exit status of a child that went over its memory limit (reported as such to the parent).
constexpr int kOverMemoryExit = 75;

#if defined(SKELCD_UNDER_ASAN)
// Under AddressSanitizer RLIMIT_AS cannot be used (its shadow memory alone exceeds any limit);
// its allocator hooks count what the child allocates instead.
std::atomic<long long> asan_live_bytes{0};
long long asan_limit_bytes = 0;

void asan_on_malloc(const volatile void*, std::size_t size) {
  if (asan_live_bytes.fetch_add(static_cast<long long>(size)) + static_cast<long long>(size) >
      asan_limit_bytes) {
    _exit(kOverMemoryExit);
  }
}

void asan_on_free(const volatile void* p) {
  asan_live_bytes.fetch_sub(static_cast<long long>(__sanitizer_get_allocated_size(p)));
}
#endif

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return s;
}

std::string mib(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f MiB", bytes / (1024.0 * 1024.0));
  return text;
}

[[noreturn]] void too_many(
    const std::string& file, const std::string& declared, long double need, std::uintmax_t size) {
  char text[64];
  std::snprintf(text, sizeof text, "%.0Lf", need);
  throw InvalidInput(
      file + ": declares " + declared + ", which needs at least " + text +
      " bytes, but the file has " + std::to_string(size));
}

// OFF: an optional magic ("OFF", "COFF", "NOFF", "STOFF", "4OFF", …), then "#vertices #faces
// #edges". A vertex takes at least 6 bytes ("0 0 0\n"), a face at least 4 ("1 0\n").
void check_off(const std::filesystem::path& file, std::uintmax_t size) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> tokens;
  bool magic_seen = false;
  while (tokens.size() < 2 && std::getline(in, line)) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      if (!magic_seen && tokens.empty() && lower(word).find("off") != std::string::npos) {
        magic_seen = true;
        continue;
      }
      tokens.push_back(word);
    }
  }
  if (tokens.size() < 2) return;  // the importer says what is wrong
  const auto count = [](const std::string& t) -> long double {
    if (t.empty() ||
        !std::all_of(t.begin(), t.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
      return -1;
    return std::strtold(t.c_str(), nullptr);
  };
  const long double vertices = count(tokens[0]);
  const long double faces = count(tokens[1]);
  if (vertices < 0 || faces < 0) return;
  const long double need = 6.0L * vertices + 4.0L * faces;
  if (need > static_cast<long double>(size)) {
    too_many(file.string(), tokens[0] + " vertices and " + tokens[1] + " faces", need, size);
  }
}

// PLY: "element NAME COUNT" lines each followed by their properties, up to "end_header". A binary
// element takes at least the sum of its properties' sizes (a list: its count's size); an ASCII
// one at least two bytes per property ("0 ").
void check_ply(const std::filesystem::path& file, std::uintmax_t size) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) return;
  const auto type_size = [](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" ||
        t == "float32")
      return 4;
    if (t == "double" || t == "float64") return 8;
    return 1;  // unknown: the importer says what is wrong; count it as small as can be
  };
  bool binary = false;
  struct Element {
    std::string name;
    std::string count_text;
    long double count = 0;
    long double min_bytes = 0;
  };
  std::vector<Element> elements;
  for (int lines = 0; std::getline(in, line) && lines < 100000; ++lines) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      std::string kind;
      words >> kind;
      binary = kind.rfind("binary", 0) == 0;
    } else if (keyword == "element") {
      Element e;
      words >> e.name >> e.count_text;
      if (e.count_text.empty() ||
          !std::all_of(e.count_text.begin(), e.count_text.end(), [](unsigned char c) {
            return std::isdigit(c) != 0;
          })) {
        return;
      }
      e.count = std::strtold(e.count_text.c_str(), nullptr);
      elements.push_back(e);
    } else if (keyword == "property" && !elements.empty()) {
      std::string type;
      words >> type;
      if (type == "list") words >> type;  // the count's type comes first
      elements.back().min_bytes += binary ? type_size(type) : 2;
    }
  }
  const auto header = static_cast<long double>(
      std::max<std::streamoff>(0, static_cast<std::streamoff>(in.tellg())));
  long double need = header;
  std::string declared;
  for (const auto& e : elements) {
    need += e.count * e.min_bytes;
    if (e.count > 0)
      declared += (declared.empty() ? "" : " and ") + e.count_text + " " + e.name + " elements";
  }
  if (need > static_cast<long double>(size)) too_many(file.string(), declared, need, size);
}

// MD5 mesh (.md5mesh, assimp 5.2's MD5 loader). The loader indexes its arrays with the file's
// numbers unchecked: a vertex's weights (`vert I ( U V ) FIRST COUNT`) beyond the mesh's weights,
// a weight's joint beyond the joints, a triangle's corner beyond the vertices, a triangle that
// `numtris` declares but no `tri` line gives (a null index array) — it reads, and for a joint
// writes, outside its buffers (found by fuzz_assimp_import: fuzz/crashes/assimp/md5mesh_*). Its
// parser also reads past the end of the text when the file stops where a value or a quoted name
// is expected. This walks the text as that parser does (the same section and element splits),
// reads the elements the loader indexes with in their strict form — one assimp would only warn
// about, and read on from wherever it stopped, is refused — and refuses what would send the
// loader outside its arrays. A valid file passes untouched.
class Md5MeshCheck {
 public:
  Md5MeshCheck(std::string file, std::string text)
      : file_(std::move(file)), text_(std::move(text)), b_(text_ + '\0'), n_(text_.size()) {}

  void run() {
    remove_line_comments();
    if (!header()) return;  // not MD5 version 10: assimp refuses it itself
    std::vector<Section> sections;
    while (true) {
      const std::size_t start = pos_;
      sections.emplace_back();
      if (!section(sections.back())) break;
      // A form feed where a section starts: assimp's parser neither reads it nor steps over it,
      // and adds empty sections for ever (until memory runs out).
      if (pos_ == start)
        refuse(
            "MD5 line " + std::to_string(line_of(start)) +
            ": a form feed where a section starts (assimp's MD5 reader would loop for ever)");
    }
    std::uint64_t joints = 0;
    std::vector<Mesh> meshes;
    for (const auto& s : sections) {
      if (s.name == "joints") {
        for (const auto e : s.elements) {
          joint(e);
          ++joints;
        }
      } else if (s.name == "mesh") {
        meshes.push_back(mesh(s));
      }
    }
    for (std::size_t m = 0; m < meshes.size(); ++m) indices(meshes[m], m + 1, joints);
  }

 private:
  struct Section {
    std::string name;
    std::size_t at = 0;
    std::vector<std::size_t> elements;  // offsets of the element texts (ended by '\0' in b_)
  };
  struct Mesh {
    std::size_t line = 0;
    // The array sizes as the parser resizes them, and what the lines give (by index).
    std::uint64_t vertices = 0, triangles = 0, weights = 0;
    std::map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> vertex_weights;
    std::map<std::uint32_t, std::array<std::uint32_t, 3>> corners;
    std::map<std::uint32_t, std::uint32_t> weight_joint;
  };

  static bool space(char c) { return c == ' ' || c == '\t'; }
  static bool line_end(char c) { return c == '\r' || c == '\n' || c == '\0' || c == '\f'; }
  static bool space_or_line_end(char c) { return space(c) || line_end(c); }

  std::size_t line_of(std::size_t offset) const {
    return 1 + static_cast<std::size_t>(std::count(
                   text_.begin(),
                   text_.begin() + static_cast<std::ptrdiff_t>(std::min(offset, n_)),
                   '\n'));
  }

  [[noreturn]] void refuse(const std::string& what) const {
    throw InvalidInput(file_ + ": " + what);
  }

  // The character at `p`; the parser reading beyond the text's terminating NUL is a refusal.
  char at(std::size_t p) const {
    if (p > n_)
      refuse(
          "the MD5 text ends where assimp's MD5 reader expects more (it would read past the end of "
          "the file)");
    return b_[p];
  }

  void skip_spaces(std::size_t& p) const {
    while (space(at(p))) ++p;
  }
  bool skip_spaces_and_line_ends(std::size_t& p) const {
    while (space(at(p)) || at(p) == '\r' || at(p) == '\n') ++p;
    return at(p) != '\0';
  }
  // assimp's TokenMatch: the word, then a space or line end (stepped over unless the NUL).
  bool token(std::size_t& p, std::string_view word) const {
    for (std::size_t i = 0; i < word.size(); ++i) {
      if (at(p + i) != word[i]) return false;
    }
    const char next = at(p + word.size());
    if (!space_or_line_end(next)) return false;
    p += word.size() + (next != '\0' ? 1 : 0);
    return true;
  }
  // After a number: what may follow it for assimp to stop where this reading stops.
  bool number_end(std::size_t p) const {
    const char c = at(p);
    return space(c) || c == '\0' || c == '(' || c == ')';
  }

  // CommentRemover::RemoveLineComments("//", …, ' '), which assimp runs over the text first. It
  // steps over quotes ('"' or '\'') to the next quote character, and past the end of the text when
  // there is none.
  void remove_line_comments() {
    std::size_t p = 0;
    while (at(p) != '\0') {
      if (at(p) == '"' || at(p) == '\'') {
        while (true) {
          const char c = at(p++);
          if (c == '\0' || at(p) == '"' || at(p) == '\'') break;
        }
      }
      if (at(p) == '/' && at(p + 1) == '/') {
        while (!line_end(at(p))) b_[p++] = ' ';
        if (at(p) == '\0') break;
      }
      ++p;
    }
  }

  bool header() {
    std::size_t p = 0;
    skip_spaces(p);
    if (!token(p, "MD5Version")) return false;
    skip_spaces(p);
    std::uint32_t version = 0;
    while (at(p) >= '0' && at(p) <= '9')
      version = version * 10 + static_cast<std::uint32_t>(at(p++) - '0');
    if (version != 10) return false;
    while (at(p) != '\r' && at(p) != '\n' && at(p) != '\0') ++p;  // the rest of the line
    while (at(p) == '\r' || at(p) == '\n') ++p;
    while (!line_end(at(p++))) {
    }  // the command line, through its line end
    skip_spaces_and_line_ends(p);
    pos_ = p;
    return true;
  }

  // MD5Parser::ParseSection: "name [value…] { element lines }" or "name value".
  bool section(Section& s) {
    std::size_t& p = pos_;
    s.at = p;
    const std::size_t start = p;
    while (!space_or_line_end(at(p))) ++p;
    s.name = b_.substr(start, p - start);
    skip_spaces(p);
    while (true) {
      if (at(p) == '{') {
        ++p;
        while (true) {
          if (!skip_spaces_and_line_ends(p)) return false;
          if (at(p) == '}') {
            ++p;
            break;
          }
          s.elements.push_back(p);
          while (!line_end(at(p))) ++p;
          if (at(p) != '\0') b_[p++] = '\0';
        }
        break;
      }
      if (!space_or_line_end(at(p))) {
        while (!space_or_line_end(at(p++))) {
        }  // a value at global scope, through the character after it
        continue;
      }
      break;
    }
    return skip_spaces_and_line_ends(p);
  }

  bool read_uint(std::size_t& p, std::uint32_t& value) const {
    if (at(p) < '0' || at(p) > '9') return false;
    std::uint64_t v = 0;
    while (at(p) >= '0' && at(p) <= '9') {
      v = v * 10 + static_cast<std::uint64_t>(at(p++) - '0');
      if (v > std::numeric_limits<std::uint32_t>::max()) return false;
    }
    value = static_cast<std::uint32_t>(v);
    return number_end(p);
  }

  bool read_int(std::size_t& p) const {
    if (at(p) == '-' || at(p) == '+') ++p;
    std::uint32_t ignored = 0;
    return read_uint(p, ignored);
  }

  // A decimal number as assimp's fast_atoreal_move reads it whole (nan, inf, infinity too).
  bool read_float(std::size_t& p) const {
    if (at(p) == '-' || at(p) == '+') ++p;
    for (const std::string_view word : {"infinity", "inf", "nan"}) {
      bool match = true;
      for (std::size_t i = 0; i < word.size() && match; ++i) {
        match = std::tolower(static_cast<unsigned char>(at(p + i))) == word[i];
      }
      if (match) {
        p += word.size();
        return number_end(p);
      }
    }
    const auto digits = [&] {
      std::size_t count = 0;
      while (at(p) >= '0' && at(p) <= '9') ++p, ++count;
      return count;
    };
    std::size_t mantissa = digits();
    if (at(p) == '.') {
      ++p;
      mantissa += digits();
    }
    if (mantissa == 0) return false;
    if (at(p) == 'e' || at(p) == 'E') {
      ++p;
      if (at(p) == '-' || at(p) == '+') ++p;
      if (digits() == 0) return false;
    }
    return number_end(p);
  }

  bool expect(std::size_t& p, char c) const {
    skip_spaces(p);
    if (at(p) != c) return false;
    ++p;
    return true;
  }
  bool uint_field(std::size_t& p, std::uint32_t& value) const {
    skip_spaces(p);
    return read_uint(p, value);
  }
  bool int_field(std::size_t& p) const {
    skip_spaces(p);
    return read_int(p);
  }
  bool float_field(std::size_t& p) const {
    skip_spaces(p);
    return read_float(p);
  }

  // A name in quotes within the element (assimp scans to the next quote wherever it is, and
  // copies the name into a 1024-byte string).
  bool quoted(std::size_t& p) const {
    std::size_t q = p;
    while (at(q) != '"' && at(q) != '\0') ++q;
    if (at(q) != '"') return false;
    const std::size_t begin = ++q;
    while (at(q) != '"' && at(q) != '\0') ++q;
    if (at(q) != '"' || q - begin >= 1024) return false;
    p = q + 1;
    return true;
  }

  [[noreturn]] void unreadable(std::size_t element, const char* form) const {
    refuse(
        "MD5 line " + std::to_string(line_of(element)) + " is not `" + form +
        "` (assimp's MD5 reader would read on from wherever it stopped)");
  }

  // "name" PARENT ( X Y Z ) ( QX QY QZ )
  void joint(std::size_t e) const {
    std::size_t p = e;
    const bool ok = at(p) == '"' && quoted(p) && int_field(p) && expect(p, '(') && float_field(p) &&
                    float_field(p) && float_field(p) && expect(p, ')') && expect(p, '(') &&
                    float_field(p) && float_field(p) && float_field(p) && expect(p, ')');
    if (!ok) unreadable(e, "\"NAME\" PARENT ( X Y Z ) ( QX QY QZ )");
  }

  static void resize(std::uint64_t& size, std::uint32_t count, auto& given) {
    size = count;
    given.erase(given.lower_bound(count), given.end());
  }
  void grow(std::uint64_t& size, std::uint32_t index, std::size_t e) const {
    // idx + 1 wraps to 0 in assimp's unsigned int: the array shrinks to nothing, then is indexed.
    if (index == std::numeric_limits<std::uint32_t>::max())
      refuse("MD5 line " + std::to_string(line_of(e)) + ": index 4294967295 is out of range");
    if (index >= size) size = std::uint64_t{index} + 1;
  }

  Mesh mesh(const Section& s) const {
    Mesh m;
    m.line = line_of(s.at);
    for (const auto e : s.elements) {
      std::size_t p = e;
      std::uint32_t index = 0;
      std::uint32_t count = 0;
      if (token(p, "shader")) {
        skip_spaces(p);
        if (!quoted(p)) unreadable(e, "shader \"NAME\"");
      } else if (token(p, "numverts")) {
        if (!uint_field(p, count)) unreadable(e, "numverts COUNT");
        resize(m.vertices, count, m.vertex_weights);
      } else if (token(p, "numtris")) {
        if (!uint_field(p, count)) unreadable(e, "numtris COUNT");
        resize(m.triangles, count, m.corners);
      } else if (token(p, "numweights")) {
        if (!uint_field(p, count)) unreadable(e, "numweights COUNT");
        resize(m.weights, count, m.weight_joint);
      } else if (token(p, "vert")) {
        std::uint32_t first = 0;
        if (!(uint_field(p, index) && expect(p, '(') && float_field(p) && float_field(p) &&
              expect(p, ')') && uint_field(p, first) && uint_field(p, count)))
          unreadable(e, "vert INDEX ( U V ) FIRST_WEIGHT WEIGHT_COUNT");
        grow(m.vertices, index, e);
        m.vertex_weights[index] = {first, count};
      } else if (token(p, "tri")) {
        std::array<std::uint32_t, 3> c{};
        if (!(uint_field(p, index) && uint_field(p, c[0]) && uint_field(p, c[1]) &&
              uint_field(p, c[2])))
          unreadable(e, "tri INDEX VERTEX VERTEX VERTEX");
        grow(m.triangles, index, e);
        m.corners[index] = c;
      } else if (token(p, "weight")) {
        std::uint32_t joint = 0;
        if (!(uint_field(p, index) && uint_field(p, joint) && float_field(p) && expect(p, '(') &&
              float_field(p) && float_field(p) && float_field(p) && expect(p, ')')))
          unreadable(e, "weight INDEX JOINT BIAS ( X Y Z )");
        grow(m.weights, index, e);
        m.weight_joint[index] = joint;
      }
    }
    return m;
  }

  // What MD5Importer::MakeDataUnique and LoadMD5MeshFile index with.
  void indices(const Mesh& m, std::size_t number, std::uint64_t joints) const {
    if (m.triangles == 0 || m.vertices == 0) return;  // skipped by the loader
    const std::string name =
        "MD5 mesh " + std::to_string(number) + " (line " + std::to_string(m.line) + ")";
    if (3 * m.triangles > std::numeric_limits<std::uint32_t>::max())
      refuse(
          name + " declares " + std::to_string(m.triangles) +
          " triangles, more than assimp's MD5 reader can count");
    if (m.corners.size() < m.triangles) {
      std::uint64_t missing = 0;
      for (const auto& [index, corners] : m.corners) {
        if (index != missing) break;
        ++missing;
      }
      refuse(
          name + " declares " + std::to_string(m.triangles) +
          " triangles but gives no `tri` line for triangle " + std::to_string(missing));
    }
    // MakeDataUnique gives every repeated corner a new vertex after the old ones, in an array of
    // 3 x triangles: a vertex no triangle uses leaves one slot too few (it writes past the array).
    if (m.vertices > 3 * m.triangles)
      refuse(
          name + " has " + std::to_string(m.vertices) + " vertices, more than its " +
          std::to_string(m.triangles) +
          " triangles can use (assimp's MD5 reader would write past its vertex array)");
    std::vector<bool> used(static_cast<std::size_t>(m.vertices));
    for (const auto& [index, corners] : m.corners) {
      for (const auto v : corners) {
        if (v >= m.vertices)
          refuse(
              name + ": triangle " + std::to_string(index) + " uses vertex " + std::to_string(v) +
              ", but the mesh has " + std::to_string(m.vertices) + " vertices");
        used[v] = true;
      }
    }
    if (const auto unused = std::find(used.begin(), used.end(), false); unused != used.end())
      refuse(
          name + ": vertex " + std::to_string(unused - used.begin()) +
          " is in no triangle (assimp's MD5 reader would write past its vertex array)");
    // The given weights whose joint does not exist, and all given weights, by index.
    std::vector<std::uint32_t> bad;
    std::vector<std::uint32_t> given;
    for (const auto& [index, joint] : m.weight_joint) {
      given.push_back(index);
      if (joint >= joints) bad.push_back(index);
    }
    for (const auto& [vertex, range] : m.vertex_weights) {
      const auto [first, count] = range;
      if (count == 0) continue;
      const std::uint64_t end = std::uint64_t{first} + count;
      if (end > m.weights)
        refuse(
            name + ": vertex " + std::to_string(vertex) + " uses weights " + std::to_string(first) +
            " to " + std::to_string(end - 1) + ", but the mesh has " + std::to_string(m.weights) +
            " weights");
      const auto b = std::lower_bound(bad.begin(), bad.end(), first);
      if (b != bad.end() && *b < end)
        refuse(
            name + ": weight " + std::to_string(*b) + " names joint " +
            std::to_string(m.weight_joint.at(*b)) + ", but the file has " + std::to_string(joints) +
            " joints");
      const auto listed = std::lower_bound(given.begin(), given.end(), end) -
                          std::lower_bound(given.begin(), given.end(), first);
      if (joints == 0 && static_cast<std::uint64_t>(listed) < count)
        refuse(
            name + ": vertex " + std::to_string(vertex) +
            " uses a weight without a `weight` line (joint 0), but the file has no joints");
    }
  }

  std::string file_;
  std::string text_;  // the file
  std::string b_;     // the file and a NUL, split into elements as assimp's parser does
  std::size_t n_;     // offset of that NUL
  std::size_t pos_ = 0;
};

void check_md5mesh(const std::filesystem::path& file) {
  std::string text;
  try {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    text = std::move(bytes).str();
  } catch (const std::bad_alloc&) {
    return;  // too large to look at here; the import's child process still contains assimp
  }
  Md5MeshCheck(file.string(), std::move(text)).run();
}

#if !defined(SKELCD_UNDER_ASAN)
// The process's current address space, bytes (/proc/self/statm: pages).
std::size_t mapped_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}
#endif

// What the child tells its parent: one status byte, then the message (or, after kOk, the probe's
// answer).
constexpr char kOk = 'O';
constexpr char kInvalidInput = 'I';
constexpr char kIoError = 'E';
constexpr char kOutOfMemory = 'M';
constexpr char kOther = 'X';

// Exit status of a child whose probe failed after part of its answer was already on its way (no
// report can follow it: the parent reads an incomplete answer).
constexpr int kBrokenAnswerExit = 76;

void write_all(int fd, const char* p, std::size_t left) {
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

void write_all(int fd, const std::string& data) { write_all(fd, data.data(), data.size()); }

// The child's answer on its way to the parent: kOk, then what the probe sends, a block at a time.
// Nothing reaches the pipe before the first block is full, so a probe that fails before it has
// sent that much still reports its failure instead.
class AnswerWriter {
 public:
  explicit AnswerWriter(int fd) : fd_(fd), block_(kBlockBytes) {}

  void write(const void* data, std::size_t n) {
    const char* p = static_cast<const char*>(data);
    if (n >= kBlockBytes) {  // a large array: straight through
      flush();
      write_all(fd_, p, n);
      return;
    }
    while (n > 0) {
      const std::size_t take = std::min(n, kBlockBytes - used_);
      std::memcpy(block_.data() + used_, p, take);
      used_ += take;
      p += take;
      n -= take;
      if (used_ == kBlockBytes) flush();
    }
  }

  // Sends kOk and whatever is buffered (also when the probe sent nothing).
  void flush() {
    if (!started_) {
      write_all(fd_, &kOk, 1);
      started_ = true;
    }
    write_all(fd_, block_.data(), used_);
    used_ = 0;
  }

  [[nodiscard]] bool started() const { return started_; }

 private:
  static constexpr std::size_t kBlockBytes = std::size_t{64} << 10;
  int fd_;
  std::vector<char> block_;
  std::size_t used_ = 0;
  bool started_ = false;
};

// The child starts with the parent's small heap and grows it for everything the import reads and
// builds, a page fault per 4 KiB page first touched: a third of the child's time for the
// 28k-triangle CesiumMan-dense on this project's VMs, whose faults are dear (docs/benchmarks.md,
// "The import child's heap on huge pages"). So the heap's top is grown by `bytes` at once, under
// the child's limit, and advised as transparent huge pages: what the import then allocates there
// (large blocks too: malloc serves any request the top can hold before it maps one) is first
// touched a 2 MiB page at a time, where the kernel offers them (its `madvise` or `always` mode).
// Kept, not trimmed: the child exits when its import is done. `skelcd check` calls it too.
}  // namespace

void grow_heap_on_huge_pages(std::size_t bytes) noexcept {
  constexpr std::size_t kHuge = std::size_t{2} << 20;
  if (bytes < 2 * kHuge) return;
  // The freed block stays the top; it comes from the heap, not a mapping of its own (glibc takes
  // thresholds up to 32 MiB).
  mallopt(M_TRIM_THRESHOLD, static_cast<int>(2 * bytes));
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(std::size_t{32} << 20));
  void* block = std::malloc(bytes);
  if (block == nullptr) return;  // over the limit: the heap grows as it would have
  const auto first = (reinterpret_cast<std::uintptr_t>(block) + kHuge - 1) & ~(kHuge - 1);
  const auto last = (reinterpret_cast<std::uintptr_t>(block) + bytes) & ~(kHuge - 1);
  if (last > first) (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  std::free(block);
}

namespace {

[[noreturn]] void child(
    int fd, const ImportLimits& limits, const std::function<void(const AnswerSink&)>& probe) {
#if defined(SKELCD_UNDER_ASAN)
  // Under the sanitizers a library's memory error in the child is caught by ASan, which prints a
  // report of dozens of lines and exits 1 instead of dying by a signal: the user's stderr keeps
  // the parent's one line only (the child answers through the pipe; no answer is the crash).
  if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) {
    ::dup2(null, STDERR_FILENO);
    ::close(null);
  }
#endif
  AnswerWriter answer(fd);  // its buffer before the limit, which is the probe's
  if (limits.memory_bytes > 0) {
#if defined(SKELCD_UNDER_ASAN)
    asan_limit_bytes = static_cast<long long>(limits.memory_bytes);
    __sanitizer_install_malloc_and_free_hooks(asan_on_malloc, asan_on_free);
#else
    // Heap the parent freed but still maps is room the probe allocates in without adding address
    // space: it counts against the limit (a process that has imported a few models holds a few
    // MB of it, as much as a small limit). The probe may still use `memory_bytes` in all.
    const std::size_t reusable = std::min(::mallinfo2().fordblks, limits.memory_bytes);
    const rlim_t cap = static_cast<rlim_t>(mapped_bytes() + limits.memory_bytes - reusable);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
#endif
  }
#if !defined(SKELCD_UNDER_ASAN)
  // 30 MiB, at most an eighth of the limit: a large block the top cannot hold is still mapped
  // apart, and the top's address space then counts against the limit beside it.
  if (limits.heap_on_huge_pages) {
    grow_heap_on_huge_pages(
        limits.memory_bytes > 0 ? std::min(kHeapOnHugePages, limits.memory_bytes / 8)
                                : kHeapOnHugePages);
  }
#endif
  std::string report;
  try {
    probe([&answer](const void* data, std::size_t size) { answer.write(data, size); });
    answer.flush();
    ::close(fd);
    _exit(0);  // no atexit handlers, no stdio flush: the parent owns those
  } catch (const std::bad_alloc&) {
    report = kOutOfMemory;
  } catch (const InvalidInput& e) {
    report = std::string(1, kInvalidInput) + e.what();
  } catch (const IoError& e) {
    report = std::string(1, kIoError) + e.what();
  } catch (const std::length_error&) {
    report = kOutOfMemory;  // a size beyond max_size(): a declared count no memory can hold
  } catch (const std::exception& e) {
    report = std::string(1, kOther) + e.what();
  } catch (...) {
    report = std::string(1, kOther) + "unknown exception";
  }
  if (answer.started()) _exit(kBrokenAnswerExit);
  write_all(fd, report);
  ::close(fd);
  _exit(0);
}

std::string signal_name(int sig) {
  switch (sig) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGABRT:
      return "SIGABRT";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGKILL:
      return "SIGKILL";
    default:
      return "signal " + std::to_string(sig);
  }
}

}  // namespace

void check_declared_counts(const std::filesystem::path& file) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) return;
  const auto ext = lower(file.extension().string());
  if (ext == ".off") check_off(file, size);
  if (ext == ".ply") check_ply(file, size);
  if (ext == ".md5mesh") check_md5mesh(file);
}

void ChildAnswer::append(std::vector<char> piece) {
  if (piece.empty()) return;
  size_ += piece.size();
  pieces_.push_back(std::move(piece));
}

bool ChildAnswer::read(void* out, std::size_t n) {
  if (n > size_) return false;
  char* to = static_cast<char*>(out);
  while (n > 0) {
    const std::vector<char>& front = pieces_.front();
    const std::size_t take = std::min(n, front.size() - offset_);
    std::memcpy(to, front.data() + offset_, take);
    to += take;
    n -= take;
    offset_ += take;
    size_ -= take;
    if (offset_ == front.size()) {  // read through: released
      pieces_.pop_front();
      offset_ = 0;
    }
  }
  return true;
}

void run_isolated(
    const std::filesystem::path& file,
    const ImportLimits& limits,
    const std::function<void()>& probe) {
  (void)run_isolated_with_answer(file, limits, [&probe](const AnswerSink&) { probe(); });
}

ChildAnswer run_isolated_with_answer(
    const std::filesystem::path& file,
    const ImportLimits& limits,
    const std::function<void(const AnswerSink& send)>& probe) {
  const std::string name = file.string();
  int fds[2];
  if (::pipe(fds) != 0)
    throw IoError(name + ": cannot start the import (pipe: " + std::strerror(errno) + ")");
  // The rig comes back through the pipe: 1.8 MB for the 28k-triangle CesiumMan-dense, 28 rounds
  // of the default 64 KiB, each a wait for the reader. A larger pipe when the system allows it
  // (fs.pipe-max-size, 1 MiB by default; a refusal keeps 64 KiB).
  (void)::fcntl(fds[1], F_SETPIPE_SZ, 1 << 20);
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw IoError(name + ": cannot start the import (fork: " + std::strerror(err) + ")");
  }
  if (pid == 0) {
    ::close(fds[0]);
    child(fds[1], limits, probe);
  }
  ::close(fds[1]);
  // The caller's own work beside the child's import. A failure of it is not the import's: dropped,
  // and the child is read and reaped as always.
  if (limits.while_waiting) {
    try {
      limits.while_waiting();
    } catch (...) {
    }
  }

  // Read the child's report until it closes the pipe, within the time limit, while it writes (a
  // pipe holds 64 KiB: a child waiting for room would wait for ever). Pieces grow from 64 KiB to
  // 4 MiB: small reports stay small, large answers take few allocations.
  constexpr std::size_t kFirstPieceBytes = std::size_t{64} << 10;
  constexpr std::size_t kLargestPieceBytes = std::size_t{4} << 20;
  ChildAnswer answer;
  std::vector<char> piece;
  std::size_t filled = 0;
  std::size_t received = 0;
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
  bool too_large = false;
  for (;;) {
    int wait_ms = -1;
    if (limits.time_s > 0) {
      const double left =
          limits.time_s -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0) {
        timed_out = true;
        break;
      }
      wait_ms = static_cast<int>(std::min(left * 1000.0 + 1.0, 60000.0));
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) continue;  // the deadline is checked above
    if (filled == piece.size()) {
      const std::size_t next =
          piece.empty() ? kFirstPieceBytes : std::min(2 * piece.size(), kLargestPieceBytes);
      answer.append(std::move(piece));
      piece = std::vector<char>(next);
      filled = 0;
    }
    const ssize_t n = ::read(fds[0], piece.data() + filled, piece.size() - filled);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    filled += static_cast<std::size_t>(n);
    received += static_cast<std::size_t>(n);
    // An answer is what the child held in memory, written out: more than its limit is a child
    // gone wrong, and this process would hold it all.
    if (limits.memory_bytes > 0 && received > limits.memory_bytes) {
      too_large = true;
      break;
    }
  }
  piece.resize(filled);
  answer.append(std::move(piece));
  ::close(fds[0]);
  if (timed_out || too_large) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", limits.time_s);
    throw IoError(name + ": importing it took longer than " + text + " s; gave up");
  }
  const std::string limit_text =
      "the import memory limit of " + mib(static_cast<double>(limits.memory_bytes));
  const std::string over_memory =
      name + ": importing it needs more memory than " + limit_text + " (--import-memory raises it)";
  if (too_large) throw InvalidInput(over_memory);
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    if (sig == SIGKILL)
      throw InvalidInput(
          name + ": the import was killed, most likely for memory (" + limit_text + ")");
    throw IoError(
        name + ": " + limits.reader + " crashed reading it (" + signal_name(sig) +
        "); the file is damaged or uses a feature it cannot read");
  }
  const int exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  char kind = 0;
  const bool answered = answer.read(&kind, 1);
  if ((!answered || kind == kOk) && exit_status == kOverMemoryExit) throw InvalidInput(over_memory);
  if (!answered) {
    throw IoError(
        name + ": " + limits.reader + " ended without an answer (exit status " +
        std::to_string(exit_status) + ")");
  }
  if (kind == kOk) {
    if (exit_status != 0)
      throw IoError(
          name + ": " + limits.reader + " ended without completing its answer (exit status " +
          std::to_string(exit_status) + ")");
    return answer;
  }
  std::string message(answer.size(), '\0');
  (void)answer.read(message.data(), message.size());
  switch (kind) {
    case kInvalidInput:
      throw InvalidInput(message);
    case kIoError:
      throw IoError(message);
    case kOutOfMemory:
      throw InvalidInput(over_memory);
    default:
      throw IoError(name + ": " + message);
  }
}

}  // namespace skelcd::skinning::detail
