// Frame sequences: the cloth-funnel frames read bit-exactly (checked against a separate reader of
// the binary PLY written here), vertex order as in the file (and as assimp reads it), natural
// order, globs, refused topologies and coordinates.

#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "skinning/errors.hpp"
#include "skinning/frame_sequence.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

namespace fs = std::filesystem;

fs::path funnel_frames() { return test::asset("cloth-funnel/frames"); }

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A reader for exactly the cloth-funnel PLY layout (binary little endian, vertex: double x y z,
// face: list uchar int vertex_indices), written from the header we see in the file.
struct FunnelPly {
  std::vector<double> xyz;
  std::vector<std::array<std::int32_t, 3>> faces;
};
FunnelPly read_funnel_ply(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 9450\nproperty double x\nproperty double y\n"
      "property double z\nelement face 18484\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  FunnelPly ply;
  std::size_t at = header.size();
  ply.xyz.resize(3 * 9450);
  std::memcpy(ply.xyz.data(), bytes.data() + at, 8 * ply.xyz.size());
  at += 8 * ply.xyz.size();
  for (int f = 0; f < 18484; ++f) {
    EXPECT_EQ(static_cast<unsigned char>(bytes[at]), 3);
    std::array<std::int32_t, 3> face{};
    std::memcpy(face.data(), bytes.data() + at + 1, 12);
    ply.faces.push_back(face);
    at += 13;
  }
  EXPECT_EQ(at, bytes.size());
  return ply;
}

/// Every frame of the funnel sequence `motion` is its file's, bit for bit, each vertex and
/// triangle found under its index in the files (Mesh::vertex_index_in_part, face_index_in_part:
/// each index once, in any order the motion holds them in): the same coordinates, the same corners
/// in the same turn; frame 0 is the rest positions.
void expect_the_files_frames(const FrameSequenceMotion& motion) {
  const Mesh& mesh = motion.mesh();
  ASSERT_EQ(mesh.num_vertices(), 9450);
  ASSERT_EQ(mesh.num_triangles(), 18484);
  std::vector<std::int32_t> faces = mesh.face_index_in_part;
  std::vector<std::int32_t> vertices = mesh.vertex_index_in_part;
  std::sort(faces.begin(), faces.end());
  std::sort(vertices.begin(), vertices.end());
  for (std::size_t f = 0; f < faces.size(); ++f) ASSERT_EQ(faces[f], static_cast<std::int32_t>(f));
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    ASSERT_EQ(vertices[v], static_cast<std::int32_t>(v));
  }
  for (int i = 0; i < 2; ++i) {
    const FunnelPly ply = read_funnel_ply(motion.frame_file(i));
    Positions p;
    motion.positions(i, p);
    ASSERT_EQ(p.rows(), 9450);
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      const auto file_v =
          static_cast<std::size_t>(mesh.vertex_index_in_part[static_cast<std::size_t>(v)]);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(p(v, k), ply.xyz[3 * file_v + static_cast<std::size_t>(k)])
            << "frame " << i << " vertex " << v;
      }
    }
    if (i == 0) {
      EXPECT_EQ(p, mesh.rest_positions);
    }
    for (Eigen::Index f = 0; f < mesh.num_triangles(); ++f) {
      const auto file_f =
          static_cast<std::size_t>(mesh.face_index_in_part[static_cast<std::size_t>(f)]);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(
            mesh.vertex_index_in_part[static_cast<std::size_t>(mesh.triangles(f, k))],
            ply.faces[file_f][static_cast<std::size_t>(k)])
            << "frame " << i << " triangle " << f;
      }
    }
  }
}

