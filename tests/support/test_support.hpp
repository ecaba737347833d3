#pragma once
// Helpers shared by every module's tests: matrix comparison, exception-message checks, asset paths.

#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <gtest/gtest.h>

namespace skelcd::test {

/// Path of a file under the repository's assets/ folder.
[[nodiscard]] std::filesystem::path asset(std::string_view relative);
/// Path of a model shipped by Debian's assimp-testmodels (/usr/share/assimp/models/...).
[[nodiscard]] std::filesystem::path assimp_model(std::string_view relative);
/// A fresh, empty temporary folder for one test (removed at the next call with the same name).
[[nodiscard]] std::filesystem::path temp_dir(std::string_view name);
/// The VmFlags line of the mapping of /proc/self/smaps that holds `address` ("" when none does):
/// what the kernel was told about that memory (" hg": advised as transparent huge pages).
[[nodiscard]] std::string vm_flags_at(const void* address);

/// Succeeds when `a` and `b` have the same shape and max |a - b| <= tolerance.
[[nodiscard]] ::testing::AssertionResult expect_matrix_near(
    const Eigen::MatrixXd& a,
    const Eigen::MatrixXd& b,
    double tolerance);

}  // namespace skelcd::test

/// Expects `statement` to throw `exception_type` whose what() contains `substring`.
#define EXPECT_THROW_MESSAGE(statement, exception_type, substring)                           \
  do {                                                                                      \
    bool skelcd_thrown_ = false;                                                            \
    try {                                                                                   \
      statement;                                                                            \
    } catch (const exception_type& e) {                                                     \
      skelcd_thrown_ = true;                                                                \
      EXPECT_NE(std::string(e.what()).find(substring), std::string::npos)                   \
          << "message was: " << e.what();                                                   \
    }                                                                                       \
    EXPECT_TRUE(skelcd_thrown_) << "expected " #exception_type " from " #statement;        \
  } while (false)
