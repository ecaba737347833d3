// PLplot opened on first use (tools/report/plplot_library.hpp): not loaded before a plot is drawn,
// every function of the table found once it is, and a library that cannot be opened or lacks a
// function refused in one line naming what is wrong. (The plots themselves: test_cmd_inspect.cpp,
// test_cmd_bench.cpp.)

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "skinning/errors.hpp"
#include "tools/report/plplot_library.hpp"

namespace {

using skelcd::IoError;
using skelcd::tools::detail::open_plplot_library;
using skelcd::tools::detail::plplot;
using skelcd::tools::detail::PlplotLibrary;

/// Whether a mapping of this process comes from a file whose name holds `name`.
bool mapped(const std::string& name) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    if (line.find(name) != std::string::npos) return true;
  }
  return false;
}

/// The message of the IoError `f` throws ("" when it throws none).
template <typename F>
std::string io_error_of(F&& f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

// ctest runs each test in a process of its own: nothing has drawn a plot before this one.
TEST(PlplotLibrary, OpenedOnFirstUseOnly) {
  ASSERT_FALSE(mapped("libplplot")) << "PLplot is loaded before any plot: linked again?";
  const PlplotLibrary& pl = plplot();
  EXPECT_TRUE(mapped("libplplot"));
#define SKELCD_EXPECT_FOUND(name) EXPECT_NE(pl.name, nullptr) << #name;
  SKELCD_PLPLOT_FUNCTIONS(SKELCD_EXPECT_FOUND)
#undef SKELCD_EXPECT_FOUND
  EXPECT_EQ(&plplot(), &pl);  // opened once
}

TEST(PlplotLibrary, MissingLibraryIsOneLineNamingIt) {
  const std::string what =
      io_error_of([] { (void)open_plplot_library("libskelcd-no-such-plplot.so.9"); });
  EXPECT_EQ(what.rfind("plotting needs PLplot", 0), 0u) << what;
  EXPECT_NE(what.find("libskelcd-no-such-plplot.so.9"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

TEST(PlplotLibrary, LibraryWithoutItsFunctionsIsRefusedNamingThem) {
  // The C library opens, and has none of PLplot's functions.
  const std::string what = io_error_of([] { (void)open_plplot_library("libc.so.6"); });
  EXPECT_EQ(what.rfind("plotting needs PLplot: libc.so.6 lacks c_pladv, c_plbox", 0), 0u) << what;
  EXPECT_NE(what.find("c_plwind"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

}  // namespace
