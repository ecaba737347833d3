// export --highlight: which triangles are coloured for a frame of a log, worked out by hand on a
// mesh with a welded seam; a colour per event in a labelled log, one colour in a log written before
// events.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>

#include "skinning/errors.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"
#include "tools/io/log/log_writer.hpp"
#include "tools/report/highlight.hpp"

namespace {

using namespace skelcd;
using namespace skelcd::tools;
using Kind = culling::CcdContact::Kind;

/// Triangle 0 = part 0 triangle 0 (vertices 0 1 2). Triangles 1 and 2 = part 1 triangles 0 and 1,
/// a square split along its diagonal with its own vertices 3..8; 6 repeats 5 and 8 repeats 3.
skinning::Mesh seam_mesh() {
  skinning::Mesh m;
  m.rest_positions.resize(9, 3);
  m.rest_positions << 0, 0, 1, 1, 0, 1, 0, 1, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0, 1, 1, 0, 0, 1, 0, 0, 0,
      0;
  m.triangles.resize(3, 3);
  m.triangles << 0, 1, 2, 3, 4, 5, 6, 7, 8;
  m.face_part = {0, 1, 1};
  m.face_index_in_part = {0, 0, 1};
  m.vertex_part = {0, 0, 0, 1, 1, 1, 1, 1, 1};
  m.vertex_index_in_part = {0, 1, 2, 0, 1, 2, 3, 4, 5};
  m.part_names = {"tri", "square"};
  return m;
}

LogData seam_log() {
  LogData log;
  log.header.num_vertices = 9;
  log.header.num_triangles = 3;
  // Frame 1: the seam vertex (part 1 index 3 = file vertex 6, welded with 5) against triangle 0.
  log.contacts.push_back({1, Kind::vf, {1, 3, -1}, {0, 0, -1}, 0.5, 0.5});
  // Frame 2: vertex 4 (only in triangle 1) against triangle 0.
  log.contacts.push_back({2, Kind::vf, {1, 1, -1}, {0, 0, -1}, 0.5, 0.5});
  // Frame 4: the diagonal (side 2 of part 1 triangle 0: corner 2 → 0, vertices 5 → 3) against
  // side 0 of triangle 0.
  log.contacts.push_back({4, Kind::ee, {1, 0, 2}, {0, 0, 0}, 0.5, 0.5});
  // Frame 3: triangles 0 and 2 intersect.
  log.dcd_pairs.push_back({3, {0, 0, -1}, {1, 1, -1}});
  return log;
}

TEST(Highlight, MarksTheTrianglesOfEachFindingAtThatFrameOnly) {
  const auto mesh = seam_mesh();
  const auto log = seam_log();
  using V = std::vector<std::int32_t>;
  EXPECT_EQ(highlighted_triangles(log, mesh, 0), V{});
  EXPECT_EQ(highlighted_triangles(log, mesh, 1), (V{0, 1, 2}));  // the welded vertex is in 1 and 2
  EXPECT_EQ(highlighted_triangles(log, mesh, 2), (V{0, 1}));
  EXPECT_EQ(highlighted_triangles(log, mesh, 3), (V{0, 2}));
  EXPECT_EQ(highlighted_triangles(log, mesh, 4), (V{0, 1, 2}));  // the diagonal borders 1 and 2
}

TEST(Highlight, RefusesALogOfAnotherMesh) {
  auto mesh = seam_mesh();
  auto log = seam_log();
  log.header.num_triangles = 4;
  EXPECT_THROW_MESSAGE((void)highlighted_triangles(log, mesh, 1), InvalidInput, "4 triangles");
  log = seam_log();
  log.dcd_pairs.push_back({1, {0, 7, -1}, {1, 0, -1}});
  EXPECT_THROW_MESSAGE((void)highlighted_triangles(log, mesh, 1), InvalidInput, "triangle 7");
}

TEST(Highlight, ALogWrittenAtAFloatNoisyRateMatchesTheRoundRate) {
  // A clip whose keys are single-precision gives a rate of 23.999999407829137 samples/s: frame 12
  // is at 0.500000012 s in its log and at 0.5 s when exported with --rate 24. Same sample.
  const auto mesh = seam_mesh();
  const auto path = test::temp_dir("highlight-rate") / "run.h5";
  const double rate = 23.999999407829137;
  LogHeader header;
  header.num_vertices = 9;
  header.num_triangles = 3;
  header.clip = "walk";
  header.fps = rate;
  {
    LogWriter writer(path, header);
    FrameReport report;
    report.row.sample = 12;
    report.row.t0 = report.row.t1 = 12 / rate;
    report.dcd_pairs = seam_log().dcd_pairs;
    for (auto& p : report.dcd_pairs) p.frame = 12;
    writer.append(report);
    writer.finish();
  }
  const auto colours = highlight_face_colors(path, mesh, 12, 12 / 24.0, "walk");
  EXPECT_EQ(colours[0], kHighlightColour);
  // A real difference of rate is still refused, and the message shows the two times apart and
  // the rate to export at.
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path, mesh, 12, 12 / 25.0, "walk"),
      InvalidInput,
      "frame 12 is at t = 0.500000012 s in the log (written at 23.9999994 samples/s) but at t = "
      "0.48 s here");
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path, mesh, 12, 12 / 25.0, "walk"),
      InvalidInput,
      "pose it at the log's rate (--rate 23.9999994)");
}