TEST(FrameSequence, ClothFunnelIsReadBitExactly) {
  const FrameSequenceMotion motion = load_frame_sequence(funnel_frames());
  ASSERT_EQ(motion.num_samples(), 2);
  EXPECT_EQ(motion.frame_file(0).filename(), "227.ply");
  EXPECT_EQ(motion.frame_file(1).filename(), "228.ply");
  EXPECT_EQ(motion.name(), "frames");
  EXPECT_EQ(motion.mesh().num_parts(), 1);
  EXPECT_DOUBLE_EQ(motion.sample_time(1), 1.0 / 30.0);
  // The files' order (FrameSequenceOptions' default): every index where the file has it.
  const Mesh& mesh = motion.mesh();
  for (std::size_t f = 0; f < mesh.face_index_in_part.size(); ++f) {
    ASSERT_EQ(mesh.face_index_in_part[f], static_cast<std::int32_t>(f));
  }
  for (std::size_t v = 0; v < mesh.vertex_index_in_part.size(); ++v) {
    ASSERT_EQ(mesh.vertex_index_in_part[v], static_cast<std::int32_t>(v));
  }
  expect_the_files_frames(motion);
  // The two frames differ (the cloth moves).
  Positions p1;
  motion.positions(1, p1);
  EXPECT_GT((p1 - mesh.rest_positions).cwiseAbs().maxCoeff(), 0.0);
}

// In the spatial order (what load_model gives) every vertex and triangle is still the file's,
// found under its index in the file, in every frame, kept in memory or read again from the file.
TEST(FrameSequence, TheSpatialOrderHoldsTheFilesElementsUnderTheirFileIndices) {
  for (const std::size_t budget : {kKeptFrameBytesPerTriangle, std::size_t{0}}) {
    const FrameSequenceMotion motion(
        list_frame_files(funnel_frames()),
        FrameSequenceOptions{.kept_bytes_per_triangle = budget, .order = MeshOrder::spatial});
    EXPECT_EQ(motion.frames_in_memory(), budget != 0);
    const Mesh& mesh = motion.mesh();
    EXPECT_FALSE(std::is_sorted(mesh.face_index_in_part.begin(), mesh.face_index_in_part.end()));
    EXPECT_FALSE(
        std::is_sorted(mesh.vertex_index_in_part.begin(), mesh.vertex_index_in_part.end()));
    expect_the_files_frames(motion);
  }
  // load_model's default is this order; MeshOrder::file keeps the file's.
  const LoadedModel spatial = load_frame_sequence_model(funnel_frames(), {});
  EXPECT_FALSE(std::is_sorted(
      spatial.mesh->face_index_in_part.begin(), spatial.mesh->face_index_in_part.end()));
  LoadOptions file_order;
  file_order.mesh_order = MeshOrder::file;
  const LoadedModel file = load_frame_sequence_model(funnel_frames(), file_order);
  EXPECT_TRUE(
      std::is_sorted(file.mesh->face_index_in_part.begin(), file.mesh->face_index_in_part.end()));
  EXPECT_EQ(file.mesh->triangles, load_frame_sequence(funnel_frames()).mesh().triangles);
}

// assimp (float precision) reads the same vertices in the same order: each coordinate of ours
// rounds to assimp's float.
TEST(FrameSequence, VertexOrderAgreesWithAssimp) {
  const FrameMesh ours = read_frame_mesh(funnel_frames() / "227.ply");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile((funnel_frames() / "227.ply").string(), 0);
  ASSERT_NE(scene, nullptr);
  ASSERT_EQ(scene->mNumMeshes, 1U);
  const aiMesh* m = scene->mMeshes[0];
  ASSERT_EQ(static_cast<Eigen::Index>(m->mNumVertices), ours.positions.rows());
  for (unsigned v = 0; v < m->mNumVertices; ++v) {
    const auto row = static_cast<Eigen::Index>(v);
    ASSERT_EQ(static_cast<float>(ours.positions(row, 0)), m->mVertices[v].x) << v;
    ASSERT_EQ(static_cast<float>(ours.positions(row, 1)), m->mVertices[v].y) << v;
    ASSERT_EQ(static_cast<float>(ours.positions(row, 2)), m->mVertices[v].z) << v;
  }
  ASSERT_EQ(static_cast<Eigen::Index>(m->mNumFaces), ours.triangles.rows());
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    for (unsigned k = 0; k < 3; ++k) ASSERT_EQ(static_cast<unsigned>(ours.triangles(f, k)), m->mFaces[f].mIndices[k]);
  }
}

