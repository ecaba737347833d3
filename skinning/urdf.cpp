#include "skinning/urdf.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <numbers>
#include <numeric>
#include <set>
#include <sstream>
#include <unordered_map>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "skinning/errors.hpp"
#include "skinning/urdf_srdf.hpp"

namespace skelcd::skinning {

namespace fs = std::filesystem;

std::string_view joint_type_name(JointType type) {
  switch (type) {
    case JointType::kFixed: return "fixed";
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
  }
  return "unknown";
}

std::int32_t Robot::num_movable_joints() const {
  return static_cast<std::int32_t>(
      std::count_if(joints.begin(), joints.end(), [](const RobotJoint& j) { return j.movable(); }));
}

std::int32_t Robot::find_link(std::string_view link_name) const {
  for (std::size_t i = 0; i < links.size(); ++i) {
    if (links[i].name == link_name) return static_cast<std::int32_t>(i);
  }
  return -1;
}

std::int32_t Robot::find_joint(std::string_view joint_name) const {
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == joint_name) return static_cast<std::int32_t>(i);
  }
  return -1;
}

Eigen::Affine3d joint_transform(const RobotJoint& joint, double position) {
  switch (joint.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      return joint.origin * Eigen::AngleAxisd(position, joint.axis);
    case JointType::kPrismatic:
      return joint.origin * Eigen::Translation3d(position * joint.axis);
    case JointType::kFixed:
      break;
  }
  return joint.origin;
}

std::vector<double> resolve_mimic(const Robot& robot, std::span<const double> positions) {
  std::vector<double> q(positions.begin(), positions.end());
  // Mimic chains were checked acyclic at load; follow each to its master.
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    if (robot.joints[j].mimic_joint < 0) continue;
    double multiplier = 1.0;
    double offset = 0.0;
    std::int32_t k = static_cast<std::int32_t>(j);
    while (robot.joints[static_cast<std::size_t>(k)].mimic_joint >= 0) {
      const RobotJoint& mj = robot.joints[static_cast<std::size_t>(k)];
      // value(k) = m * value(master) + o; compose outer(value) = multiplier * value + offset.
      offset += multiplier * mj.mimic_offset;
      multiplier *= mj.mimic_multiplier;
      k = mj.mimic_joint;
    }
    q[j] = multiplier * positions[static_cast<std::size_t>(k)] + offset;
  }
  return q;
}

std::vector<Eigen::Affine3d> forward_kinematics(
    const Robot& robot,
    std::span<const double> positions) {
  assert(positions.size() == robot.joints.size());
  const std::vector<double> q = resolve_mimic(robot, positions);
  std::vector<Eigen::Affine3d> world(robot.links.size(), Eigen::Affine3d::Identity());
  // Links are in skeleton order: a parent's transform is ready before its children's.
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    const std::int32_t j = robot.links[i].parent_joint;
    if (j < 0) continue;
    const RobotJoint& joint = robot.joints[static_cast<std::size_t>(j)];
    world[i] = world[static_cast<std::size_t>(joint.parent_link)] *
               joint_transform(joint, q[static_cast<std::size_t>(j)]);
  }
  return world;
}

