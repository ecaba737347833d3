#include "tools/report/bench_report.hpp"

#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <ostream>
#include <sstream>
#include <system_error>
#include <utility>

#include "culling/method.hpp"
#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"
#include "tools/report/plplot_library.hpp"
#include "tools/report/progress.hpp"
#include "tools/report/summary_json.hpp"

namespace skelcd::tools {
namespace {

constexpr std::array<ccd::Accuracy, 3> kAllAccuracies{
    ccd::Accuracy::exact, ccd::Accuracy::conservative, ccd::Accuracy::fast};

/// Rows the run will produce, estimated from the frame range before any runner validates it
/// (ClipRunner refuses a bad range with its own message afterwards).
std::int64_t estimated_rows(const skinning::Motion& motion, const RunOptions& options) {
  const std::int64_t n = motion.num_samples();
  const std::int64_t first =
      std::clamp<std::int64_t>(options.frames.first, 0, std::max<std::int64_t>(n - 1, 0));
  const std::int64_t last = std::clamp<std::int64_t>(
      options.frames.last.value_or(static_cast<std::int32_t>(n - 1)),
      first,
      std::max<std::int64_t>(n - 1, 0));
  const std::int64_t samples = last - first + 1;
  const std::int64_t dcd = options.query != QuerySet::ccd ? samples : 0;
  const std::int64_t ccd = options.query != QuerySet::dcd ? samples - 1 : 0;
  return dcd + ccd;
}

/// What one run produced: its rows and its findings, sorted and duplicate-free.
struct RunOutput {
  RunPlan plan;
  std::vector<FrameRow> rows;
  std::vector<FindingKey> findings;
};

RunOutput run_one(
    const skinning::Motion& motion,
    const BenchOptions& options,
    const std::string& method,
    ccd::Accuracy accuracy,
    const std::string& label) {
  RunOptions run = options.run;
  run.method = method;
  run.accuracy = accuracy;
  if (options.prepare) options.prepare(run);
  MethodFactory factory;
  if (options.factory) factory = options.factory(method, accuracy);
  ClipRunner runner(motion, run, factory);

  RunOutput out;
  out.plan = runner.plan();
  out.rows.reserve(static_cast<std::size_t>(runner.plan().rows));
  std::optional<Progress> progress;
  if (options.progress) progress.emplace(label, runner.plan().rows);
  runner.run([&](const FrameReport& report) {
    out.rows.push_back(report.row);
    append_finding_keys(report, out.findings);
    if (progress) progress->update(static_cast<std::int64_t>(out.rows.size()));
  });
  if (progress) progress->finish();
  std::sort(out.findings.begin(), out.findings.end());
  out.findings.erase(std::unique(out.findings.begin(), out.findings.end()), out.findings.end());
  return out;
}

BenchRow make_row(const std::string& method, ccd::Accuracy accuracy, const RunOutput& run) {
  BenchRow row;
  row.method = method;
  row.accuracy = accuracy;
  row.summary = summarize(run.rows, 0);
  for (const auto& r : run.rows) {
    const auto& c = r.counters;
    row.elementary_tests += c.vf_tests + c.ee_tests + c.tt_tests;
    row.contacts += findings(r);
  }
  return row;
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

/// Decimals that keep about four significant digits of a time in ms.
int time_decimals(double ms) {
  if (ms >= 100) return 1;
  if (ms >= 10) return 2;
  if (ms >= 1) return 3;
  return 4;
}

}  // namespace

void append_finding_keys(const FrameReport& report, std::vector<FindingKey>& keys) {
  for (const auto& p : report.dcd_pairs) {
    keys.push_back(
        FindingKey{p.frame, 0, 0, p.a.part, p.a.index, p.a.side, p.b.part, p.b.index, p.b.side});
  }
  for (const auto& c : report.contacts) {
    keys.push_back(FindingKey{
        c.frame,
        1,
        static_cast<std::int32_t>(c.kind),
        c.a.part,
        c.a.index,
        c.a.side,
        c.b.part,
        c.b.index,
        c.b.side});
  }
}

FindingDifference compare_findings(
    std::span<const FindingKey> reference, std::span<const FindingKey> run) {
  assert(std::is_sorted(reference.begin(), reference.end()));
  assert(std::is_sorted(run.begin(), run.end()));
  // One merge pass over both sorted lists.
  FindingDifference d;
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < reference.size() && j < run.size()) {
    if (reference[i] < run[j]) {
      ++d.false_negatives;
      ++i;
    } else if (run[j] < reference[i]) {
      ++d.false_positives;
      ++j;
    } else {
      ++i;
      ++j;
    }
  }
  d.false_negatives += static_cast<std::int64_t>(reference.size() - i);
  d.false_positives += static_cast<std::int64_t>(run.size() - j);
  return d;
}

std::optional<ReferenceChoice> parse_reference_choice(std::string_view name) {
  if (name == "auto") return ReferenceChoice::automatic;
  if (name == "brute") return ReferenceChoice::brute;
  if (name == "bvh") return ReferenceChoice::bvh;
  return std::nullopt;
}

double brute_cost(std::int64_t triangles, std::int64_t rows) {
  const auto t = static_cast<double>(triangles);
  return t * t * static_cast<double>(rows);
}

ReferencePick pick_reference(
    ReferenceChoice choice, std::int64_t triangles, std::int64_t rows, double budget) {
  char cost[128];
  std::snprintf(cost, sizeof cost, "%.3g triangles² × rows", brute_cost(triangles, rows));
  switch (choice) {
    case ReferenceChoice::brute:
      return {"brute", std::string("forced by --reference (estimated brute force ") + cost + ")"};
    case ReferenceChoice::bvh:
      return {"bvh", "forced by --reference"};
    case ReferenceChoice::automatic:
      break;
  }
  char text[256];
  if (brute_cost(triangles, rows) <= budget) {
    std::snprintf(text, sizeof text, "brute force fits: %s <= budget %.3g", cost, budget);
    return {"brute", text};
  }
  std::snprintf(text, sizeof text, "brute force too slow: %s > budget %.3g", cost, budget);
  return {"bvh", text};
}

void validate_methods(std::span<const std::string> methods, bool radial_view) {
  const std::vector<std::string> known = culling::method_names();
  for (const auto& m : methods) {
    if (std::find(known.begin(), known.end(), m) != known.end()) {
      if (culling::method_needs(m).bone_poses && !radial_view) {
        throw InvalidInput(
            "--methods: '" + m + "' needs a rigged model (bones move the observers)");
      }
      continue;
    }
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InvalidInput("--methods: unknown method '" + m + "' (known: " + list + ")");
  }
}

BenchReport run_bench(const skinning::Motion& motion, const BenchOptions& options) {
  validate_methods(options.methods, options.radial_view);
  if (options.run.min_separation != 0.0) {
    throw InvalidInput("bench: the exact reference supports only min_separation = 0");
  }

  BenchReport report;
  report.motion = motion.name();
  report.triangles = motion.mesh().num_triangles();
  report.query = options.run.query;
  const std::int64_t rows = estimated_rows(motion, options.run);
  report.reference =
      pick_reference(options.reference, report.triangles, rows, options.brute_budget);

  // The table's methods: the ones asked for, else every method (brute only when it fits).
  std::vector<std::string> methods = options.methods;
  if (methods.empty()) {
    const bool brute_fits = brute_cost(report.triangles, rows) <= options.brute_budget ||
                            report.reference.method == "brute";
    for (const auto& m : culling::method_names()) {
      // Methods that need bone poses run on a rig's clip only.
      if (culling::method_needs(m).bone_poses && !options.radial_view) continue;
      if (m == "brute" && !brute_fits) {
        report.notes.push_back(
            "brute left out: estimated brute force over the budget (name it in --methods to run "
            "it anyway)");
        continue;
      }
      methods.push_back(m);
    }
  }
  std::vector<ccd::Accuracy> accuracies = options.accuracies;
  if (accuracies.empty()) accuracies.assign(kAllAccuracies.begin(), kAllAccuracies.end());

  const std::size_t total_runs = methods.size() * accuracies.size();
  std::size_t run_index = 0;
  const auto label = [&](const std::string& method, ccd::Accuracy accuracy) {
    return "bench " + method + "/" + std::string(ccd::to_string(accuracy)) + " (" +
           std::to_string(run_index) + "/" + std::to_string(total_runs) + ")";
  };

  // The reference first: every other run is compared with its findings.
  const std::string& reference_method = report.reference.method;
  const auto reference = run_one(
      motion,
      options,
      reference_method,
      ccd::Accuracy::exact,
      "bench reference " + reference_method + "/exact");
  report.reference_contacts = static_cast<std::int64_t>(reference.findings.size());
  report.plan = reference.plan;  // every run of these options resolves the same plan

  for (const auto& method : methods) {
    for (const auto accuracy : accuracies) {
      ++run_index;
      if (method == reference_method && accuracy == ccd::Accuracy::exact) {
        auto row = make_row(method, accuracy, reference);
        row.reference = true;
        report.rows.push_back(std::move(row));
        continue;
      }
      const auto run = run_one(motion, options, method, accuracy, label(method, accuracy));
      auto row = make_row(method, accuracy, run);
      const auto d = compare_findings(reference.findings, run.findings);
      row.false_negatives = d.false_negatives;
      row.false_positives = d.false_positives;
      report.rows.push_back(std::move(row));
    }
  }
  return report;
}

void print_bench_table(std::ostream& out, const BenchReport& report) {
  std::size_t method_width = 6;
  for (const auto& r : report.rows) method_width = std::max(method_width, r.method.size());
  const auto w = static_cast<int>(method_width);
  char line[512];
  out << "motion    " << report.motion << ": " << report.triangles << " triangles, samples "
      << report.plan.first_sample << ".." << report.plan.last_sample << " (" << report.plan.samples
      << " samples, " << report.plan.intervals << " intervals), query " << to_string(report.query)
      << "\n";
  out << "reference " << report.reference.method << " + exact (" << report.reference.reason
      << "): " << report.reference_contacts << " findings\n";
  for (const auto& note : report.notes) out << "note      " << note << "\n";
  out << "times in ms per " << (report.plan.intervals > 0 ? "interval" : "sample")
      << "; FN/FP against the reference (* marks it)\n\n";
  std::snprintf(
      line,
      sizeof line,
      "  %-*s %-12s %10s %8s %8s %8s %8s %8s %8s %8s %12s %12s %12s %9s %7s %7s\n",
      w,
      "method",
      "accuracy",
      "ms/int",
      "skin",
      "refit",
      "classify",
      "merge",
      "traverse",
      "elem",
      "other",
      "bv_tests",
      "cand_pairs",
      "elem_tests",
      "contacts",
      "FN",
      "FP");
  out << line;
  for (const auto& r : report.rows) {
    const auto& s = r.summary;
    const auto t = [](double ms) { return fixed(ms, time_decimals(ms)); };
    std::snprintf(
        line,
        sizeof line,
        "%c %-*s %-12s %10s %8s %8s %8s %8s %8s %8s %8s %12lld %12lld %12lld %9lld %7lld %7lld\n",
        r.reference ? '*' : ' ',
        w,
        r.method.c_str(),
        std::string(ccd::to_string(r.accuracy)).c_str(),
        t(s.ms_per_interval).c_str(),
        t(s.skin_ms).c_str(),
        t(s.refit_ms).c_str(),
        t(s.classify_ms).c_str(),
        t(s.merge_ms).c_str(),
        t(s.traverse_ms).c_str(),
        t(s.elementary_ms).c_str(),
        t(s.other_ms).c_str(),
        static_cast<long long>(s.bv_tests),
        static_cast<long long>(s.candidate_pairs),
        static_cast<long long>(r.elementary_tests),
        static_cast<long long>(r.contacts),
        static_cast<long long>(r.false_negatives),
        static_cast<long long>(r.false_positives));
    out << line;
  }
}

std::string bench_csv(const BenchReport& report) {
  std::ostringstream csv;
  csv << "method,accuracy,ms_per_interval,bv_tests,candidate_pairs,contacts,false_negatives,"
         "false_positives,skin_ms,refit_ms,classify_ms,merge_ms,traverse_ms,elementary_ms,"
         "other_ms,elementary_tests,dcd_pairs,ccd_vf,ccd_ee,reference\n";
  const auto ms = [](double v) {
    char text[64];
    std::snprintf(text, sizeof text, "%.6f", v);
    return std::string(text);
  };
  for (const auto& r : report.rows) {
    const auto& s = r.summary;
    csv << r.method << ',' << ccd::to_string(r.accuracy) << ',' << ms(s.ms_per_interval) << ','
        << s.bv_tests << ',' << s.candidate_pairs << ',' << r.contacts << ',' << r.false_negatives
        << ',' << r.false_positives << ',' << ms(s.skin_ms) << ',' << ms(s.refit_ms) << ','
        << ms(s.classify_ms) << ',' << ms(s.merge_ms) << ',' << ms(s.traverse_ms) << ','
        << ms(s.elementary_ms) << ',' << ms(s.other_ms) << ',' << r.elementary_tests << ','
        << s.dcd_pairs << ',' << s.ccd_vf << ',' << s.ccd_ee << ',' << (r.reference ? 1 : 0)
        << '\n';
  }
  return csv.str();
}

nlohmann::json bench_json(const BenchReport& report) {
  auto rows = nlohmann::json::array();
  for (const auto& r : report.rows) {
    const auto& s = r.summary;
    rows.push_back(
        {{"method", r.method},
         {"accuracy", std::string(ccd::to_string(r.accuracy))},
         {"reference", r.reference},
         {"ms_per_interval", s.ms_per_interval},
         {"stages_ms", stages_json(s)},
         {"bv_tests", s.bv_tests},
         {"candidate_pairs", s.candidate_pairs},
         {"elementary_tests", r.elementary_tests},
         {"contacts", r.contacts},
         {"dcd_pairs", s.dcd_pairs},
         {"ccd_vf", s.ccd_vf},
         {"ccd_ee", s.ccd_ee},
         {"false_negatives", r.false_negatives},
         {"false_positives", r.false_positives}});
  }
  return nlohmann::json{
      {"motion", report.motion},
      {"triangles", report.triangles},
      {"first_sample", report.plan.first_sample},
      {"last_sample", report.plan.last_sample},
      {"samples", report.plan.samples},
      {"intervals", report.plan.intervals},
      {"query", std::string(to_string(report.query))},
      {"reference",
       {{"method", report.reference.method},
        {"accuracy", "exact"},
        {"reason", report.reference.reason},
        {"findings", report.reference_contacts}}},
      {"notes", report.notes},
      {"rows", rows},
  };
}

namespace {

// Plot colours (cmap0 indices 2…): one per method, in table order.
constexpr std::array<std::array<int, 3>, 10> kMethodColours{{
    {31, 119, 180},   // blue
    {214, 39, 40},    // red
    {44, 160, 44},    // green
    {255, 127, 14},   // orange
    {148, 103, 189},  // purple
    {140, 86, 75},    // brown
    {227, 119, 194},  // pink
    {23, 190, 207},   // cyan
    {188, 189, 34},   // olive
    {127, 127, 127},  // grey
}};
constexpr PLINT kGridColour = 15;

/// Marker of an accuracy (a glyph cairo draws in the text font).
const char* marker(ccd::Accuracy accuracy) {
  switch (accuracy) {
    case ccd::Accuracy::exact:
      return "●";
    case ccd::Accuracy::conservative:
      return "■";
    case ccd::Accuracy::fast:
      return "▲";
  }
  return "●";
}

}  // namespace

void write_bench_plot(
    const std::filesystem::path& path, const BenchReport& report, const std::string& title) {
  const std::string name = path.string();
  (void)detail::plplot();  // PLplot itself first (opened on first use): without it, no file
  {
    // PLplot reports a file it cannot open by exiting the process; check writability first.
    std::ofstream probe(path, std::ios::binary | std::ios::trunc);
    if (!probe) throw IoError(name + ": cannot write plot");
  }

  // Data: x = false negatives, y = log10(ms per interval).
  std::vector<std::string> methods;
  for (const auto& r : report.rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) {
      methods.push_back(r.method);
    }
  }
  std::vector<double> xs;
  std::vector<double> ys;
  for (const auto& r : report.rows) {
    xs.push_back(static_cast<double>(r.false_negatives));
    ys.push_back(std::log10(std::max(r.summary.ms_per_interval, 1e-6)));
  }
  double x_max = 0;
  double y_min = 0;
  double y_max = 1;
  if (!xs.empty()) {
    x_max = *std::max_element(xs.begin(), xs.end());
    y_min = *std::min_element(ys.begin(), ys.end());
    y_max = *std::max_element(ys.begin(), ys.end());
  }
  // Whole decades around the times. The x range leaves room on the right for the labels of the
  // rightmost points (about 40% of the width); FN ticks are whole numbers.
  y_min = std::floor(y_min - 0.05);
  y_max = std::ceil(y_max + 0.05);
  const double x_span = std::max(x_max, 1.0);
  const double x_lo = -0.06 * x_span;
  const double x_hi = x_lo + (x_span - x_lo) / 0.58;
  double x_tick = std::pow(10.0, std::floor(std::log10((x_hi - x_lo) / 8.0)));
  for (const double m : {2.0, 5.0, 10.0}) {
    if ((x_hi - x_lo) / x_tick <= 10.0) break;
    x_tick = std::pow(10.0, std::floor(std::log10((x_hi - x_lo) / 8.0))) * m;
  }
  x_tick = std::max(x_tick, 1.0);

