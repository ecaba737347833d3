// skelcd inspect LOG.h5… — batch summary of many logs (table, CSV, JSON), the per-frame table of
// one log, and per-log PNG plots. Files that are not readable skelcd logs are reported by name on
// stderr and skipped; the command fails only when no file could be read (docs/check.md).

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "skinning/errors.hpp"
#include "tools/cli_util.hpp"
#include "tools/commands.hpp"
#include "tools/log/log_reader.hpp"
#include "tools/plot.hpp"
#include "tools/run_summary.hpp"

namespace skelcd::tools {
namespace {

struct InspectOptions {
  std::vector<std::string> logs;
  std::string sort;
  bool descending = false;
  bool csv = false;
  bool json = false;
  bool frames = false;
  std::string plot_dir;
};

/// A table whose cells are JSON values: numbers stay numbers for --json and for sorting.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<nlohmann::json>> rows;
};

std::string cell_text(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) {
    char text[64];
    std::snprintf(text, sizeof text, "%.3f", v.get<double>());
    return text;
  }
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_null()) return "";
  return v.dump();
}

/// Columns a text takes on a terminal: UTF-8 code points (continuation bytes do not count).
std::size_t display_width(const std::string& text) {
  std::size_t n = 0;
  for (const char c : text) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1 : 0;
  return n;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + '"';
}

void sort_table(Table& table, const std::string& column, bool descending) {
  if (column.empty()) return;
  const auto it = std::find(table.columns.begin(), table.columns.end(), column);
  if (it == table.columns.end()) {
    std::string known;
    for (const auto& c : table.columns) known += (known.empty() ? "" : ", ") + c;
    throw InvalidInput("--sort: unknown column '" + column + "' (columns: " + known + ")");
  }
  const auto k = static_cast<std::size_t>(it - table.columns.begin());
  std::stable_sort(table.rows.begin(), table.rows.end(), [&](const auto& a, const auto& b) {
    return descending ? b[k] < a[k] : a[k] < b[k];
  });
}

void print_text(const Table& table) {
  std::vector<std::vector<std::string>> text;
  std::vector<std::size_t> width(table.columns.size());
  for (std::size_t c = 0; c < table.columns.size(); ++c) width[c] = display_width(table.columns[c]);
  for (const auto& row : table.rows) {
    auto& line = text.emplace_back();
    for (std::size_t c = 0; c < row.size(); ++c) {
      line.push_back(cell_text(row[c]));
      width[c] = std::max(width[c], display_width(line.back()));
    }
  }
  const auto print_line = [&](const std::vector<std::string>& cells,
                              const std::vector<nlohmann::json>* values) {
    std::string out;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const bool number = values != nullptr && (*values)[c].is_number();
      const std::string pad(width[c] - display_width(cells[c]), ' ');
      out += (c == 0 ? "" : "  ") + (number ? pad + cells[c] : cells[c] + pad);
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    std::cout << out << '\n';
  };
  print_line(table.columns, nullptr);
  for (std::size_t r = 0; r < text.size(); ++r) print_line(text[r], &table.rows[r]);
}

void print_csv(const Table& table) {
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    std::cout << (c == 0 ? "" : ",") << csv_field(table.columns[c]);
  }
  std::cout << '\n';
  for (const auto& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string text = row[c].is_number_float() ? row[c].dump() : cell_text(row[c]);
      std::cout << (c == 0 ? "" : ",") << csv_field(text);
    }
    std::cout << '\n';
  }
}

nlohmann::json table_json(const Table& table) {
  auto array = nlohmann::json::array();
  for (const auto& row : table.rows) {
    nlohmann::json object;
    for (std::size_t c = 0; c < row.size(); ++c) object[table.columns[c]] = row[c];
    array.push_back(std::move(object));
  }
  return array;
}

std::string model_name(const LogHeader& h) {
  return std::filesystem::path(h.input_path).filename().string();
}

std::string completeness(const LogData& log) {
  if (!log.damage.empty()) {
    return "damaged (" + std::to_string(log.frames.size()) + "/" +
           std::to_string(log.header.planned_rows) + " rows readable)";
  }
  if (log.header.complete) return "yes";
  return "no (" + std::to_string(log.frames.size()) + "/" + std::to_string(log.header.planned_rows) +
         " rows)";
}

Table summary_table(const std::vector<std::pair<std::string, LogData>>& logs) {
  Table t;
  t.columns = {"log",       "model",        "clip",        "method",
               "accuracy",  "query",        "frames",      "intervals",
               "frames_with_contacts",      "dcd_pairs",   "ccd_contacts",
               "contacts",  "max_candidate_pairs",         "ms_per_interval",
               "complete"};
  for (const auto& [path, log] : logs) {
    const auto s = summarize(log.frames);
    const auto& h = log.header;
    t.rows.push_back({path, model_name(h), h.clip, h.method, h.accuracy, h.query, s.samples,
                      s.intervals, s.frames_with_contacts, s.dcd_pairs, s.ccd_vf + s.ccd_ee,
                      s.dcd_pairs + s.ccd_vf + s.ccd_ee, s.max_candidate_pairs, s.ms_per_interval,
                      completeness(log)});
  }
  return t;
}

