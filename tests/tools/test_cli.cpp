// The CLI as a user meets it: help, version, unknown commands.

#include <gtest/gtest.h>

#include "tests/tools/cli_runner.hpp"

namespace {

using skelcd::test::run_skelcd;

TEST(Cli, HelpListsCommandsAndExitsZero) {
  const auto r = run_skelcd({"--help"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("skelcd"), std::string::npos);
}

TEST(Cli, VersionPrintsAVersion) {
  const auto r = run_skelcd({"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find('.'), std::string::npos) << r.out;
}

TEST(Cli, UnknownCommandFailsWithOneLine) {
  const auto r = run_skelcd({"no-such-command"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(r.err.empty());
}

TEST(Cli, NoCommandFails) {
  const auto r = run_skelcd({});
  EXPECT_NE(r.exit_code, 0);
}

}  // namespace
