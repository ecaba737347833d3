#include "skinning/detail/collada_bind_shape.hpp"

#include <tinyxml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "skinning/errors.hpp"

namespace skelcd::skinning::detail {
namespace {

const TiXmlElement* child(const TiXmlNode* parent, const char* name) {
  return parent == nullptr ? nullptr : parent->FirstChildElement(name);
}

}  // namespace

std::map<std::string, Eigen::Affine3d> collada_bind_shape_matrices(
    const std::filesystem::path& file) {
  std::map<std::string, Eigen::Affine3d> out;
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  if (ext != ".dae") return out;
  TiXmlDocument doc;
  if (!doc.LoadFile(file.string().c_str())) return out;  // assimp says what is wrong with it
  const TiXmlElement* root = doc.RootElement();
  if (root == nullptr || std::string(root->Value()) != "COLLADA") return out;

  // Geometry id → name, so that a skin can be found by either.
  std::map<std::string, std::string> geometry_name;
  for (const auto* g = child(child(root, "library_geometries"), "geometry"); g != nullptr;
       g = g->NextSiblingElement("geometry")) {
    const char* id = g->Attribute("id");
    const char* name = g->Attribute("name");
    if (id != nullptr && name != nullptr) geometry_name[id] = name;
  }
  for (const auto* library = child(root, "library_controllers"); library != nullptr;
       library = library->NextSiblingElement("library_controllers")) {
    for (const auto* controller = child(library, "controller"); controller != nullptr;
         controller = controller->NextSiblingElement("controller")) {
      const auto* skin = child(controller, "skin");
      const auto* matrix = child(skin, "bind_shape_matrix");
      const char* source = skin != nullptr ? skin->Attribute("source") : nullptr;
      if (matrix == nullptr || source == nullptr || matrix->GetText() == nullptr) continue;
      const char* cid = controller->Attribute("id");
      const std::string where =
          file.string() + ": controller '" + (cid != nullptr ? cid : "?") + "'";
      // Sixteen numbers, row by row (COLLADA stores matrices in row-major order).
      std::vector<double> values;
      const char* p = matrix->GetText();
      for (char* end = nullptr;; p = end) {
        const double v = std::strtod(p, &end);
        if (end == p) break;
        values.push_back(v);
      }
      if (values.size() != 16 ||
          !std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); })) {
        throw InvalidInput(where + ": bind_shape_matrix is not 16 finite numbers");
      }
      Eigen::Matrix4d m;
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) m(r, c) = values[static_cast<std::size_t>(4 * r + c)];
      }
      if (m.isIdentity(0.0)) continue;
      Eigen::Affine3d a = Eigen::Affine3d::Identity();
      a.matrix().topRows<3>() = m.topRows<3>();
      std::string geometry = source;
      if (!geometry.empty() && geometry.front() == '#') geometry.erase(0, 1);
      out[geometry] = a;
      if (const auto it = geometry_name.find(geometry); it != geometry_name.end())
        out[it->second] = a;
    }
  }
  return out;
}

}  // namespace skelcd::skinning::detail