namespace {

std::string read_text_file(const fs::path& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open " + what);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": cannot read " + what);
  return text.str();
}

// ---------------------------------------------------------------------------------------------
// Structure check on the raw XML, before urdfdom: urdfdom accepts a link with two parents (the
// second joint silently wins) and reports other faults only through its log, so the faults a
// user can make are found here with messages that name them.
void check_urdf_structure(const std::string& text, const std::string& source) {
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error()) {
    throw IoError(source + ": not well-formed XML at row " + std::to_string(doc.ErrorRow()) +
                  ", column " + std::to_string(doc.ErrorCol()) + ": " + doc.ErrorDesc());
  }
  const TiXmlElement* robot = doc.RootElement();
  if (robot == nullptr || robot->ValueStr() != "robot") {
    throw InvalidInput(source + ": URDF root element is not <robot>");
  }
  std::set<std::string> links;
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const char* name = e->Attribute("name");
    if (name == nullptr) {
      throw InvalidInput(source + ": <link> at row " + std::to_string(e->Row()) + " has no name");
    }
    if (!links.insert(name).second) {
      throw InvalidInput(source + ": link '" + name + "' is defined twice");
    }
  }
  std::map<std::string, std::string> parent_of;       // child link -> parent link
  std::map<std::string, std::string> joint_of_child;  // child link -> joint name
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const char* name = e->Attribute("name");
    const std::string joint = name != nullptr ? name : "(row " + std::to_string(e->Row()) + ")";
    const TiXmlElement* p = e->FirstChildElement("parent");
    const TiXmlElement* c = e->FirstChildElement("child");
    const char* parent = p != nullptr ? p->Attribute("link") : nullptr;
    const char* child = c != nullptr ? c->Attribute("link") : nullptr;
    if (parent == nullptr || child == nullptr) {
      throw InvalidInput(source + ": joint '" + joint + "' lacks <parent link> or <child link>");
    }
    if (links.count(parent) == 0) {
      throw InvalidInput(source + ": joint '" + joint + "' names unknown parent link '" + parent + "'");
    }
    if (links.count(child) == 0) {
      throw InvalidInput(source + ": joint '" + joint + "' names unknown child link '" + child + "'");
    }
    if (std::string(parent) == child) {
      throw InvalidInput(source + ": joint '" + joint + "' connects link '" + parent + "' to itself (joint cycle)");
    }
    if (const auto it = joint_of_child.find(child); it != joint_of_child.end()) {
      throw InvalidInput(source + ": link '" + child + "' has two parents (joints '" + it->second +
                         "' and '" + joint + "')");
    }
    parent_of[child] = parent;
    joint_of_child[child] = joint;
  }
  // Every link has at most one parent now; a link from which following parents never reaches a
  // root lies on a cycle.
  for (const std::string& link : links) {
    std::set<std::string> seen;
    std::string at = link;
    while (parent_of.count(at) != 0) {
      if (!seen.insert(at).second) {
        std::string cycle;
        std::string c = at;
        do {
          cycle += (cycle.empty() ? "" : " -> ") + c;
          c = parent_of[c];
        } while (c != at);
        throw InvalidInput(source + ": joint cycle through links " + cycle + " -> " + at);
      }
      at = parent_of[at];
    }
  }
  std::size_t roots = 0;
  for (const std::string& link : links) roots += parent_of.count(link) == 0 ? 1U : 0U;
  if (links.empty()) throw InvalidInput(source + ": URDF has no links");
  if (roots != 1) {
    throw InvalidInput(source + ": URDF has " + std::to_string(roots) +
                       " root links (links without a parent joint); a robot is one tree");
  }
}

// urdfdom reports faults through console_bridge; capture them for our message and keep them off
// stderr. console_bridge's handler is process-global, hence the lock.
class CapturingHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      if (!errors.empty()) errors += "; ";
      errors += text;
    }
  }
  std::string errors;
};

urdf::ModelInterfaceSharedPtr parse_with_urdfdom(const std::string& text, const std::string& source) {
  static std::mutex mutex;
  const std::lock_guard lock(mutex);
  CapturingHandler handler;
  console_bridge::OutputHandler* previous = console_bridge::getOutputHandler();
  console_bridge::useOutputHandler(&handler);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    console_bridge::useOutputHandler(previous);
    throw InvalidInput(source + ": invalid URDF: " + e.what());
  }
  console_bridge::useOutputHandler(previous);
  if (!model) {
    throw InvalidInput(source + ": invalid URDF: " +
                       (handler.errors.empty() ? std::string("urdfdom rejected it") : handler.errors));
  }
  return model;
}

Eigen::Affine3d to_affine(const urdf::Pose& pose) {
  double x = 0, y = 0, z = 0, w = 1;
  pose.rotation.getQuaternion(x, y, z, w);
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() = Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return t;
}

// ---------------------------------------------------------------------------------------------
// Geometry of one URDF element, in the element's own frame.
struct ElementMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
};

ElementMesh tessellate_box(const Eigen::Vector3d& size) {
  ElementMesh m;
  const Eigen::Vector3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  // Two triangles per face, counter-clockwise seen from outside.
  m.triangles = {{0, 2, 1}, {1, 2, 3},   // -z
                 {4, 5, 6}, {5, 7, 6},   // +z
                 {0, 1, 4}, {1, 5, 4},   // -y
                 {2, 6, 3}, {3, 6, 7},   // +y
                 {0, 4, 2}, {2, 4, 6},   // -x
                 {1, 3, 5}, {3, 7, 5}};  // +x
  return m;
}

