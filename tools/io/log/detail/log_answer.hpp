#pragma once
// A read log as bytes, from the reader's child process to its parent (internal): the child's read
// is then the only one, and the parent never hands the file to libhdf5 (read_log, isolate). Native
// byte order and sizes: a message between two processes of the same program, not a file format.

#include <string>

#include "skinning/detail/import_guard.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools::detail {

/// Sends every field of `log` to `send` (doubles bit for bit), in the order read_log_answer reads
/// them.
/// @note A field added to LogData, LogHeader, LogRoute, LogCheck, FrameRow, ContactRow, DcdPairRow
///       or EventRecord must be added here and in read_log_answer; tests/tools/test_log.cpp
///       compares an isolated read with an in-process one field by field.
void write_log_answer(const LogData& log, const skinning::detail::AnswerSink& send);

/// Reads what write_log_answer sent, releasing `bytes` as it goes. Every count is checked against
/// the bytes left before anything is allocated for it.
/// @param file  named in the messages.
/// @throws IoError "<file>: the log reader's answer from its child process is damaged (…)" when
///         the bytes end early, carry more than the log, or hold a value no log has.
[[nodiscard]] LogData read_log_answer(
    skinning::detail::ChildAnswer& bytes, const std::string& file);

}  // namespace skelcd::tools::detail