TEST(FrameSequence, NaturalOrderAndGlobs) {
  EXPECT_TRUE(natural_less("2.ply", "10.ply"));
  EXPECT_FALSE(natural_less("10.ply", "2.ply"));
  EXPECT_TRUE(natural_less("frame_9.obj", "frame_010.obj"));
  EXPECT_TRUE(natural_less("a.ply", "b.ply"));
  EXPECT_TRUE(natural_less("f1x2", "f1x10"));
  EXPECT_FALSE(natural_less("same", "same"));

  const fs::path dir = test::temp_dir("frames_natural");
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  for (const char* name : {"10.obj", "2.obj", "1.obj", "note.txt"}) write_file(dir / name, tri);
  const auto files = list_frame_files(dir);
  ASSERT_EQ(files.size(), 3U);
  EXPECT_EQ(files[0].filename(), "1.obj");
  EXPECT_EQ(files[1].filename(), "2.obj");
  EXPECT_EQ(files[2].filename(), "10.obj");
  const auto globbed = list_frame_files(dir / "1*.obj");
  ASSERT_EQ(globbed.size(), 2U);
  EXPECT_EQ(globbed[1].filename(), "10.obj");
  EXPECT_EQ(list_frame_files(funnel_frames() / "22[78].ply").size(), 2U);
  EXPECT_THROW_MESSAGE((void)list_frame_files(dir / "*.ply"), InvalidInput, "no OBJ or PLY frame files");
  EXPECT_THROW_MESSAGE((void)list_frame_files(dir / "missing"), IoError, "missing: no such folder");
}

TEST(FrameSequence, ObjAndPlyVariants) {
  const fs::path dir = test::temp_dir("frames_variants");
  // A quad (split into a fan), negative indices, texture/normal references, a comment.
  write_file(dir / "quad.obj", "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nv 0 1 0.1\nf 1/1 2/1/1 3//1 -1\nf -4 -2 -1\n");
  const FrameMesh quad = read_frame_mesh(dir / "quad.obj");
  ASSERT_EQ(quad.triangles.rows(), 3);
  EXPECT_EQ(quad.triangles.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(quad.triangles.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(quad.triangles.row(2), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(quad.positions(3, 2), 0.1);

  // ASCII PLY with an extra property and an extra element.
  write_file(dir / "a.ply",
             "ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n"
             "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
             "0 0 0 255\n0.1 0 0 0\n0 1e-300 0.3 1\n3 2 1 0\n0 1\n");
  const FrameMesh a = read_frame_mesh(dir / "a.ply");
  EXPECT_EQ(a.positions(1, 0), 0.1);  // parsed as written, double precision
  EXPECT_EQ(a.positions(2, 1), 1e-300);
  EXPECT_EQ(a.triangles.row(0), Eigen::RowVector3i(2, 1, 0));

  // Binary big-endian PLY with float coordinates and uint indices.
  std::string big = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  const auto put_be = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const char*>(p);
    for (std::size_t k = n; k-- > 0;) big.push_back(b[k]);
  };
  const float coords[9] = {0.0f, 0.0f, 0.0f, 0.1f, 2.0f, 0.0f, -3.5f, 0.0f, 1e-30f};
  for (const float c : coords) put_be(&c, 4);
  big.push_back(3);
  for (const std::uint32_t i : {0U, 1U, 2U}) put_be(&i, 4);
  write_file(dir / "big.ply", big);
  const FrameMesh b = read_frame_mesh(dir / "big.ply");
  EXPECT_EQ(b.positions(1, 0), static_cast<double>(0.1f));
  EXPECT_EQ(b.positions(2, 0), -3.5);
  EXPECT_EQ(b.positions(2, 2), static_cast<double>(1e-30f));
  // Truncated: drop the last index byte.
  write_file(dir / "cut.ply", big.substr(0, big.size() - 1));
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "cut.ply"), IoError, "cut.ply: PLY body ends early");
}