ElementMesh tessellate_cylinder(double radius, double length, int segments) {
  ElementMesh m;
  const auto n = static_cast<std::int32_t>(segments);
  for (int ring = 0; ring < 2; ++ring) {
    const double z = ring == 0 ? -0.5 * length : 0.5 * length;
    for (std::int32_t k = 0; k < n; ++k) {
      const double a = 2.0 * std::numbers::pi * k / n;
      m.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
    }
  }
  const std::int32_t bottom = 2 * n;
  const std::int32_t top = 2 * n + 1;
  m.vertices.emplace_back(0.0, 0.0, -0.5 * length);
  m.vertices.emplace_back(0.0, 0.0, 0.5 * length);
  for (std::int32_t k = 0; k < n; ++k) {
    const std::int32_t k1 = (k + 1) % n;
    m.triangles.push_back({k, k1, n + k});
    m.triangles.push_back({k1, n + k1, n + k});
    m.triangles.push_back({bottom, k1, k});
    m.triangles.push_back({top, n + k, n + k1});
  }
  return m;
}

ElementMesh tessellate_sphere(double radius, int segments, int rings) {
  ElementMesh m;
  const auto n = static_cast<std::int32_t>(segments);
  m.vertices.emplace_back(0.0, 0.0, radius);  // north pole
  for (int r = 1; r < rings; ++r) {
    const double polar = std::numbers::pi * r / rings;
    for (std::int32_t k = 0; k < n; ++k) {
      const double a = 2.0 * std::numbers::pi * k / n;
      m.vertices.emplace_back(radius * std::sin(polar) * std::cos(a),
                              radius * std::sin(polar) * std::sin(a), radius * std::cos(polar));
    }
  }
  const auto south = static_cast<std::int32_t>(m.vertices.size());
  m.vertices.emplace_back(0.0, 0.0, -radius);
  const auto at = [n](int ring, std::int32_t k) { return 1 + (ring - 1) * n + (k % n); };
  for (std::int32_t k = 0; k < n; ++k) {
    m.triangles.push_back({0, at(1, k), at(1, k + 1)});
    for (int r = 1; r + 1 < rings; ++r) {
      m.triangles.push_back({at(r, k), at(r + 1, k), at(r + 1, k + 1)});
      m.triangles.push_back({at(r, k), at(r + 1, k + 1), at(r, k + 1)});
    }
    m.triangles.push_back({south, at(rings - 1, k + 1), at(rings - 1, k)});
  }
  return m;
}

// Loads a mesh file through assimp: every triangle of every mesh node, node transforms applied,
// points and lines skipped, vertices in file order (nothing welded or reordered).
ElementMesh load_mesh_file(const fs::path& path, const std::string& context) {
  Assimp::Importer importer;
  // URDF meshes are authored in the link frame: keep Collada's Z-up coordinates as they are
  // (assimp would otherwise rotate them to Y-up); the Collada unit is still applied.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    throw IoError(context + ": cannot load mesh " + path.string() + ": " + importer.GetErrorString());
  }
  ElementMesh m;
  std::function<void(const aiNode*, const aiMatrix4x4&)> visit = [&](const aiNode* node,
                                                                      const aiMatrix4x4& parent) {
    const aiMatrix4x4 global = parent * node->mTransformation;
    Eigen::Matrix4d t;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) t(r, c) = static_cast<double>(global[static_cast<unsigned>(r)][static_cast<unsigned>(c)]);
    }
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
      const auto base = static_cast<std::int32_t>(m.vertices.size());
      for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const Eigen::Vector4d h = t * Eigen::Vector4d(static_cast<double>(p.x), static_cast<double>(p.y),
                                                      static_cast<double>(p.z), 1.0);
        m.vertices.emplace_back(h.head<3>());
      }
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3) continue;
        m.triangles.push_back({base + static_cast<std::int32_t>(face.mIndices[0]),
                               base + static_cast<std::int32_t>(face.mIndices[1]),
                               base + static_cast<std::int32_t>(face.mIndices[2])});
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], global);
  };
  visit(scene->mRootNode, aiMatrix4x4());
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    if (!m.vertices[v].allFinite()) {
      throw InvalidInput(context + ": mesh " + path.string() + ": vertex " + std::to_string(v) +
                         " has a non-finite coordinate");
    }
  }
  if (m.triangles.empty()) {
    throw InvalidInput(context + ": mesh " + path.string() + " has no triangles");
  }
  return m;
}

