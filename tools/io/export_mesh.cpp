#include "tools/io/export_mesh.hpp"

#include <assimp/material.h>
#include <assimp/scene.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <system_error>

#include "skinning/errors.hpp"

namespace skelcd::tools {
namespace {

const char* assimp_format_id(MeshFormat format) {
  switch (format) {
    case MeshFormat::obj:
      return "objnomtl";  // no .mtl beside it: one self-contained file
    case MeshFormat::ply:
      return "plyb";  // not used: PLY is written by write_ply (below)
    case MeshFormat::glb:
      return "glb2";
  }
  return "objnomtl";
}

template <typename T>
void append_le(std::string& out, T value) {
  static_assert(std::endian::native == std::endian::little, "binary PLY is written little-endian");
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

// Binary little-endian PLY of the scene's meshes, merged (PLY has no parts): float x y z, uchar
// red green blue alpha when the meshes carry colours, faces as uchar-counted int lists. Written
// here because the binary PLY exporter of the assimp Debian 12 ships (5.2) declares uchar colours
// but writes four floats per vertex (assimp issue 3827, fixed upstream in 2024), a file no other
// reader can parse.
std::string write_ply(const aiScene& scene) {
  std::size_t vertices = 0, faces = 0;
  bool colored = false;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    vertices += scene.mMeshes[m]->mNumVertices;
    faces += scene.mMeshes[m]->mNumFaces;
    colored = colored || scene.mMeshes[m]->mColors[0] != nullptr;
  }
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by skelcd\n";
  out += "element vertex " + std::to_string(vertices) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (colored) {
    out += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  }
  out += "element face " + std::to_string(faces) + "\n";
  out += "property list uchar int vertex_index\nend_header\n";
  const auto to_byte = [](float c) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
  };
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& am = *scene.mMeshes[m];
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      append_le(out, static_cast<float>(am.mVertices[v].x));
      append_le(out, static_cast<float>(am.mVertices[v].y));
      append_le(out, static_cast<float>(am.mVertices[v].z));
      if (colored) {
        const aiColor4D c = am.mColors[0] != nullptr ? am.mColors[0][v] : aiColor4D(1, 1, 1, 1);
        for (const float channel : {c.r, c.g, c.b, c.a}) append_le(out, to_byte(channel));
      }
    }
  }
  std::int32_t base = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& am = *scene.mMeshes[m];
    for (unsigned f = 0; f < am.mNumFaces; ++f) {
      append_le(out, static_cast<std::uint8_t>(am.mFaces[f].mNumIndices));
      for (unsigned k = 0; k < am.mFaces[f].mNumIndices; ++k) {
        append_le(
            out,
            static_cast<std::int32_t>(base + static_cast<std::int32_t>(am.mFaces[f].mIndices[k])));
      }
    }
    base += static_cast<std::int32_t>(am.mNumVertices);
  }
  return out;
}

