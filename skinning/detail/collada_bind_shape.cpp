#include "skinning/detail/collada_bind_shape.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <pugixml.hpp>
#include <string>
#include <vector>

#include "skinning/errors.hpp"

namespace skelcd::skinning::detail {
namespace {

// The text an element starts with, as TinyXML (which read these extras before) gave it: the
// element's first child when that is text (character data or CDATA), else none; character data
// with leading and trailing white space dropped and every inner run of it one space.
std::optional<std::string> leading_text(const pugi::xml_node element) {
  const pugi::xml_node first = element.first_child();
  if (first.type() == pugi::node_cdata) return std::string(first.value());
  if (first.type() != pugi::node_pcdata) return std::nullopt;
  std::string text;
  bool blank = false;
  for (const char* p = first.value(); *p != '\0'; ++p) {
    if (std::isspace(static_cast<unsigned char>(*p)) != 0) {
      blank = true;
    } else {
      if (blank && !text.empty()) text += ' ';
      blank = false;
      text += *p;
    }
  }
  return text;
}

// The 3ds Max <frame_rate> of a visual scene: its text (empty when it has none), or nothing when
// the scene has no such element.
std::optional<std::string> max3d_frame_rate(const pugi::xml_node scene) {
  for (pugi::xml_node extra = scene.child("extra"); extra; extra = extra.next_sibling("extra")) {
    for (pugi::xml_node technique = extra.child("technique"); technique;
         technique = technique.next_sibling("technique")) {
      const pugi::xml_attribute profile = technique.attribute("profile");
      if (!profile || std::strcmp(profile.value(), "MAX3D") != 0) continue;
      if (const pugi::xml_node rate = technique.child("frame_rate")) {
        return leading_text(rate).value_or(std::string());
      }
    }
  }
  return std::nullopt;
}

// The <frame_rate> text of the visual scene <scene> instances, else of the first that has one.
std::optional<std::string> scene_frame_rate(const pugi::xml_node root) {
  std::string instanced;
  if (const pugi::xml_node instance = root.child("scene").child("instance_visual_scene")) {
    const pugi::xml_attribute url = instance.attribute("url");
    if (url && url.value()[0] == '#') instanced = url.value() + 1;
  }
  std::optional<std::string> first;
  for (pugi::xml_node library = root.child("library_visual_scenes"); library;
       library = library.next_sibling("library_visual_scenes")) {
    for (pugi::xml_node scene = library.child("visual_scene"); scene;
         scene = scene.next_sibling("visual_scene")) {
      std::optional<std::string> rate = max3d_frame_rate(scene);
      if (!rate) continue;
      const pugi::xml_attribute id = scene.attribute("id");
      if (id && !instanced.empty() && instanced == id.value()) return rate;
      if (!first) first = std::move(rate);
    }
  }
  return first;
}

void read_frame_rate(const pugi::xml_node root, ColladaExtras& out) {
  const std::optional<std::string> rate = scene_frame_rate(root);
  if (!rate) return;
  const char* text = rate->c_str();
  char* end = nullptr;
  const double hz = std::strtod(text, &end);
  const bool only_blanks_after =
      std::all_of(static_cast<const char*>(end), text + rate->size(), [](unsigned char c) {
        return std::isspace(c) != 0;
      });
  if (end != text && only_blanks_after && std::isfinite(hz) && hz > 0) {
    out.frame_rate_hz = hz;
  } else {
    out.bad_frame_rate = *rate;
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
  pugi::xml_document doc;
  // TinyXML's reading before: comments are nodes (an element that starts with one has no
  // leading text); entities and CDATA are decoded.
  if (!doc.load_file(file.c_str(), pugi::parse_default | pugi::parse_comments))
    return extras;  // assimp says what is wrong with it
  const pugi::xml_node root = doc.document_element();
  if (!root || std::strcmp(root.name(), "COLLADA") != 0) return extras;
  read_frame_rate(root, extras);

  // Geometry id → name, so that a skin can be found by either.
  std::map<std::string, std::string> geometry_name;
  for (pugi::xml_node g = root.child("library_geometries").child("geometry"); g;
       g = g.next_sibling("geometry")) {
    const pugi::xml_attribute id = g.attribute("id");
    const pugi::xml_attribute name = g.attribute("name");
    if (id && name) geometry_name[id.value()] = name.value();
  }
  for (pugi::xml_node library = root.child("library_controllers"); library;
       library = library.next_sibling("library_controllers")) {
    for (pugi::xml_node controller = library.child("controller"); controller;
         controller = controller.next_sibling("controller")) {
      const pugi::xml_node skin = controller.child("skin");
      const pugi::xml_attribute source = skin.attribute("source");
      const std::optional<std::string> text = leading_text(skin.child("bind_shape_matrix"));
      if (!text || !source) continue;
      const pugi::xml_attribute cid = controller.attribute("id");
      const std::string where = file.string() + ": controller '" + (cid ? cid.value() : "?") + "'";
      // Sixteen numbers, row by row (COLLADA stores matrices in row-major order).
      std::vector<double> values;
      const char* p = text->c_str();
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
      std::string geometry = source.value();
      if (!geometry.empty() && geometry.front() == '#') geometry.erase(0, 1);
      out[geometry] = a;
      if (const auto it = geometry_name.find(geometry); it != geometry_name.end())
        out[it->second] = a;
    }
  }
  return extras;
}

}  // namespace skelcd::skinning::detail