// The folders searched for mesh files: the URDF's folder, its ancestors, then --package-path.
std::vector<fs::path> search_path(const fs::path& urdf_file, const std::vector<fs::path>& extra) {
  std::vector<fs::path> dirs;
  fs::path dir = fs::absolute(urdf_file).parent_path();
  while (true) {
    dirs.push_back(dir);
    if (!dir.has_parent_path() || dir.parent_path() == dir) break;
    dir = dir.parent_path();
  }
  for (const fs::path& p : extra) dirs.push_back(fs::absolute(p));
  return dirs;
}

// Resolves a URDF mesh filename: package://NAME/REST is DIR/REST for a searched DIR named NAME,
// or DIR/NAME/REST; file://PATH is PATH; a relative path is tried against each searched folder.
fs::path resolve_mesh(const std::string& filename, const std::vector<fs::path>& dirs,
                      const std::string& context) {
  static constexpr std::string_view kPackage = "package://";
  static constexpr std::string_view kFile = "file://";
  std::string tried;
  const auto exists = [&](const fs::path& p) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return true;
    tried += (tried.empty() ? "" : ", ") + p.string();
    return false;
  };
  if (filename.rfind(kPackage, 0) == 0) {
    const std::string rest = filename.substr(kPackage.size());
    const auto slash = rest.find('/');
    if (slash == std::string::npos || slash == 0) {
      throw InvalidInput(context + ": malformed mesh filename '" + filename + "'");
    }
    const std::string package = rest.substr(0, slash);
    const fs::path relative = rest.substr(slash + 1);
    for (const fs::path& d : dirs) {
      if (d.filename() == package && exists(d / relative)) return d / relative;
      if (exists(d / package / relative)) return d / package / relative;
    }
  } else if (filename.rfind(kFile, 0) == 0) {
    const fs::path p = filename.substr(kFile.size());
    if (exists(p)) return p;
  } else if (fs::path(filename).is_absolute()) {
    if (exists(filename)) return filename;
  } else {
    for (const fs::path& d : dirs) {
      if (exists(d / filename)) return d / filename;
    }
  }
  throw IoError(context + ": mesh file '" + filename + "' not found (tried " + tried + ")");
}

}  // namespace

