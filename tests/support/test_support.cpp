#include "tests/support/test_support.hpp"

#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <sstream>

namespace skelcd::test {

std::filesystem::path asset(std::string_view relative) {
  return std::filesystem::path(SKELCD_SOURCE_DIR) / "assets" / relative;
}

std::filesystem::path assimp_model(std::string_view relative) {
  return std::filesystem::path(SKELCD_ASSIMP_MODELS) / relative;
}

std::string vm_flags_at(const void* address) {
  const auto a = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0;
    std::uintptr_t hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= a && a < hi;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  return "";
}

std::filesystem::path temp_dir(std::string_view name) {
  // ctest runs every test in its own process, several at once: a directory shared by two tests
  // would be removed under the other's feet. The process id and the running test's name keep
  // each test's files apart.
  std::string owner = "process";
  if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info()) {
    owner = std::string(info->test_suite_name()) + "." + info->name();
    for (char& c : owner) {
      if (c == '/') c = '_';
    }
  }
  const auto dir = std::filesystem::temp_directory_path() / "skelcd-tests" /
                   (std::to_string(::getpid()) + "-" + owner) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

::testing::AssertionResult expect_matrix_near(
    const Eigen::MatrixXd& a,
    const Eigen::MatrixXd& b,
    double tolerance) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "shapes differ: " << a.rows() << "x" << a.cols()
                                         << " vs " << b.rows() << "x" << b.cols();
  }
  if (a.size() == 0) return ::testing::AssertionSuccess();
  Eigen::Index r = 0;
  Eigen::Index c = 0;
  const double worst = (a - b).cwiseAbs().maxCoeff(&r, &c);
  if (!(worst <= tolerance)) {
    std::ostringstream os;
    os << "max |a-b| = " << worst << " > " << tolerance << " at (" << r << "," << c
       << "): " << a(r, c) << " vs " << b(r, c);
    return ::testing::AssertionFailure() << os.str();
  }
  return ::testing::AssertionSuccess();
}

}  // namespace skelcd::test