// Builds an aiScene with one aiMesh per non-empty part, each in a node of its own. aiScene's
// destructor frees everything allocated here with new/new[], as assimp expects.
std::unique_ptr<aiScene> build_scene(
    const skinning::Mesh& mesh,
    const skinning::Positions& positions,
    const ExportOptions& options,
    ExportResult& result) {
  const auto nf = mesh.num_triangles();
  const auto nv = mesh.num_vertices();
  const bool colored = !options.face_colors.empty();
  auto scene = std::make_unique<aiScene>();
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial* [1] { new aiMaterial() };
  aiString material_name("skelcd");
  scene->mMaterials[0]->AddProperty(&material_name, AI_MATKEY_NAME);

  const auto num_parts = std::max<std::int32_t>(mesh.num_parts(), 1);
  std::vector<std::vector<Eigen::Index>> faces_of_part(static_cast<std::size_t>(num_parts));
  for (Eigen::Index f = 0; f < nf; ++f) {
    const auto part = mesh.face_part.empty() ? 0 : mesh.face_part[static_cast<std::size_t>(f)];
    faces_of_part[static_cast<std::size_t>(part)].push_back(f);
  }
  std::vector<aiMesh*> meshes;
  std::vector<std::int32_t> local(static_cast<std::size_t>(nv), -1);
  for (std::int32_t p = 0; p < num_parts; ++p) {
    const auto& faces = faces_of_part[static_cast<std::size_t>(p)];
    if (faces.empty()) continue;
    auto* am = new aiMesh();
    meshes.push_back(am);
    am->mName = aiString(
        p < mesh.num_parts() ? mesh.part_names[static_cast<std::size_t>(p)] : std::string("mesh"));
    am->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    am->mMaterialIndex = 0;
    // Vertices of this part: shared as in the Mesh, or three per triangle with colours.
    std::vector<Eigen::Index> used;
    if (!colored) {
      for (const auto f : faces) {
        for (int k = 0; k < 3; ++k) {
          const auto v = static_cast<std::size_t>(mesh.triangles(f, k));
          if (local[v] < 0) {
            local[v] = static_cast<std::int32_t>(used.size());
            used.push_back(static_cast<Eigen::Index>(v));
          }
        }
      }
    } else {
      for (const auto f : faces) {
        for (int k = 0; k < 3; ++k) used.push_back(mesh.triangles(f, k));
      }
    }
    am->mNumVertices = static_cast<unsigned>(used.size());
    am->mVertices = new aiVector3D[used.size()];
    for (std::size_t i = 0; i < used.size(); ++i) {
      const auto row = positions.row(used[i]);
      am->mVertices[i] = aiVector3D(
          static_cast<ai_real>(row(0)), static_cast<ai_real>(row(1)), static_cast<ai_real>(row(2)));
    }
    if (colored) {
      am->mColors[0] = new aiColor4D[used.size()];
      for (std::size_t i = 0; i < faces.size(); ++i) {
        const auto& c = options.face_colors[static_cast<std::size_t>(faces[i])];
        for (std::size_t k = 0; k < 3; ++k)
          am->mColors[0][3 * i + k] = aiColor4D(c[0], c[1], c[2], c[3]);
      }
    }
    am->mNumFaces = static_cast<unsigned>(faces.size());
    am->mFaces = new aiFace[faces.size()];
    for (std::size_t i = 0; i < faces.size(); ++i) {
      aiFace& face = am->mFaces[i];
      face.mNumIndices = 3;
      face.mIndices = new unsigned[3];
      for (int k = 0; k < 3; ++k) {
        face.mIndices[k] = colored
                               ? static_cast<unsigned>(3 * i + static_cast<std::size_t>(k))
                               : static_cast<unsigned>(
                                     local[static_cast<std::size_t>(mesh.triangles(faces[i], k))]);
      }
    }
    if (!colored) {
      for (const auto v : used) local[static_cast<std::size_t>(v)] = -1;
    }
    result.vertices += static_cast<std::int64_t>(used.size());
    result.triangles += static_cast<std::int64_t>(faces.size());
  }
  scene->mNumMeshes = static_cast<unsigned>(meshes.size());
  scene->mMeshes = new aiMesh*[meshes.size()];
  std::copy(meshes.begin(), meshes.end(), scene->mMeshes);
  // One node per part, named as the part and holding its one mesh: glTF makes a mesh of each
  // node (the meshes of one node would become primitives of a single glTF mesh), OBJ a group.
  scene->mRootNode = new aiNode("posed");
  auto* root = scene->mRootNode;
  root->mNumChildren = scene->mNumMeshes;
  root->mChildren = new aiNode*[scene->mNumMeshes];
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    auto* node = new aiNode(scene->mMeshes[i]->mName.C_Str());
    node->mParent = root;
    node->mNumMeshes = 1;
    node->mMeshes = new unsigned[1]{i};
    root->mChildren[i] = node;
  }
  return scene;
}

void write_all(std::FILE* f, const void* data, std::size_t size, const std::string& where) {
  if (size > 0 && std::fwrite(data, 1, size, f) != size) throw IoError(where + ": write failed");
}

}  // namespace