TEST(Highlight, FaceColoursFromALogFile) {
  const auto mesh = seam_mesh();
  const auto path = test::temp_dir("highlight") / "run.h5";
  LogHeader header;
  header.num_vertices = 9;
  header.num_triangles = 3;
  header.clip = "walk";
  {
    LogWriter writer(path, header);
    FrameReport report;
    report.row.sample = 3;
    report.row.t0 = report.row.t1 = 0.125;
    report.dcd_pairs = seam_log().dcd_pairs;
    writer.append(report);
    writer.finish();
  }
  const auto colours = highlight_face_colors(path, mesh, 3, 0.125, "walk");
  ASSERT_EQ(colours.size(), 3u);
  EXPECT_EQ(colours[0], kHighlightColour);
  EXPECT_EQ(colours[1], kPlainColour);
  EXPECT_EQ(colours[2], kHighlightColour);
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path.parent_path() / "none.h5", mesh, 3, 0.125, "walk"),
      IoError,
      "none.h5");
  // A frame the log does not cover, and the right frame at another rate's time.
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path, mesh, 4, 0.125, "walk"),
      InvalidInput,
      "no row for frame 4");
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path, mesh, 3, 0.1, "walk"),
      InvalidInput,
      "pose it at the log's rate");
  // The right frame and time of another clip (same rate, same mesh): refused, not mis-coloured.
  EXPECT_THROW_MESSAGE(
      (void)highlight_face_colors(path, mesh, 3, 0.125, "run"),
      InvalidInput,
      "checked clip 'walk', not 'run'");
}

TEST(Highlight, ATriangleInSeveralFindingsTakesTheEventBeforeTheBaselineBeforeAllowed) {
  const auto mesh = seam_mesh();
  LogData log;
  log.header.num_vertices = 9;
  log.header.num_triangles = 3;
  log.dcd_pairs.push_back({3, {0, 0, -1}, {1, 1, -1}, kLabelBaseline});  // triangles 0, 2
  log.dcd_pairs.push_back({3, {0, 0, -1}, {1, 0, -1}, kLabelAllowed});   // 0, 1
  log.dcd_pairs.push_back({3, {1, 0, -1}, {1, 1, -1}, 4});               // 1, 2
  log.dcd_pairs.push_back({3, {0, 0, -1}, {1, 1, -1}, 2});               // 0, 2
  using V = std::vector<std::pair<std::int32_t, std::int32_t>>;
  EXPECT_EQ(labelled_triangles(log, mesh, 3), (V{{0, 2}, {1, 4}, {2, 2}}));
  log.dcd_pairs.resize(2);
  EXPECT_EQ(
      labelled_triangles(log, mesh, 3),
      (V{{0, kLabelBaseline}, {1, kLabelAllowed}, {2, kLabelBaseline}}));
  // A CCD contact of the interval [3, 4] carries its label to every triangle it marks.
  log.contacts.push_back({3, Kind::vf, {1, 3, -1}, {0, 0, -1}, 0.5, 0.5, 0});
  EXPECT_EQ(labelled_triangles(log, mesh, 3), (V{{0, 0}, {1, 0}, {2, 0}}));
  EXPECT_EQ(highlighted_triangles(log, mesh, 3), (std::vector<std::int32_t>{0, 1, 2}));
}

