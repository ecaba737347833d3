// skelcd inspect LOG.h5… — batch summary of many logs (table, CSV, JSON), the per-frame table of
// one log, the collision events of every log (docs/events.md), and PNG plots. Files that are not
// readable skelcd logs are reported by name on stderr and skipped; the command fails only when no
// file could be read (docs/check.md).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "skinning/errors.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/io/log/log_reader.hpp"
#include "tools/report/plot.hpp"

namespace skelcd::tools {
namespace {

struct InspectOptions {
  std::vector<std::string> logs;
  std::string sort;
  bool descending = false;
  bool csv = false;
  bool json = false;
  bool frames = false;
  bool events = false;
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
  if (v.is_null()) return "–";
  if (v.is_array()) {  // names: one field, "; " between them
    std::string text;
    for (const auto& item : v) text += (text.empty() ? "" : "; ") + cell_text(item);
    return text;
  }
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
      const bool number = values != nullptr && ((*values)[c].is_number() || (*values)[c].is_null());
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
      const std::string text = row[c].is_null()           ? std::string()
                               : row[c].is_number_float() ? row[c].dump()
                                                          : cell_text(row[c]);
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
  return "no (" + std::to_string(log.frames.size()) + "/" +
         std::to_string(log.header.planned_rows) + " rows)";
}

Table summary_table(const std::vector<std::pair<std::string, LogData>>& logs) {
  Table t;
  t.columns = {
      "log",
      "model",
      "clip",
      "method",
      "accuracy",
      "query",
      "frames",
      "intervals",
      "frames_with_contacts",
      "dcd_pairs",
      "ccd_contacts",
      "contacts",
      "max_candidate_pairs",
      "ms_per_interval",
      "complete",
      "events",
      "new_findings",
      "baseline_findings",
      "allowed_findings",
      "baseline"};
  for (const auto& [path, log] : logs) {
    const auto s = summarize(log.frames);
    const auto& h = log.header;
    t.rows.push_back(
        {path,
         model_name(h),
         h.clip,
         h.method,
         h.accuracy,
         h.query,
         s.samples,
         s.intervals,
         s.frames_with_contacts,
         s.dcd_pairs,
         s.ccd_vf + s.ccd_ee,
         s.dcd_pairs + s.ccd_vf + s.ccd_ee,
         s.max_candidate_pairs,
         s.ms_per_interval,
         completeness(log)});
    // Labelled logs only: an older log's findings are neither new nor baseline (null, "–").
    auto& row = t.rows.back();
    if (h.baseline.empty()) {
      row.insert(row.end(), {nullptr, nullptr, nullptr, nullptr, ""});
      continue;
    }
    const auto totals = summarize(log.frames, 0);
    row.push_back(
        log.events_recorded ? nlohmann::json(root_events(log.events).size()) : nlohmann::json());
    row.push_back(totals.new_dcd_pairs + totals.new_ccd_contacts);
    row.push_back(totals.baseline_dcd_pairs + totals.baseline_ccd_contacts);
    row.push_back(totals.allowed_dcd_pairs + totals.allowed_ccd_contacts);
    row.push_back(h.baseline);
  }
  return t;
}

/// Why a log has no events to list ("" when it has them, possibly none).
std::string missing_events(const LogData& log) {
  if (log.events_recorded) return "";
  if (log.header.baseline.empty()) return "no event data (log written before events)";
  if (!log.damage.empty()) return "no event data (the log is damaged before them)";
  return "no event data (the run did not finish)";
}

/// One row per event of every log, every field (--events, --csv, --json): bones and parts as
/// lists of names, t_first_contact and merged_into null when absent.
Table events_table(const std::vector<std::pair<std::string, LogData>>& logs) {
  Table t;
  t.columns = {
      "log",
      "clip",
      "event",
      "first_sample",
      "last_sample",
      "t_first",
      "t_last",
      "t_first_contact",
      "bones",
      "parts",
      "peak_pairs",
      "peak_sample",
      "dcd_pairs",
      "ccd_contacts",
      "depth",
      "merged_into"};
  for (const auto& [path, log] : logs) {
    for (const auto& e : log.events) {
      auto parts = nlohmann::json::array();
      for (const auto p : e.parts) {
        const auto k = static_cast<std::size_t>(p);
        parts.push_back(
            p >= 0 && k < log.header.part_names.size() ? log.header.part_names[k]
                                                       : "part " + std::to_string(p));
      }
      t.rows.push_back(
          {path,
           log.header.clip,
           e.id,
           e.first_sample,
           e.last_sample,
           e.t_first,
           e.t_last,
           e.t_first_contact ? nlohmann::json(*e.t_first_contact) : nlohmann::json(),
           e.bones,
           parts,
           e.peak_pairs,
           e.peak_sample >= 0 ? nlohmann::json(e.peak_sample) : nlohmann::json(),
           e.dcd_pairs,
           e.ccd_contacts,
           e.depth,
           e.merged_into >= 0 ? nlohmann::json(e.merged_into) : nlohmann::json()});
    }
  }
  return t;
}

/// "A, B, C +2": the first three names of a list and how many more.
std::string top_names(const nlohmann::json& names) {
  std::string text;
  std::size_t shown = 0;
  for (const auto& n : names) {
    if (shown == 3) break;
    text += (shown++ == 0 ? "" : ", ") + n.get<std::string>();
  }
  if (names.size() > shown) text += " +" + std::to_string(names.size() - shown);
  return text;
}

std::string number_text(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

/// The events for a terminal: event, samples a–b, time range, bones (top 3), parts, peak pairs,
/// depth, merged into; `with_log` keeps the log and clip columns (several logs).
Table events_text(const Table& full, bool with_log) {
  const auto at = [&](const char* name) {
    return static_cast<std::size_t>(
        std::find(full.columns.begin(), full.columns.end(), name) - full.columns.begin());
  };
  Table t;
  if (with_log) t.columns = {"log", "clip"};
  for (const char* c :
       {"event", "samples", "time_s", "bones", "parts", "peak_pairs", "depth", "merged_into"}) {
    t.columns.emplace_back(c);
  }
  for (const auto& r : full.rows) {
    auto& row = t.rows.emplace_back();
    if (with_log) row = {r[at("log")], r[at("clip")]};
    const auto first = r[at("first_sample")].get<std::int64_t>();
    const auto last = r[at("last_sample")].get<std::int64_t>();
    std::string time = number_text("%.3f", r[at("t_first")].get<double>()) + "–" +
                       number_text("%.3f", r[at("t_last")].get<double>());
    if (!r[at("t_first_contact")].is_null()) {
      time += " (contact " + number_text("%.3f", r[at("t_first_contact")].get<double>()) + ")";
    }
    std::string peak = std::to_string(r[at("peak_pairs")].get<std::int64_t>());
    if (!r[at("peak_sample")].is_null()) peak += " @ " + r[at("peak_sample")].dump();
    row.insert(
        row.end(),
        {r[at("event")],
         first == last ? std::to_string(first) : std::to_string(first) + "–" + std::to_string(last),
         time,
         top_names(r[at("bones")]),
         top_names(r[at("parts")]),
         peak,
         number_text("%.4g", r[at("depth")].get<double>()),
         r[at("merged_into")]});
  }
  return t;
}

/// "Hat:Body, adjacent bones" or "none".
std::string allowances(const LogHeader& h) {
  std::string text;
  for (const auto& rule : h.allow) text += (text.empty() ? "" : ", ") + rule;
  if (h.allow_adjacent_bones) text += std::string(text.empty() ? "" : ", ") + "adjacent bones";
  return text.empty() ? "none" : text;
}

/// The events section of the text output, before the summary (or the per-frame table): `full`
/// is events_table(logs), sorted as asked.
void print_events_text(
    const std::vector<std::pair<std::string, LogData>>& logs, const Table& full) {
  if (logs.size() == 1) {
    const auto& log = logs.front().second;
    const auto& h = log.header;
    const std::string missing = missing_events(log);
    if (!missing.empty()) {
      std::cout << "events: " << missing << '\n';
    } else if (full.rows.empty()) {
      std::cout << "events: none\n";
    } else {
      // As check counts them: events that ran into an older one are listed, not counted.
      const auto roots = root_events(log.events).size();
      std::cout << "events: " << roots;
      if (roots < log.events.size()) {
        std::cout << " (+" << log.events.size() - roots << " merged into an older one)";
      }
      std::cout << '\n';
      print_text(events_text(full, false));
    }
    if (!h.baseline.empty()) {
      const auto totals = summarize(log.frames, 0);
      std::cout << "baseline: " << totals.baseline_dcd_pairs << " DCD pairs, "
                << totals.baseline_ccd_contacts << " CCD contacts (" << h.baseline << ", slack "
                << h.baseline_slack << ")\n";
      std::cout << "allowed: " << totals.allowed_dcd_pairs << " DCD pairs, "
                << totals.allowed_ccd_contacts << " CCD contacts (" << allowances(h) << ")\n";
    }
    return;
  }
  std::cout << "events: " << full.rows.size() << " in " << logs.size() << " logs\n";
  if (!full.rows.empty()) print_text(events_text(full, true));
  for (const auto& [path, log] : logs) {
    const std::string missing = missing_events(log);
    if (!missing.empty()) {
      std::cout << path << ": " << missing << '\n';
    } else if (log.events.empty()) {
      std::cout << path << ": no events\n";
    }
  }
}

/// Lanes of the events timeline: one per log, a bar per event from t_first to t_last.
std::vector<PlotLane> event_lanes(const std::vector<std::pair<std::string, LogData>>& logs) {
  // Lanes are named by clip, or by log file when two logs share a clip name.
  std::map<std::string, int> clips;
  for (const auto& entry : logs) ++clips[entry.second.header.clip];
  std::vector<PlotLane> lanes;
  for (const auto& [path, log] : logs) {
    auto& lane = lanes.emplace_back();
    const auto& h = log.header;
    lane.label = clips[h.clip] > 1 || h.clip.empty()
                     ? std::filesystem::path(path).stem().string() + " (" + h.clip + ")"
                     : h.clip;
    if (!log.events_recorded) {
      lane.label += " (no event data)";
      continue;
    }
    if (!log.frames.empty()) {
      lane.span_begin = log.frames.front().t0;
      lane.span_end = log.frames.back().t1;
    }
    for (const auto& e : log.events) {
      lane.bars.push_back(PlotBar{e.t_first, e.t_last, e.id, std::to_string(e.id)});
    }
  }
  return lanes;
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
std::filesystem::path plot_path(
    const std::filesystem::path& dir, const std::string& log, std::set<std::string>& used) {
  const std::string stem = std::filesystem::path(log).stem().string();
  std::string name = stem + ".png";
  for (int k = 2; used.count(name) > 0; ++k) name = stem + "-" + std::to_string(k) + ".png";
  used.insert(name);
  return dir / name;
}

void run_inspect(const InspectOptions& o) {
  if (o.csv && o.json) throw InvalidInput("inspect: --csv and --json exclude each other");
  if (o.frames && o.events) throw InvalidInput("inspect: --frames and --events exclude each other");
  if (o.frames && o.logs.size() != 1) {
    throw InvalidInput(
        "inspect --frames: give exactly one log (got " + std::to_string(o.logs.size()) + ")");
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
      // One file given: its reason, naming it, is the whole answer (one line, exit status 1).
      if (o.logs.size() == 1) throw;
      std::cerr << "skelcd: " << e.what() << " (skipped)\n";
      ++skipped;
    }
  }
  if (logs.empty()) {
    throw IoError(
        o.logs.size() == 1
            ? o.logs.front() + ": no readable skelcd log"
            : "none of the " + std::to_string(o.logs.size()) + " files is a readable skelcd log");
  }

  Table events = events_table(logs);
  Table table = o.frames   ? frames_table(logs.front().second)
                : o.events ? events
                           : summary_table(logs);
  sort_table(table, o.sort, o.descending);
  if (o.events) events = table;

  // Plots, one PNG per log, and the events of every log on one timeline.
  std::vector<std::string> plots(logs.size());
  std::string timeline;
  if (!o.plot_dir.empty()) {
    const std::filesystem::path dir(o.plot_dir);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
      throw IoError(o.plot_dir + ": cannot create plot folder");
    }
    std::set<std::string> used{"events.png"};
    if (std::any_of(
            logs.begin(), logs.end(), [](const auto& l) { return l.second.events_recorded; })) {
      timeline = (dir / "events.png").string();
      write_events_timeline(timeline, event_lanes(logs), "collision events");
    }
    for (std::size_t i = 0; i < logs.size(); ++i) {
      const auto& [path, log] = logs[i];
      const auto png = plot_path(dir, path, used);
      const std::string title = model_name(log.header) + " / " + log.header.clip + " / " +
                                log.header.method + " (" + log.header.accuracy + ")";
      write_log_plot(png, log, title);
      plots[i] = png.string();
    }
  }

  // --events with --csv/--json: a log that has no events to list is named on stderr.
  if (o.events && (o.csv || o.json)) {
    for (const auto& [path, log] : logs) {
      if (const auto missing = missing_events(log); !missing.empty()) {
        std::cerr << path << ": " << missing << '\n';
      }
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
        if (!timeline.empty()) entry["events_plot"] = timeline;
      }
    }
    print_json(out);
  } else {
    if (o.csv) {
      print_csv(table);
    } else {
      // The events first: for one log its table and what its findings were compared with; over
      // many, every log's events.
      print_events_text(logs, events);
      if (!o.events) {
        std::cout << '\n';
        print_text(table);
      }
    }
    for (const auto& p : plots) {
      if (p.empty()) continue;
      (o.csv ? std::cerr : std::cout) << "plot: " << p << '\n';
    }
    if (!timeline.empty()) (o.csv ? std::cerr : std::cout) << "plot: " << timeline << '\n';
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
      "inspect",
      "Summarise skelcd logs: their collision events, one row per log (or per event, or per frame "
      "of one log); plots");
  cmd->add_option("logs", options->logs, "LOG.h5 files written by `skelcd check`")->required();
  cmd->add_option("--sort", options->sort, "sort rows by this column (ascending)");
  cmd->add_flag("--desc", options->descending, "sort descending");
  cmd->add_flag("--csv", options->csv, "print CSV instead of a table");
  cmd->add_flag("--json", options->json, "print JSON instead of a table");
  cmd->add_flag("--frames", options->frames, "per-frame table of one log");
  cmd->add_flag(
      "--events",
      options->events,
      "one row per collision event of every log (with --csv/--json: every field)");
  cmd->add_option(
      "--plot",
      options->plot_dir,
      "write one PNG plot per log, and the events of every log on a timeline "
      "(events.png), into this folder");
  cmd->callback([options] { run_inspect(*options); });
}

}  // namespace skelcd::tools