std::optional<MeshFormat> parse_mesh_format(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  if (!name.empty() && name.front() == '.') name = name.substr(1);
  if (name == "obj") return MeshFormat::obj;
  if (name == "ply") return MeshFormat::ply;
  if (name == "glb") return MeshFormat::glb;
  return std::nullopt;
}

bool is_stdout(const std::filesystem::path& path) { return path == "-" || path == "/dev/stdout"; }

ExportResult export_mesh(
    const skinning::Mesh& mesh,
    const skinning::Positions& positions,
    const std::filesystem::path& out,
    const ExportOptions& options) {
  const bool to_stdout = is_stdout(out);
  ExportResult result;
  if (options.format) {
    result.format = *options.format;
  } else if (const auto f = parse_mesh_format(out.extension().string())) {
    result.format = *f;
  } else if (to_stdout) {
    result.format = MeshFormat::obj;
  } else {
    throw InvalidInput(
        out.string() + ": unknown output format '" + out.extension().string() +
        "' (use .obj, .ply or .glb)");
  }
  if (positions.rows() != mesh.num_vertices() || positions.cols() != 3) {
    throw InvalidInput(
        "export_mesh: positions are " + std::to_string(positions.rows()) + " x " +
        std::to_string(positions.cols()) + " for a mesh of " + std::to_string(mesh.num_vertices()) +
        " vertices");
  }
  if (!positions.allFinite())
    throw InvalidInput(out.string() + ": the posed positions are not finite");
  if (!options.face_colors.empty() &&
      static_cast<std::int64_t>(options.face_colors.size()) != mesh.num_triangles()) {
    throw InvalidInput(
        "export_mesh: " + std::to_string(options.face_colors.size()) + " face colours for " +
        std::to_string(mesh.num_triangles()) + " triangles");
  }
  if (mesh.num_triangles() == 0)
    throw InvalidInput(out.string() + ": nothing to export (no triangles)");

  const auto scene = build_scene(mesh, positions, options, result);
  Assimp::Exporter exporter;
  std::string ply;
  const void* data = nullptr;
  std::size_t size = 0;
  if (result.format == MeshFormat::ply) {
    ply = write_ply(*scene);
    data = ply.data();
    size = ply.size();
  } else {
    const aiExportDataBlob* blob =
        exporter.ExportToBlob(scene.get(), assimp_format_id(result.format));
    if (blob == nullptr)
      throw IoError(out.string() + ": assimp could not export: " + exporter.GetErrorString());
    if (blob->next != nullptr)
      throw IoError(out.string() + ": the exporter produced several files; expected one");
    data = blob->data;
    size = blob->size;
  }
  result.bytes = static_cast<std::int64_t>(size);

  if (to_stdout) {
    write_all(stdout, data, size, "standard output");
    if (std::fflush(stdout) != 0) throw IoError("standard output: write failed");
    return result;
  }
  // A temporary file in the same folder (same file system), renamed over the target at the end.
  const auto folder = out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw IoError(out.string() + ": folder " + folder.string() + " does not exist");
  std::string temp_name(".");
  temp_name.append(out.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  const auto temp = folder / temp_name;
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (f == nullptr) throw IoError(out.string() + ": cannot create " + temp.string());
  try {
    write_all(f, data, size, out.string());
    if (std::fflush(f) != 0 || ::fsync(::fileno(f)) != 0)
      throw IoError(out.string() + ": write failed");
  } catch (...) {
    std::fclose(f);
    std::filesystem::remove(temp, ec);
    throw;
  }
  if (std::fclose(f) != 0) {
    std::filesystem::remove(temp, ec);
    throw IoError(out.string() + ": write failed");
  }
  std::filesystem::rename(temp, out, ec);
  if (ec) {
    const auto reason = ec.message();
    std::filesystem::remove(temp, ec);
    throw IoError(out.string() + ": cannot move the finished file into place: " + reason);
  }
  return result;
}

}  // namespace skelcd::tools