// Every PLY scalar type, as a coordinate, a skipped property, a list's count and its indices:
// the same values written as ASCII, binary little endian and binary big endian read the same,
// and as written (each binary value of a type is read through that type's own byte order; a value
// read with the wrong width or order would differ).
TEST(FrameSequence, EveryPlyTypeReadsTheSameInEachByteOrder) {
  const fs::path dir = test::temp_dir("frames_ply_types");
  struct Type {
    const char* name;
    int bytes;
    bool floating;
    bool is_signed;
  };
  const Type types[] = {
      {"char", 1, false, true},
      {"uchar", 1, false, false},
      {"short", 2, false, true},
      {"ushort", 2, false, false},
      {"int", 4, false, true},
      {"uint", 4, false, false},
      {"float", 4, true, true},
      {"double", 8, true, true}};
  // A value of `t` with distinct bytes where the width allows (so a swapped read is seen).
  const auto value = [](const Type& t, int vertex, int axis) -> double {
    const int k = 3 * vertex + axis;
    if (t.floating) return (t.bytes == 4 ? 1.5 : 1.0 + 0x1p-40) * (k + 1) * (axis == 1 ? -1 : 1);
    if (t.bytes == 1) return t.is_signed ? -(k + 1) : 200 + k;
    if (t.bytes == 2) return t.is_signed ? -(0x1234 + k) : 0xA1B2 + k;
    return t.is_signed ? -(305419896.0 + k) : 2712847316.0 + k;  // 0x12345678, 0xA1B2C3D4
  };
  const auto put = [](std::string& out, const Type& t, double v, bool big) {
    unsigned char raw[8];
    switch (t.bytes) {
      case 1: {
        const auto b = t.is_signed ? static_cast<std::uint8_t>(static_cast<std::int8_t>(v))
                                   : static_cast<std::uint8_t>(v);
        std::memcpy(raw, &b, 1);
        break;
      }
      case 2: {
        const auto b = t.is_signed ? static_cast<std::uint16_t>(static_cast<std::int16_t>(v))
                                   : static_cast<std::uint16_t>(v);
        std::memcpy(raw, &b, 2);
        break;
      }
      case 4: {
        if (t.floating) {
          const auto f = static_cast<float>(v);
          std::memcpy(raw, &f, 4);
        } else {
          const auto b = t.is_signed ? static_cast<std::uint32_t>(static_cast<std::int32_t>(v))
                                     : static_cast<std::uint32_t>(v);
          std::memcpy(raw, &b, 4);
        }
        break;
      }
      default:
        std::memcpy(raw, &v, 8);
    }
    const auto n = static_cast<std::size_t>(t.bytes);
    if (big) std::reverse(raw, raw + n);  // this machine is little endian (x86-64)
    out.append(reinterpret_cast<const char*>(raw), n);
  };
  const Type index_types[] = {types[0], types[1], types[2], types[3], types[4], types[5]};
  int files = 0;
  for (const Type& coordinate : types) {
    for (const Type& index : index_types) {
      // The list count: a type other than the index's, where there is one of that width.
      const Type& count = index_types[(&index - index_types + 1) % 6];
      const Type& skipped = types[(&coordinate - types + 3) % 8];
      std::string header = "ply\nformat FORMAT 1.0\nelement vertex 4\n";
      for (const char* axis : {"x", "y", "z"})
        header += std::string("property ") + coordinate.name + " " + axis + "\n";
      header += std::string("property ") + skipped.name + " extra\n";
      header += std::string("element face 2\nproperty list ") + count.name + " " + index.name +
                " vertex_indices\nend_header\n";
      const int faces[2][3] = {{0, 1, 2}, {3, 2, 1}};
      std::vector<FrameMesh> read;
      for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
        std::string text = header;
        text.replace(text.find("FORMAT"), 6, format);
        const bool ascii = std::string(format) == "ascii";
        const bool big = std::string(format) == "binary_big_endian";
        for (int v = 0; v < 4; ++v) {
          for (int a = 0; a < 3; ++a) {
            const double x = value(coordinate, v, a);
            if (ascii) {
              char buffer[64];
              std::snprintf(
                  buffer,
                  sizeof buffer,
                  "%.17g ",
                  coordinate.bytes == 4 && coordinate.floating
                      ? static_cast<double>(static_cast<float>(x))
                      : x);
              text += buffer;
            } else {
              put(text, coordinate, x, big);
            }
          }
          const double e = value(skipped, v, 0);
          if (ascii) {
            text += std::to_string(static_cast<long long>(std::llround(e))) + "\n";
          } else {
            put(text, skipped, e, big);
          }
        }
        for (const auto& f : faces) {
          if (ascii) {
            text += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " +
                    std::to_string(f[2]) + "\n";
          } else {
            put(text, count, 3, big);
            for (const int i : f) put(text, index, i, big);
          }
        }
        const fs::path file =
            dir / (std::string(coordinate.name) + "_" + index.name + "_" + format + ".ply");
        write_file(file, text);
        read.push_back(read_frame_mesh(file));
        ++files;
      }
      SCOPED_TRACE(
          std::string(coordinate.name) + " coordinates, " + count.name + "/" + index.name +
          " lists, " + skipped.name + " skipped");
      for (const FrameMesh& m : read) {
        ASSERT_EQ(m.positions.rows(), 4);
        ASSERT_EQ(m.triangles.rows(), 2);
        for (int v = 0; v < 4; ++v) {
          for (int a = 0; a < 3; ++a) {
            double want = value(coordinate, v, a);
            if (coordinate.floating && coordinate.bytes == 4) want = static_cast<float>(want);
            EXPECT_EQ(m.positions(v, a), want) << v << "," << a;
          }
        }
        EXPECT_EQ(m.triangles.row(0), Eigen::RowVector3i(0, 1, 2));
        EXPECT_EQ(m.triangles.row(1), Eigen::RowVector3i(3, 2, 1));
      }
    }
  }
  EXPECT_EQ(files, 8 * 6 * 3);
}

