#include "tools/cli/cli_util.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>

#include "skinning/errors.hpp"

namespace skelcd::tools {

void print_json(const nlohmann::json& object) { std::cout << object.dump(2) << '\n'; }

CLI::Option* add_rate_option(
    CLI::App& command, const std::string& names, double& rate, const std::string& help) {
  const std::string flag = names.substr(0, names.find(','));
  return command
      .add_option_function<double>(
          names,
          [&rate, flag](double value) {
            if (!(std::isfinite(value) && value > 0)) {
              char text[64];
              std::snprintf(text, sizeof text, "%g", value);
              throw InvalidInput(flag + " " + text + ": expected a rate > 0 (samples/s)");
            }
            rate = value;
          },
          help)
      ->type_name("HZ");
}

void require_exists(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(path.string() + ": no such file");
}

}  // namespace skelcd::tools