TEST(Highlight, EachEventHasItsColourAndBaselineAndAllowedTheirNeutralOnes) {
  // Two parts of the seam mesh plus a fourth, far triangle.
  auto mesh = seam_mesh();
  mesh.triangles.conservativeResize(5, 3);
  mesh.triangles.row(3) << 0, 2, 1;
  mesh.triangles.row(4) << 3, 5, 4;
  mesh.face_part = {0, 1, 1, 0, 1};
  mesh.face_index_in_part = {0, 0, 1, 1, 2};
  const auto path = test::temp_dir("highlight-events") / "run.h5";
  LogHeader header;
  header.num_vertices = 9;
  header.num_triangles = 5;
  header.clip = "walk";
  header.baseline = "rest pose";
  {
    LogWriter writer(path, header);
    FrameReport report;
    report.row.sample = 3;
    report.row.t0 = report.row.t1 = 0.125;
    report.dcd_pairs.push_back({3, {0, 0, -1}, {1, 1, -1}, 0});               // 0, 2: event 0
    report.dcd_pairs.push_back({3, {0, 1, -1}, {1, 2, -1}, 13});              // 3, 4: event 13
    report.dcd_pairs.push_back({3, {1, 0, -1}, {1, 1, -1}, kLabelBaseline});  // 1 (2 is event 0)
    writer.append(report);
    writer.write_events({});
    writer.finish();
  }
  const auto h = highlight_frame(path, mesh, 3, 0.125, "walk");
  EXPECT_TRUE(h.labelled);
  ASSERT_EQ(h.face_colors.size(), 5u);
  EXPECT_EQ(h.face_colors[0], label_colour(0));
  EXPECT_EQ(h.face_colors[2], label_colour(0));
  EXPECT_EQ(h.face_colors[3], label_colour(13));
  EXPECT_EQ(h.face_colors[4], label_colour(13));
  EXPECT_EQ(h.face_colors[1], kBaselineColour);
  // The palette: event 0 red, 13 = 1 + 12 the second colour, blue; every event colour differs from
  // the neutral ones.
  EXPECT_EQ(label_colour(0), (std::array<float, 4>{228 / 255.0f, 26 / 255.0f, 28 / 255.0f, 1.0f}));
  EXPECT_EQ(label_colour(13), label_colour(1));
  EXPECT_EQ(label_colour(kLabelAllowed), kAllowedColour);
  for (std::int32_t e = 0; e < 12; ++e) {
    for (const auto& neutral : {kBaselineColour, kAllowedColour, kPlainColour, kHighlightColour}) {
      EXPECT_NE(label_colour(e), neutral) << e;
    }
    for (std::int32_t other = 0; other < e; ++other)
      EXPECT_NE(label_colour(e), label_colour(other));
  }
  EXPECT_EQ(
      legend(h),
      "event 0 red: 2 triangles, event 13 blue: 2 triangles, baseline (slate): 1 triangle");
  EXPECT_EQ(legend(highlight_frame(path, mesh, 3, 0.125, "walk")), legend(h));
}

TEST(Highlight, ALogWrittenBeforeEventsKeepsOneColour) {
  // tests/tools/data/log_before_events.hdf5 (the version-1 writer, no labels) for the seam mesh:
  // at frame 3 a DCD pair (triangles 0 and 2), a VF contact (vertex 4: triangles 1 and 0) and an
  // EE contact (the diagonal against triangle 0's side 0): every triangle, all in one colour.
  const auto old =
      std::filesystem::path(SKELCD_SOURCE_DIR) / "tests/tools/data/log_before_events.hdf5";
  const auto mesh = seam_mesh();
  const auto h = highlight_frame(old, mesh, 3, 3 / 8.0, "walk");
  EXPECT_FALSE(h.labelled);
  for (const auto& c : h.face_colors) EXPECT_EQ(c, kHighlightColour);
  EXPECT_EQ(legend(h), "3 triangles in red");
  const auto quiet = highlight_frame(old, mesh, 4, 4 / 8.0, "walk");
  for (const auto& c : quiet.face_colors) EXPECT_EQ(c, kPlainColour);
  EXPECT_EQ(legend(quiet), "no finding at this frame");
}