TEST(FrameSequence, MismatchedTopologyIsRefusedNamingTheFrame) {
  const fs::path dir = test::temp_dir("frames_mismatch");
  const std::string square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
  write_file(dir / "frame1.obj", square);
  write_file(dir / "frame2.obj", square);
  write_file(dir / "frame10.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 4\nf 2 3 4\n");
  EXPECT_THROW_MESSAGE((void)load_frame_sequence(dir), InvalidInput, "frame10.obj: frame 2: triangle 0 differs");
  write_file(dir / "frame10.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 3 1\n");
  EXPECT_THROW_MESSAGE((void)load_frame_sequence(dir), InvalidInput, "frame10.obj: frame 2 has 3 vertices, frame 0");
  write_file(dir / "frame10.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THROW_MESSAGE((void)load_frame_sequence(dir), InvalidInput, "frame10.obj: frame 2 has 1 triangles");
  // Same topology: fine, three samples.
  write_file(dir / "frame10.obj", square);
  EXPECT_EQ(load_frame_sequence(dir).num_samples(), 3);
}

TEST(FrameSequence, FramesBeyondTheBudgetAreReadAgainBitExactly) {
  // The funnel's two frames take 2 × 9,450 × 24 bytes, 24.5 per triangle: kept by default.
  const FrameSequenceMotion kept = load_frame_sequence(funnel_frames());
  EXPECT_TRUE(kept.frames_in_memory());
  // With no budget only the first frame is held; the others are read again, to the same bits.
  const FrameSequenceMotion read_again(
      list_frame_files(funnel_frames()), FrameSequenceOptions{.kept_bytes_per_triangle = 0});
  EXPECT_FALSE(read_again.frames_in_memory());
  ASSERT_EQ(read_again.num_samples(), kept.num_samples());
  EXPECT_TRUE(read_again.mesh().rest_positions == kept.mesh().rest_positions);
  EXPECT_TRUE(read_again.mesh().triangles == kept.mesh().triangles);
  for (int i = 0; i < kept.num_samples(); ++i) {
    Positions a, b;
    kept.positions(i, a);
    read_again.positions(i, b);
    ASSERT_EQ(a.rows(), b.rows());
    EXPECT_EQ(
        0, std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())))
        << "frame " << i;
    // Kept frames are lent where they are (the runner reads them without a copy); frames read
    // again are not held, so there is nothing to lend.
    const Positions* held = kept.held_positions(i);
    ASSERT_NE(held, nullptr) << "frame " << i;
    EXPECT_EQ(held, kept.held_positions(i));
    ASSERT_EQ(held->rows(), a.rows());
    EXPECT_EQ(
        0, std::memcmp(held->data(), a.data(), sizeof(double) * static_cast<std::size_t>(a.size())))
        << "frame " << i;
    EXPECT_EQ(read_again.held_positions(i), nullptr) << "frame " << i;
  }
  // A budget just below the two frames' size reads them again too; at it, they are kept.
  const std::size_t per_triangle = (2 * 9450 * 24) / 18484;  // 24 (24.54 rounded down)
  EXPECT_FALSE(FrameSequenceMotion(
                   list_frame_files(funnel_frames()),
                   FrameSequenceOptions{.kept_bytes_per_triangle = per_triangle})
                   .frames_in_memory());
  EXPECT_TRUE(FrameSequenceMotion(
                  list_frame_files(funnel_frames()),
                  FrameSequenceOptions{.kept_bytes_per_triangle = per_triangle + 1})
                  .frames_in_memory());
}

