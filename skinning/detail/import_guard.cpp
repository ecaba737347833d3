#include "skinning/detail/import_guard.hpp"

#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <new>
#include <sstream>
#include <string>
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

#if !defined(SKELCD_UNDER_ASAN)
// The process's current address space, bytes (/proc/self/statm: pages).
std::size_t mapped_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}
#endif

// What the child tells its parent: one status byte, then the message.
constexpr char kOk = 'O';
constexpr char kInvalidInput = 'I';
constexpr char kIoError = 'E';
constexpr char kOutOfMemory = 'M';
constexpr char kOther = 'X';

void write_all(int fd, const std::string& data) {
  const char* p = data.data();
  std::size_t left = data.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

[[noreturn]] void child(int fd, const ImportLimits& limits, const std::function<void()>& probe) {
  if (limits.memory_bytes > 0) {
#if defined(SKELCD_UNDER_ASAN)
    asan_limit_bytes = static_cast<long long>(limits.memory_bytes);
    __sanitizer_install_malloc_and_free_hooks(asan_on_malloc, asan_on_free);
#else
    const rlim_t cap = static_cast<rlim_t>(mapped_bytes() + limits.memory_bytes);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
#endif
  }
  std::string report;
  try {
    probe();
    report = kOk;
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
  write_all(fd, report);
  ::close(fd);
  _exit(0);  // no atexit handlers, no stdio flush: the parent owns those
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
}

void run_isolated(
    const std::filesystem::path& file,
    const ImportLimits& limits,
    const std::function<void()>& probe) {
  const std::string name = file.string();
  int fds[2];
  if (::pipe(fds) != 0)
    throw IoError(name + ": cannot start the import (pipe: " + std::strerror(errno) + ")");
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

  // Read the child's report until it closes the pipe, within the time limit.
  std::string report;
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
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
    char buffer[4096];
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    report.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
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
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    if (sig == SIGKILL)
      throw InvalidInput(
          name + ": the import was killed, most likely for memory (" + limit_text + ")");
    throw IoError(
        name + ": " + limits.reader + " crashed reading it (" + signal_name(sig) +
        "); the file is damaged or uses a feature it cannot read");
  }
  if (report.empty() && WIFEXITED(status) && WEXITSTATUS(status) == kOverMemoryExit)
    report = kOutOfMemory;
  if (report.empty()) {
    throw IoError(
        name + ": " + limits.reader + " ended without an answer (exit status " +
        std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  }
  const std::string message = report.substr(1);
  switch (report.front()) {
    case kOk:
      return;
    case kInvalidInput:
      throw InvalidInput(message);
    case kIoError:
      throw IoError(message);
    case kOutOfMemory:
      throw InvalidInput(
          name + ": importing it needs more memory than " + limit_text +
          " (--import-memory raises it)");
    default:
      throw IoError(name + ": " + message);
  }
}

}  // namespace skelcd::skinning::detail
