#include "tests/support/test_support.hpp"

#include <sstream>

namespace skelcd::test {

std::filesystem::path asset(std::string_view relative) {
  return std::filesystem::path(SKELCD_SOURCE_DIR) / "assets" / relative;
}

std::filesystem::path assimp_model(std::string_view relative) {
  return std::filesystem::path(SKELCD_ASSIMP_MODELS) / relative;
}

std::filesystem::path temp_dir(std::string_view name) {
  const auto dir = std::filesystem::temp_directory_path() / "skelcd-tests" / name;
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
