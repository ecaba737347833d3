// export --highlight: which triangles are coloured for a frame of a log, worked out by hand on a
// mesh with a welded seam.

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "tests/support/test_support.hpp"
#include "tools/highlight.hpp"
#include "tools/log/log_writer.hpp"

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

TEST(Highlight, FaceColoursFromALogFile) {
  const auto mesh = seam_mesh();
  const auto path = test::temp_dir("highlight") / "run.h5";
  LogHeader header;
  header.num_vertices = 9;
  header.num_triangles = 3;
  {
    LogWriter writer(path, header);
    FrameReport report;
    report.row.sample = 3;
    report.dcd_pairs = seam_log().dcd_pairs;
    writer.append(report);
    writer.finish();
  }
  const auto colours = highlight_face_colors(path, mesh, 3);
  ASSERT_EQ(colours.size(), 3u);
  EXPECT_EQ(colours[0], kHighlightColour);
  EXPECT_EQ(colours[1], kPlainColour);
  EXPECT_EQ(colours[2], kHighlightColour);
  EXPECT_THROW_MESSAGE((void)highlight_face_colors(path.parent_path() / "none.h5", mesh, 3),
                       IoError, "none.h5");
}

}  // namespace
