#include "skinning/detail/collada_bind_shape.hpp"

#include <tinyxml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "skinning/errors.hpp"

namespace skelcd::skinning::detail {
namespace {

const TiXmlElement* child(const TiXmlNode* parent, const char* name) {
  return parent == nullptr ? nullptr : parent->FirstChildElement(name);
}

// The 3ds Max <frame_rate> of a visual scene: its text, or null when it has none.
const char* max3d_frame_rate(const TiXmlElement* scene) {
  for (const auto* extra = child(scene, "extra"); extra != nullptr;
       extra = extra->NextSiblingElement("extra")) {
    for (const auto* technique = child(extra, "technique"); technique != nullptr;
         technique = technique->NextSiblingElement("technique")) {
      const char* profile = technique->Attribute("profile");
      if (profile == nullptr || std::string(profile) != "MAX3D") continue;
      const auto* rate = child(technique, "frame_rate");
      if (rate != nullptr) return rate->GetText() != nullptr ? rate->GetText() : "";
    }
  }
  return nullptr;
}

// The <frame_rate> text of the visual scene <scene> instances, else of the first that has one.
const char* scene_frame_rate(const TiXmlElement* root) {
  std::string instanced;
  if (const auto* instance = child(child(root, "scene"), "instance_visual_scene")) {
    const char* url = instance->Attribute("url");
    if (url != nullptr && url[0] == '#') instanced = url + 1;
  }
  const char* first = nullptr;
  for (const auto* library = child(root, "library_visual_scenes"); library != nullptr;
       library = library->NextSiblingElement("library_visual_scenes")) {
    for (const auto* scene = child(library, "visual_scene"); scene != nullptr;
         scene = scene->NextSiblingElement("visual_scene")) {
      const char* rate = max3d_frame_rate(scene);
      if (rate == nullptr) continue;
      const char* id = scene->Attribute("id");
      if (id != nullptr && !instanced.empty() && instanced == id) return rate;
      if (first == nullptr) first = rate;
    }
  }
  return first;
}

void read_frame_rate(const TiXmlElement* root, ColladaExtras& out) {
  const char* text = scene_frame_rate(root);
  if (text == nullptr) return;
  char* end = nullptr;
  const double hz = std::strtod(text, &end);
  const bool only_blanks_after =
      std::all_of(static_cast<const char*>(end), text + std::strlen(text), [](unsigned char c) {
        return std::isspace(c) != 0;
      });
  if (end != text && only_blanks_after && std::isfinite(hz) && hz > 0) {
    out.frame_rate_hz = hz;
  } else {
    out.bad_frame_rate = text;
  }
}

}  // namespace

ColladaExtras read_collada_extras(const std::filesystem::path& file) {
  ColladaExtras extras;
  auto& out = extras.bind_shapes;
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  if (ext != ".dae") return extras;
  TiXmlDocument doc;
  if (!doc.LoadFile(file.string().c_str())) return extras;  // assimp says what is wrong with it
  const TiXmlElement* root = doc.RootElement();
  if (root == nullptr || std::string(root->Value()) != "COLLADA") return extras;
  read_frame_rate(root, extras);

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
  return extras;
}

}  // namespace skelcd::skinning::detail