TEST(Highlight, ExportColoursTheCollidingTrianglesOfAFrame) {
  // Frames: a large triangle in z = 0 (0), a small one piercing it at frame 2 (1), and a third
  // far away that nothing touches (2). check, then export frame 2 with --highlight to PLY.
  const auto dir = test::temp_dir("highlight-export");
  std::filesystem::create_directories(dir / "frames");
  const char* small[3] = {"1 1 1\nv 2 1 1\nv 1 2 1", "1 1 -1\nv 2 1 -1\nv 1 2 -1",
                          "1 1 -1\nv 1.5 1 1\nv 2 2 1"};
  for (int i = 0; i < 3; ++i) {
    std::string name = "f";  // (appending avoids GCC 12's -Wrestrict false positive on "lit" + str)
    name += std::to_string(i);
    name += ".obj";
    std::ofstream(dir / "frames" / name)
        << "v 0 0 0\nv 4 0 0\nv 0 4 0\nv " << small[i]
        << "\nv 10 10 10\nv 11 10 10\nv 10 11 10\nf 1 2 3\nf 4 5 6\nf 7 8 9\n";
  }
  const auto log = (dir / "run.h5").string();
  const auto check = test::run_skelcd({"check", (dir / "frames").string(), "-o", log});
  ASSERT_EQ(check.exit_code, 0) << check.err;
  const auto ply = dir / "frame2.ply";
  const auto r = test::run_skelcd({"export", (dir / "frames").string(), "--frame", "2",
                                   "--highlight", log, "-o", ply.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // Binary PLY read strictly by its header, as any viewer reads it: 9 vertices (one per triangle
  // corner) of float x, y, z and uchar red, green, blue, alpha — 16 bytes — then 3 faces of
  // 1 + 3 × 4 bytes, and nothing else. (Debian's assimp 5.2 wrote float colours under a uchar
  // header; export writes PLY itself for that reason.)
  std::ifstream in(ply, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const std::string text = bytes.str();
  const auto end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = text.substr(0, end);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos) << header;
  EXPECT_NE(
      header.find("element vertex 9\nproperty float x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                  "property uchar alpha\nelement face 3\n"
                  "property list uchar int vertex_index\n"),
      std::string::npos)
      << header;
  ASSERT_EQ(text.size(), end + 11 + 9 * 16 + 3 * 13) << "the body is not what the header declares";
  const char* vertices = text.data() + end + 11;
  std::vector<float> red;
  for (std::size_t v = 0; v < 9; ++v) {
    red.push_back(static_cast<float>(static_cast<unsigned char>(vertices[16 * v + 12])) / 255.0f);
  }
  // Faces index their own corners: face f is vertices 3f, 3f+1, 3f+2.
  for (std::size_t f = 0; f < 3; ++f) {
    const char* face = vertices + 9 * 16 + 13 * f;
    EXPECT_EQ(face[0], 3);
    for (std::size_t k = 0; k < 3; ++k) {
      std::int32_t index = -1;
      std::memcpy(&index, face + 1 + 4 * k, sizeof index);
      EXPECT_EQ(index, static_cast<std::int32_t>(3 * f + k));
    }
  }
  for (std::size_t v = 0; v < 6; ++v) EXPECT_NEAR(red[v], kHighlightColour[0], 0.01) << v;
  for (std::size_t v = 6; v < 9; ++v) EXPECT_NEAR(red[v], kPlainColour[0], 0.01) << v;

  // A frame the log did not check is refused, nothing written.
  const auto bad = test::run_skelcd({"export", (dir / "frames").string(), "--frame", "2", "--fps",
                                     "60", "--highlight", log, "-o", (dir / "x.ply").string()});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("log's rate"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(Highlight, ExportNamesTheColoursOfALabelledLog) {
  // The frames of the test above, checked; the log then rewritten with labels as an events run
  // writes them: the piercing pair at frame 2 is event 5.
  const auto dir = test::temp_dir("highlight-export-events");
  std::filesystem::create_directories(dir / "frames");
  const char* small[3] = {
      "1 1 1\nv 2 1 1\nv 1 2 1", "1 1 -1\nv 2 1 -1\nv 1 2 -1", "1 1 -1\nv 1.5 1 1\nv 2 2 1"};
  for (int i = 0; i < 3; ++i) {
    std::string name = "f";
    name += std::to_string(i);
    name += ".obj";
    std::ofstream(dir / "frames" / name)
        << "v 0 0 0\nv 4 0 0\nv 0 4 0\nv " << small[i]
        << "\nv 10 10 10\nv 11 10 10\nv 10 11 10\nf 1 2 3\nf 4 5 6\nf 7 8 9\n";
  }
  const auto plain = (dir / "plain.h5").string();
  const auto check = test::run_skelcd({"check", (dir / "frames").string(), "-o", plain});
  ASSERT_EQ(check.exit_code, 0) << check.err;
  const auto log = read_log(plain);
  auto header = log.header;
  header.baseline = "sample 0";
  header.format_version = kLogFormatVersion;
  const auto labelled = (dir / "labelled.h5").string();
  {
    LogWriter writer(labelled, header);
    for (const auto& row : log.frames) {
      FrameReport report;
      report.row = row;
      for (auto p : log.dcd_pairs) {
        if (p.frame != row.sample || row.kind != QueryKind::dcd) continue;
        p.label = 5;
        report.dcd_pairs.push_back(p);
      }
      writer.append(report);
    }
    writer.write_events({});
    writer.finish();
  }
  const auto r = test::run_skelcd(
      {"export",
       (dir / "frames").string(),
       "--frame",
       "2",
       "--highlight",
       labelled,
       "-o",
       (dir / "f2.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("; event 5 brown: 2 triangles\n"), std::string::npos) << r.out;
  // The same log unlabelled: red, as before events.
  const auto old = test::run_skelcd(
      {"export",
       (dir / "frames").string(),
       "--frame",
       "2",
       "--highlight",
       plain,
       "-o",
       (dir / "f2-plain.ply").string()});
  ASSERT_EQ(old.exit_code, 0) << old.err;
  if (log.header.baseline.empty()) {
    EXPECT_NE(old.out.find("; 2 triangles in red\n"), std::string::npos) << old.out;
  }
}

}  // namespace