  constexpr PLINT kWidth = 1100;
  constexpr PLINT kHeight = 800;
  PLINT stream = 0;
  plmkstrm(&stream);
  if (stream < 0) throw IoError(name + ": PLplot has no free stream");
  plsdev("pngcairo");
  plsfnam(name.c_str());
  plspage(0.0, 0.0, kWidth, kHeight, 0, 0);
  plscolbg(255, 255, 255);
  plinit();
  plscol0(1, 0, 0, 0);
  plscol0(kGridColour, 220, 220, 220);
  for (std::size_t i = 0; i < kMethodColours.size(); ++i) {
    const auto& c = kMethodColours[i];
    plscol0(static_cast<PLINT>(2 + i), c[0], c[1], c[2]);
  }
  plschr(0.0, 1.0);
  pladv(0);
  constexpr double kLeft = 0.10, kRight = 0.97, kBottom = 0.10, kTop = 0.88;
  plvpor(kLeft, kRight, kBottom, kTop);
  plwind(x_lo, x_hi, y_min, y_max);
  plcol0(kGridColour);
  plbox("g", x_tick, 0, "g", 1.0, 0);
  plcol0(1);
  plbox("bcnst", x_tick, 0, "bcnstvl", 0.0, 0);
  pllab("missed collisions (false negatives against the reference)", "ms per interval (log)", "");
  plmtex("t", 3.2, 0.5, 0.5, title.c_str());
  std::string key = "exact ● conservative ■ fast ▲ — reference: " + report.reference.method +
                    " + exact (" + std::to_string(report.reference_contacts) + " findings)";
  plschr(0.0, 0.85);
  plmtex("t", 1.4, 0.5, 0.5, key.c_str());

