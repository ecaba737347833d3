#pragma once
// Writing and reading a child process's answer (run_isolated_with_answer) field by field
// (internal). Native byte order and sizes: a message between two processes of the same program,
// not a file format. Used by the import (imported_rig_stream.cpp) and the log reader
// (tools/io/log/detail/log_answer.cpp).

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "skinning/detail/import_guard.hpp"
#include "skinning/errors.hpp"

namespace skelcd::skinning::detail {

/// Bytes a count (or a string's length) takes in the stream.
inline constexpr std::size_t kAnswerCountBytes = sizeof(std::uint64_t);

/// Sends values to an AnswerSink in the order the matching AnswerReader calls read them.
class AnswerWriter {
 public:
  explicit AnswerWriter(const AnswerSink& send) : send_(send) {}

  template <class T>
  void scalar(T value) {
    static_assert(std::is_arithmetic_v<T>);
    send_(&value, sizeof value);
  }
  void count(std::size_t n) { scalar(static_cast<std::uint64_t>(n)); }
  void string(const std::string& s) {
    count(s.size());
    send_(s.data(), s.size());
  }
  void block(const void* data, std::size_t size) { send_(data, size); }
  /// A vector of scalars, of fixed-size Eigen objects or of trivially copyable rows, as one block.
  template <class T>
  void array(const std::vector<T>& values) {
    count(values.size());
    send_(values.data(), values.size() * sizeof(T));
  }
  void strings(const std::vector<std::string>& values) {
    count(values.size());
    for (const auto& s : values) string(s);
  }

 private:
  const AnswerSink& send_;
};

/// Reads what an AnswerWriter sent, releasing the answer's bytes as it goes. Every count is
/// checked against the bytes left before anything is allocated for it.
class AnswerReader {
 public:
  /// @param file     named first in every message.
  /// @param subject  whose answer it is, for the messages ("the import's", "the log reader's").
  AnswerReader(ChildAnswer& in, const std::string& file, const char* subject)
      : in_(in), file_(file), subject_(subject) {}

  /// @throws IoError "<file>: <subject> answer from its child process is damaged (<what>)".
  [[noreturn]] void damaged(const std::string& what) const {
    throw IoError(
        file_ + ": " + subject_ + " answer from its child process is damaged (" + what + ")");
  }

  void bytes(void* out, std::size_t n) {
    if (!in_.read(out, n))
      damaged(
          "it ends " + std::to_string(n - in_.size()) + " bytes short of " + std::to_string(n) +
          " more");
  }
  template <class T>
  T scalar() {
    static_assert(std::is_arithmetic_v<T>);
    T value;
    bytes(&value, sizeof value);
    return value;
  }
  /// A count of elements taking at least `min_bytes` each, bounded by the bytes left.
  std::size_t count(std::size_t min_bytes, const char* what) {
    const auto n = scalar<std::uint64_t>();
    if (n > in_.size() / min_bytes)
      damaged(
          std::to_string(n) + " " + what + " announced, but only " + std::to_string(in_.size()) +
          " bytes follow");
    return static_cast<std::size_t>(n);
  }
  std::string string(const char* what) {
    std::string s(count(1, what), '\0');
    bytes(s.data(), s.size());
    return s;
  }
  template <class T>
  std::vector<T> array(const char* what) {
    std::vector<T> values(count(sizeof(T), what));
    bytes(values.data(), values.size() * sizeof(T));
    return values;
  }
  std::vector<std::string> strings(const char* what) {
    std::vector<std::string> values(count(kAnswerCountBytes, what));
    for (auto& s : values) s = string(what);
    return values;
  }
  [[nodiscard]] std::size_t left() const { return in_.size(); }

 private:
  ChildAnswer& in_;
  const std::string& file_;
  const char* subject_;
};

}  // namespace skelcd::skinning::detail