TEST(FrameSequence, AFrameChangedAfterReadingIsRefusedNamingIt) {
  const fs::path dir = test::temp_dir("frames_changed");
  const std::string square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
  write_file(dir / "frame1.obj", square);
  write_file(dir / "frame2.obj", "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3\nf 1 3 4\n");
  write_file(dir / "frame3.obj", square);
  const FrameSequenceMotion motion(
      list_frame_files(dir), FrameSequenceOptions{.kept_bytes_per_triangle = 0});
  Positions x;
  motion.positions(1, x);
  EXPECT_EQ(x(2, 2), 1.0);
  // Rewritten with the same topology and other positions: not the frame that was checked.
  write_file(dir / "frame2.obj", "v 0 0 2\nv 1 0 2\nv 1 1 2\nv 0 1 2\nf 1 2 3\nf 1 3 4\n");
  EXPECT_THROW_MESSAGE(motion.positions(1, x), IoError, "frame2.obj: frame 1 changed since");
  fs::remove(dir / "frame3.obj");
  EXPECT_THROW_MESSAGE(motion.positions(2, x), IoError, "frame3.obj: cannot open frame file");
  // The first frame is the rest pose, held: its file is not read again.
  fs::remove(dir / "frame1.obj");
  motion.positions(0, x);
  EXPECT_EQ(x(2, 0), 1.0);
}