Table frames_table(const LogData& log) {
  // Every counter and stage of the log's one table of them (culling/frame_result.hpp), the stages
  // in milliseconds.
  Table t;
  t.columns = {"sample", "kind", "t0", "t1"};
#define SKELCD_COUNTER_COLUMN(name, meaning) t.columns.push_back(#name);
  SKELCD_COUNTERS(SKELCD_COUNTER_COLUMN)
#undef SKELCD_COUNTER_COLUMN
  for (const std::string stage : {
#define SKELCD_STAGE_NAME(name, meaning) #name,
           SKELCD_STAGE_TIMES(SKELCD_STAGE_NAME)
#undef SKELCD_STAGE_NAME
               "total_us"}) {
    t.columns.push_back(stage.substr(0, stage.size() - 3) + "_ms");
  }
  for (const auto& r : log.frames) {
    auto& row = t.rows.emplace_back();
    row = {r.sample, std::string(to_string(r.kind)), r.t0, r.t1};
#define SKELCD_COUNTER_CELL(name, meaning) row.push_back(r.counters.name);
    SKELCD_COUNTERS(SKELCD_COUNTER_CELL)
#undef SKELCD_COUNTER_CELL
#define SKELCD_STAGE_CELL(name, meaning) row.push_back(r.times.name / 1000.0);
    SKELCD_STAGE_TIMES(SKELCD_STAGE_CELL)
#undef SKELCD_STAGE_CELL
    row.push_back(r.total_us / 1000.0);
  }
  return t;
}

/// DIR/<stem>.png, with -2, -3, … appended when two logs share a stem.
std::filesystem::path plot_path(const std::filesystem::path& dir, const std::string& log,
                                std::set<std::string>& used) {
  const std::string stem = std::filesystem::path(log).stem().string();
  std::string name = stem + ".png";
  for (int k = 2; used.count(name) > 0; ++k) name = stem + "-" + std::to_string(k) + ".png";
  used.insert(name);
  return dir / name;
}

void run_inspect(const InspectOptions& o) {
  if (o.csv && o.json) throw InvalidInput("inspect: --csv and --json exclude each other");
  if (o.frames && o.logs.size() != 1) {
    throw InvalidInput("inspect --frames: give exactly one log (got " +
                       std::to_string(o.logs.size()) + ")");
  }
  // Read every log; report and skip the ones that are not readable skelcd logs.
  std::vector<std::pair<std::string, LogData>> logs;
  std::size_t skipped = 0;
  std::size_t damaged = 0;
  for (const auto& path : o.logs) {
    try {
      auto log = read_log(path, ReadLogOptions{.findings = false});
      if (!log.damage.empty()) {
        // Summarised from the rows before the damage; the exit status still says it.
        std::cerr << "skelcd: " << path << ": " << log.damage.front() << "; the "
                  << log.frames.size() << " rows written before it are read\n";
        ++damaged;
      }
      logs.emplace_back(path, std::move(log));
    } catch (const std::exception& e) {
      std::cerr << "skelcd: " << e.what() << " (skipped)\n";
      ++skipped;
    }
  }
  if (logs.empty()) {
    throw IoError(o.logs.size() == 1 ? o.logs.front() + ": no readable skelcd log"
                                     : "none of the " + std::to_string(o.logs.size()) +
                                           " files is a readable skelcd log");
  }

  Table table = o.frames ? frames_table(logs.front().second) : summary_table(logs);
  sort_table(table, o.sort, o.descending);

  // Plots, one PNG per log.
  std::vector<std::string> plots(logs.size());
  if (!o.plot_dir.empty()) {
    const std::filesystem::path dir(o.plot_dir);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
      throw IoError(o.plot_dir + ": cannot create plot folder");
    }
    std::set<std::string> used;
    for (std::size_t i = 0; i < logs.size(); ++i) {
      const auto& [path, log] = logs[i];
      const auto png = plot_path(dir, path, used);
      const std::string title = model_name(log.header) + " / " + log.header.clip + " / " +
                                log.header.method + " (" + log.header.accuracy + ")";
      write_log_plot(png, log, title);
      plots[i] = png.string();
    }
  }

  if (o.json) {
    nlohmann::json out;
    if (o.frames) {
      out = nlohmann::json{{"log", logs.front().first}, {"rows", table_json(table)}};
      if (!plots.front().empty()) out["plot"] = plots.front();
    } else {
      out = table_json(table);
      for (auto& entry : out) {
        for (std::size_t i = 0; i < logs.size(); ++i) {
          if (entry["log"] == logs[i].first && !plots[i].empty()) entry["plot"] = plots[i];
        }
      }
    }
    print_json(out);
  } else {
    if (o.csv) {
      print_csv(table);
    } else {
      print_text(table);
    }
    for (const auto& p : plots) {
      if (p.empty()) continue;
      (o.csv ? std::cerr : std::cout) << "plot: " << p << '\n';
    }
  }
  // The readable logs are summarised above; a script still learns that some were not (as a
  // batch `check` that had failures).
  if (skipped > 0) {
    throw IoError(
        std::to_string(skipped) + " of " + std::to_string(o.logs.size()) +
        " files skipped: not readable skelcd logs (named above)");
  }
  if (damaged > 0) {
    throw IoError(
        std::to_string(damaged) + " of " + std::to_string(o.logs.size()) +
        " logs are damaged (named above); their rows before the damage are summarised");
  }
}

}  // namespace

void add_inspect_command(CLI::App& app) {
  auto options = std::make_shared<InspectOptions>();
  auto* cmd = app.add_subcommand(
      "inspect", "Summarise skelcd logs: one row per log, or per frame of one log; plots");
  cmd->add_option("logs", options->logs, "LOG.h5 files written by `skelcd check`")->required();
  cmd->add_option("--sort", options->sort, "sort rows by this column (ascending)");
  cmd->add_flag("--desc", options->descending, "sort descending");
  cmd->add_flag("--csv", options->csv, "print CSV instead of a table");
  cmd->add_flag("--json", options->json, "print JSON instead of a table");
  cmd->add_flag("--frames", options->frames, "per-frame table of one log");
  cmd->add_option("--plot", options->plot_dir, "write one PNG plot per log into this folder");
  cmd->callback([options] { run_inspect(*options); });
}

}  // namespace skelcd::tools