Robot load_urdf(const fs::path& urdf_file, const UrdfOptions& options) {
  const std::string source = urdf_file.string();
  if (options.round_segments < 3 || options.sphere_rings < 2) {
    throw InvalidInput("load_urdf: round_segments must be >= 3 and sphere_rings >= 2");
  }
  const std::string text = read_text_file(urdf_file, "URDF file");
  check_urdf_structure(text, source);
  const urdf::ModelInterfaceSharedPtr model = parse_with_urdfdom(text, source);

  Robot robot;
  robot.name = model->getName();
  robot.urdf_file = urdf_file;

  // Links in breadth-first order from the root: parents precede children.
  std::vector<urdf::LinkConstSharedPtr> order{model->getRoot()};
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (const urdf::LinkSharedPtr& child : order[i]->child_links) order.push_back(child);
  }
  if (order.size() != model->links_.size()) {
    throw InvalidInput(source + ": " + std::to_string(model->links_.size() - order.size()) +
                       " links are not connected to the root link '" + order[0]->name + "'");
  }
  std::unordered_map<std::string, std::int32_t> link_index;
  for (std::size_t i = 0; i < order.size(); ++i) {
    robot.links.push_back({order[i]->name, -1, -1, -1});
    link_index[order[i]->name] = static_cast<std::int32_t>(i);
  }

  // Joints, one per non-root link, in link order.
  std::unordered_map<std::string, std::int32_t> joint_index;
  for (std::size_t i = 1; i < order.size(); ++i) {
    const urdf::JointSharedPtr& uj = order[i]->parent_joint;
    RobotJoint j;
    j.name = uj->name;
    const std::string where = source + ": joint '" + j.name + "'";
    switch (uj->type) {
      case urdf::Joint::FIXED: j.type = JointType::kFixed; break;
      case urdf::Joint::REVOLUTE: j.type = JointType::kRevolute; break;
      case urdf::Joint::CONTINUOUS: j.type = JointType::kContinuous; break;
      case urdf::Joint::PRISMATIC: j.type = JointType::kPrismatic; break;
      case urdf::Joint::FLOATING:
      case urdf::Joint::PLANAR:
      default:
        throw InvalidInput(where + " has an unsupported type (floating and planar joints are not supported)");
    }
    j.parent_link = link_index.at(uj->parent_link_name);
    j.child_link = static_cast<std::int32_t>(i);
    j.origin = to_affine(uj->parent_to_joint_origin_transform);
    if (!j.origin.matrix().allFinite()) throw InvalidInput(where + " has a non-finite origin");
    j.axis = Eigen::Vector3d(uj->axis.x, uj->axis.y, uj->axis.z);
    if (j.movable()) {
      const double norm = j.axis.norm();
      if (!std::isfinite(norm) || norm == 0.0) throw InvalidInput(where + " has a zero or non-finite axis");
      j.axis /= norm;
    }
    if ((j.type == JointType::kRevolute || j.type == JointType::kPrismatic) && uj->limits) {
      j.has_limits = true;
      j.lower = uj->limits->lower;
      j.upper = uj->limits->upper;
      if (!(j.lower <= j.upper)) throw InvalidInput(where + " has lower limit above upper limit");
    }
    joint_index[j.name] = static_cast<std::int32_t>(robot.joints.size());
    robot.links[i].parent_joint = static_cast<std::int32_t>(robot.joints.size());
    robot.joints.push_back(j);
  }
  // Mimic joints: the master must exist and be movable; chains must end.
  for (std::size_t i = 1; i < order.size(); ++i) {
    const urdf::JointSharedPtr& uj = order[i]->parent_joint;
    if (!uj->mimic) continue;
    RobotJoint& j = robot.joints[static_cast<std::size_t>(robot.links[i].parent_joint)];
    if (!j.movable()) continue;  // a fixed joint has no position to mimic
    const auto it = joint_index.find(uj->mimic->joint_name);
    if (it == joint_index.end()) {
      throw InvalidInput(source + ": joint '" + j.name + "' mimics unknown joint '" + uj->mimic->joint_name + "'");
    }
    if (!robot.joints[static_cast<std::size_t>(it->second)].movable()) {
      throw InvalidInput(source + ": joint '" + j.name + "' mimics fixed joint '" + uj->mimic->joint_name + "'");
    }
    j.mimic_joint = it->second;
    j.mimic_multiplier = uj->mimic->multiplier;
    j.mimic_offset = uj->mimic->offset;
  }
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    std::int32_t k = static_cast<std::int32_t>(j);
    for (std::size_t steps = 0; robot.joints[static_cast<std::size_t>(k)].mimic_joint >= 0; ++steps) {
      if (steps > robot.joints.size()) {
        throw InvalidInput(source + ": mimic cycle through joint '" + robot.joints[j].name + "'");
      }
      k = robot.joints[static_cast<std::size_t>(k)].mimic_joint;
    }
  }

  // Rest pose: every joint at 0.
  const std::vector<double> zero(robot.joints.size(), 0.0);
  const std::vector<Eigen::Affine3d> rest = forward_kinematics(robot, zero);

  // Skeleton: node i = link i.
  Skeleton& skeleton = robot.rig.skeleton;
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    SkeletonNode node;
    node.name = robot.links[i].name;
    const std::int32_t j = robot.links[i].parent_joint;
    if (j >= 0) {
      node.parent = robot.joints[static_cast<std::size_t>(j)].parent_link;
      node.rest_local = robot.joints[static_cast<std::size_t>(j)].origin;
    }
    skeleton.nodes.push_back(node);
  }

  // Geometry: collision elements, or visual elements when a link has no collision element.
  const std::vector<fs::path> dirs = search_path(urdf_file, options.package_path);
  std::map<fs::path, ElementMesh> file_cache;
  Mesh& mesh = robot.rig.mesh;
  std::vector<std::vector<Eigen::Vector3d>> part_vertices;
  std::vector<Eigen::Index> vertex_bone;  // bone of each vertex
  std::vector<Eigen::Vector3d> all_vertices;
  std::vector<std::array<std::int32_t, 3>> all_triangles;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const urdf::LinkConstSharedPtr& ul = order[i];
    struct Element {
      urdf::Pose origin;
      urdf::GeometrySharedPtr geometry;
    };
    std::vector<Element> elements;
    for (const auto& c : ul->collision_array) {
      if (c && c->geometry) elements.push_back({c->origin, c->geometry});
    }
    if (elements.empty()) {
      for (const auto& v : ul->visual_array) {
        if (v && v->geometry) elements.push_back({v->origin, v->geometry});
      }
    }
    if (elements.empty()) continue;
    const std::string context = source + ": link '" + ul->name + "'";
    const auto part = static_cast<std::int32_t>(mesh.part_names.size());
    const auto bone = static_cast<std::int32_t>(skeleton.bones.size());
    mesh.part_names.push_back(ul->name);
    robot.links[i].part = part;
    robot.links[i].bone = bone;
    std::int32_t part_vertex = 0;
    std::int32_t part_face = 0;
    for (const Element& e : elements) {
      ElementMesh em;
      Eigen::Vector3d scale = Eigen::Vector3d::Ones();
      switch (e.geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& box = static_cast<const urdf::Box&>(*e.geometry);
          em = tessellate_box(Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z));
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cyl = static_cast<const urdf::Cylinder&>(*e.geometry);
          em = tessellate_cylinder(cyl.radius, cyl.length, options.round_segments);
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& sphere = static_cast<const urdf::Sphere&>(*e.geometry);
          em = tessellate_sphere(sphere.radius, options.round_segments, options.sphere_rings);
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& um = static_cast<const urdf::Mesh&>(*e.geometry);
          const fs::path file = resolve_mesh(um.filename, dirs, context);
          auto it = file_cache.find(file);
          if (it == file_cache.end()) it = file_cache.emplace(file, load_mesh_file(file, context)).first;
          em = it->second;
          scale = Eigen::Vector3d(um.scale.x, um.scale.y, um.scale.z);
          break;
        }
      }
      if (!scale.allFinite()) throw InvalidInput(context + ": non-finite mesh scale");
      // Element frame (scaled) → link frame (element origin) → object space at rest.
      const Eigen::Affine3d to_object = rest[i] * to_affine(e.origin);
      if (!to_object.matrix().allFinite()) throw InvalidInput(context + ": non-finite geometry origin");
      const auto base = static_cast<std::int32_t>(all_vertices.size());
      for (const Eigen::Vector3d& v : em.vertices) {
        all_vertices.push_back(to_object * v.cwiseProduct(scale));
        mesh.vertex_part.push_back(part);
        mesh.vertex_index_in_part.push_back(part_vertex++);
        vertex_bone.push_back(bone);
      }
      for (const auto& t : em.triangles) {
        all_triangles.push_back({base + t[0], base + t[1], base + t[2]});
        mesh.face_part.push_back(part);
        mesh.face_index_in_part.push_back(part_face++);
      }
    }
    Bone b;
    b.name = ul->name;
    b.node = static_cast<std::int32_t>(i);
    for (std::int32_t a = skeleton.nodes[i].parent; a >= 0; a = skeleton.nodes[static_cast<std::size_t>(a)].parent) {
      if (robot.links[static_cast<std::size_t>(a)].bone >= 0) {
        b.parent = robot.links[static_cast<std::size_t>(a)].bone;
        break;
      }
    }
    b.inverse_bind = rest[i].inverse();
    b.rest_head = rest[i].translation();
    // Tail: the first child link's origin; else the centroid of the link's geometry.
    b.rest_tail = b.rest_head;
    for (std::size_t c = i + 1; c < order.size(); ++c) {
      if (skeleton.nodes[c].parent == static_cast<std::int32_t>(i) &&
          (rest[c].translation() - b.rest_head).norm() > 0.0) {
        b.rest_tail = rest[c].translation();
        break;
      }
    }
    if (b.rest_tail == b.rest_head) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      std::int32_t count = 0;
      for (std::size_t v = all_vertices.size() - static_cast<std::size_t>(part_vertex); v < all_vertices.size(); ++v) {
        centroid += all_vertices[v];
        ++count;
      }
      b.rest_tail = centroid / count;
    }
    skeleton.bones.push_back(b);
  }

  mesh.rest_positions.resize(static_cast<Eigen::Index>(all_vertices.size()), 3);
  for (std::size_t v = 0; v < all_vertices.size(); ++v) {
    mesh.rest_positions.row(static_cast<Eigen::Index>(v)) = all_vertices[v].transpose();
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(all_triangles.size()), 3);
  for (std::size_t f = 0; f < all_triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      mesh.triangles(static_cast<Eigen::Index>(f), k) = all_triangles[f][static_cast<std::size_t>(k)];
    }
  }

  // Rigid skinning: each vertex follows its link's bone with weight 1.
  SkinWeights& weights = robot.rig.weights;
  weights.resize(mesh.num_vertices(), skeleton.num_bones());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(vertex_bone.size());
  for (std::size_t v = 0; v < vertex_bone.size(); ++v) {
    triplets.emplace_back(static_cast<Eigen::Index>(v), vertex_bone[v], 1.0);
  }
  weights.setFromTriplets(triplets.begin(), triplets.end());
  weights.makeCompressed();

  // Excluded part pairs.
  std::set<std::pair<std::int32_t, std::int32_t>> excluded;
  const auto exclude = [&excluded](std::int32_t a, std::int32_t b) {
    excluded.insert({std::min(a, b), std::max(a, b)});
  };
  // (a, a): a rigid link cannot deform into itself.
  for (const RobotLink& l : robot.links) {
    if (l.part >= 0) exclude(l.part, l.part);
  }
  // Parent-child: a link and the nearest ancestor with geometry touch at their joint.
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    if (robot.links[i].part < 0) continue;
    for (std::int32_t a = skeleton.nodes[i].parent; a >= 0; a = skeleton.nodes[static_cast<std::size_t>(a)].parent) {
      if (robot.links[static_cast<std::size_t>(a)].part >= 0) {
        exclude(robot.links[static_cast<std::size_t>(a)].part, robot.links[i].part);
        break;
      }
    }
  }
  // Rigid groups: links joined by fixed joints never move relative to each other.
  std::vector<std::int32_t> group(robot.links.size());
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    const std::int32_t j = robot.links[i].parent_joint;
    group[i] = (j >= 0 && robot.joints[static_cast<std::size_t>(j)].type == JointType::kFixed)
                   ? group[static_cast<std::size_t>(robot.joints[static_cast<std::size_t>(j)].parent_link)]
                   : static_cast<std::int32_t>(i);
  }
  for (std::size_t a = 0; a < robot.links.size(); ++a) {
    for (std::size_t b = a + 1; b < robot.links.size(); ++b) {
      if (group[a] == group[b] && robot.links[a].part >= 0 && robot.links[b].part >= 0) {
        exclude(robot.links[a].part, robot.links[b].part);
      }
    }
  }
  // SRDF: disabled pairs.
  if (!options.srdf.empty()) {
    for (const DisabledCollisionPair& p : read_srdf_disabled_collisions(options.srdf)) {
      const std::int32_t a = robot.find_link(p.link1);
      const std::int32_t b = robot.find_link(p.link2);
      if (a < 0 || b < 0) {
        throw InvalidInput(options.srdf.string() + ": <disable_collisions> names link '" +
                           (a < 0 ? p.link1 : p.link2) + "', which robot '" + robot.name + "' in " +
                           source + " does not have");
      }
      const std::int32_t pa = robot.links[static_cast<std::size_t>(a)].part;
      const std::int32_t pb = robot.links[static_cast<std::size_t>(b)].part;
      if (pa >= 0 && pb >= 0) exclude(pa, pb);
    }
  }
  mesh.excluded_part_pairs.assign(excluded.begin(), excluded.end());

  robot.rig.source = source;
  validate_mesh(mesh, source);
  return robot;
}

}  // namespace skelcd::skinning