  // Character size (at scale 1) in normalised viewport units, for the label boxes; cairo's
  // sans glyphs average ~0.72 of the character height in width.
  plschr(0.0, 1.0);
  PLFLT default_height = 0;
  PLFLT height_mm = 0;
  plgchr(&default_height, &height_mm);
  PLFLT page_x0 = 0, page_x1 = 0, page_y0 = 0, page_y1 = 0;
  plgspa(&page_x0, &page_x1, &page_y0, &page_y1);
  const double char_h = height_mm / ((page_y1 - page_y0) * (kTop - kBottom));
  const double char_w = 0.72 * height_mm / ((page_x1 - page_x0) * (kRight - kLeft));
  const auto to_nx = [&](double x) { return (x - x_lo) / (x_hi - x_lo); };
  const auto to_ny = [&](double y) { return (y - y_min) / (y_max - y_min); };
  const auto from_ny = [&](double ny) { return y_min + ny * (y_max - y_min); };

  // Labels: each starts just right of its point. Points whose labels would share horizontal space
  // form a column; a column's labels keep the order of their points' times and are pushed apart
  // vertically to one line each (a forward pass up, then a pass down from the top edge), with a
  // thin leader from a moved label to its point. A column too tall for the plot shrinks the font.
  const std::size_t n = report.rows.size();
  std::vector<std::string> texts(n);
  std::vector<PLINT> colours(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& r = report.rows[i];
    colours[i] = static_cast<PLINT>(
        2 + (std::find(methods.begin(), methods.end(), r.method) - methods.begin()) %
                static_cast<std::ptrdiff_t>(kMethodColours.size()));
    texts[i] = r.method + " " + std::string(ccd::to_string(r.accuracy)) +
               (r.reference ? " (ref)" : "") + "  " +
               fixed(r.summary.ms_per_interval, time_decimals(r.summary.ms_per_interval)) + " ms";
  }
  std::vector<std::size_t> by_x(n);
  for (std::size_t i = 0; i < n; ++i) by_x[i] = i;
  std::stable_sort(
      by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) { return xs[a] < xs[b]; });
  double scale = 0.8;
  std::vector<std::vector<std::size_t>> columns;
  for (int attempt = 0; attempt < 2; ++attempt) {
    columns.clear();
    double column_right = -1;
    for (const std::size_t i : by_x) {
      const double left = to_nx(xs[i]) + 0.9 * char_w;
      const double right = left + scale * char_w * static_cast<double>(texts[i].size());
      if (columns.empty() || left > column_right) {
        columns.emplace_back();
        column_right = right;
      } else {
        column_right = std::max(column_right, right);
      }
      columns.back().push_back(i);
    }
    std::size_t tallest = 0;
    for (const auto& c : columns) tallest = std::max(tallest, c.size());
    const double needed = static_cast<double>(tallest) * 1.15 * scale * char_h;
    if (needed <= 0.96) break;
    scale = std::max(0.45, scale * 0.96 / needed);
  }
  const double line = 1.15 * scale * char_h;
  std::vector<double> label_ny(n);
  for (auto& column : columns) {
    std::stable_sort(
        column.begin(), column.end(), [&](std::size_t a, std::size_t b) { return ys[a] < ys[b]; });
    double previous = -1e9;
    for (const std::size_t i : column) {
      label_ny[i] = std::max({to_ny(ys[i]), previous + line, 0.5 * line});
      previous = label_ny[i];
    }
    double next = 1e9;
    for (auto it = column.rbegin(); it != column.rend(); ++it) {
      label_ny[*it] = std::min({label_ny[*it], next - line, 1.0 - 0.5 * line});
      next = label_ny[*it];
    }
  }
  plschr(0.0, scale);
  for (std::size_t i = 0; i < n; ++i) {
    const double nx = to_nx(xs[i]) + 0.9 * char_w;
    const PLFLT label_x = x_lo + nx * (x_hi - x_lo);
    const PLFLT label_y = from_ny(label_ny[i]);
    plcol0(colours[i]);
    if (std::abs(label_ny[i] - to_ny(ys[i])) > 0.25 * line) {
      PLFLT lx[2] = {xs[i], label_x};
      PLFLT ly[2] = {ys[i], label_y};
      plwidth(0.5);
      plline(2, lx, ly);
      plwidth(1.0);
    }
    plptex(label_x, label_y, 1.0, 0.0, 0.0, texts[i].c_str());
  }
  plschr(0.0, 1.3);
  for (std::size_t i = 0; i < n; ++i) {
    plcol0(colours[i]);
    PLFLT px = xs[i];
    PLFLT py = ys[i];
    plstring(1, &px, &py, marker(report.rows[i].accuracy));
  }
  plend1();
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 || ec) {
    throw IoError(name + ": PLplot wrote no image (is the pngcairo device installed?)");
  }
}

PendingOutput::PendingOutput(std::filesystem::path path) : path_(std::move(path)) {
  temporary_ = path_;
  temporary_ += ".tmp-" + std::to_string(::getpid());
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec)) {
    throw IoError(path_.string() + ": is a directory, expected a file to write");
  }
  std::ofstream probe(temporary_, std::ios::binary | std::ios::trunc);
  if (!probe) throw IoError(path_.string() + ": cannot write (cannot create a file there)");
}

PendingOutput::~PendingOutput() {
  if (committed_) return;
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
}

void PendingOutput::write(std::string_view text) const {
  std::ofstream out(temporary_, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw IoError(path_.string() + ": write failed");
}

void PendingOutput::commit() {
  std::error_code ec;
  std::filesystem::rename(temporary_, path_, ec);
  if (ec) throw IoError(path_.string() + ": cannot write (" + ec.message() + ")");
  committed_ = true;
}

}  // namespace skelcd::tools