TEST(FrameSequence, BadCoordinatesAndIndicesAreRefused) {
  const fs::path dir = test::temp_dir("frames_bad");
  write_file(dir / "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "nan.obj"), InvalidInput, "nan.obj: vertex 1 has a non-finite coordinate");
  write_file(dir / "inf.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 0 inf\n1 1 1\n3 0 1 2\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "inf.ply"), InvalidInput, "inf.ply: vertex 1 has a non-finite coordinate");
  write_file(dir / "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "range.obj"), InvalidInput, "range.obj: face 0 has vertex index 3 out of range");
  write_file(dir / "two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "two.obj"), InvalidInput, "two.obj: face 0 has 2 corners");
  write_file(dir / "junk.obj", "v 0 0 zero\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "junk.obj"), IoError, "junk.obj:1: malformed vertex coordinate 'zero'");
  write_file(dir / "notply.ply", "hello\n");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "notply.ply"), IoError, "notply.ply: not a PLY file");
  EXPECT_THROW_MESSAGE((void)read_frame_mesh(dir / "absent.ply"), IoError, "absent.ply: cannot open");
  // A NaN in a later frame of a sequence names that frame's file.
  const fs::path seq = test::temp_dir("frames_nan_seq");
  write_file(seq / "0.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write_file(seq / "1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -nan\nf 1 2 3\n");
  EXPECT_THROW_MESSAGE((void)load_frame_sequence(seq), InvalidInput, "1.obj: vertex 2 has a non-finite coordinate");
  FrameSequenceOptions options;
  options.rate_hz = 0.0;
  EXPECT_THROW_MESSAGE((void)load_frame_sequence(funnel_frames(), options), InvalidInput, "not positive");
}

// Inputs found by fuzz/fuzz_frame_mesh (docs/fuzzing.md): each crashed, hung or asked for an
// enormous allocation before the header counts were checked against the file's size.
TEST(FrameSequence, DamagedPlyHeadersAreRefusedNotTrusted) {
  const fs::path dir = test::temp_dir("frames_fuzz");
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
      "z\n";
  const std::string body = "end_header\n0 0 0\n1 0 0\n0 1 0\n";
  // 4294967295 vertices in a 150-byte file: was a 96 GB reserve.
  write_file(
      dir / "count.ply",
      "ply\nformat ascii 1.0\nelement vertex 4294967295\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n");
  EXPECT_THROW_MESSAGE(
      (void)read_frame_mesh(dir / "count.ply"),
      IoError,
      "count.ply: PLY element 'vertex' declares 4294967295 items, more than the 6 bytes after the "
      "header hold");
  // An element without properties and 10^14 items: was a loop of 10^14 empty iterations.
  write_file(dir / "empty_element.ply", head + "element junk 100000000000000\n" + body);
  EXPECT_EQ(read_frame_mesh(dir / "empty_element.ply").positions.rows(), 3);
  // A list length and a face index of 1e300: were undefined conversions to integers.
  write_file(
      dir / "list.ply",
      head + "element face 1\nproperty list float int vertex_indices\n" + body + "1e300 0 1 2\n");
  EXPECT_THROW_MESSAGE(
      (void)read_frame_mesh(dir / "list.ply"), IoError, "list.ply: malformed PLY list length");
  write_file(
      dir / "index.ply",
      head + "element face 1\nproperty list uchar int vertex_indices\n" + body + "3 0 1 1e300\n");
  EXPECT_THROW_MESSAGE(
      (void)read_frame_mesh(dir / "index.ply"), InvalidInput, "index.ply: PLY face index");
}

TEST(FrameSequence, LoadModelEntryPoint) {
  const LoadedModel model = load_frame_sequence_model(funnel_frames(), {});
  EXPECT_EQ(model.kind, ModelKind::frame_sequence);
  EXPECT_EQ(model.mesh->num_triangles(), 18484);
  EXPECT_EQ(model.rig, nullptr);
  ASSERT_EQ(model.clips.size(), 1U);
  EXPECT_EQ(model.clips[0].name, "frames");
  EXPECT_DOUBLE_EQ(model.clips[0].duration_s, 1.0 / 30.0);
  EXPECT_DOUBLE_EQ(model.clips[0].keys_per_s, 30.0);
  EXPECT_DOUBLE_EQ(model.clips[0].rate_hz, kDefaultFrameRateHz);
  EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::frame_sequence);
  const auto motion = model.motion({});
  EXPECT_EQ(motion->num_samples(), 2);
  EXPECT_DOUBLE_EQ(motion->sample_time(1), 1.0 / 30.0);
  MotionRequest fast;
  fast.rate_hz = 120.0;
  fast.clip = "frames";
  EXPECT_DOUBLE_EQ(model.motion(fast)->sample_time(1), 1.0 / 120.0);
  MotionRequest wrong;
  wrong.clip = "walk";
  EXPECT_THROW_MESSAGE((void)model.motion(wrong), InvalidInput, "one clip, 'frames', not 'walk'");
  LoadOptions robot_only;
  robot_only.srdf = "x.srdf";
  EXPECT_THROW_MESSAGE((void)load_frame_sequence_model(funnel_frames(), robot_only), InvalidInput, "URDF robots only");
}

}  // namespace
}  // namespace skelcd::skinning
