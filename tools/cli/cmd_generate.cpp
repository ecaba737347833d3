// skelcd generate NAME [--triangles N] [--frames N] -o OUT [--json] | --list: writes a generated
// rig with a known answer where every MODEL argument can read it back exactly — a folder of
// per-frame PLY files (double precision) — or, for the Panda, its joint trajectory CSV.

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/generators_panda.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/urdf_trajectory.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"

namespace skelcd::tools {
namespace {

namespace fs = std::filesystem;

struct GenerateArgs {
  std::string name;
  std::int64_t triangles = 0;
  int frames = 0;
  std::string output;
  bool list = false;
  bool json = false;
};

// Binary little-endian PLY: double x y z, then uchar-counted int triangles.
void write_ply(
    const fs::path& file,
    const skinning::Positions& positions,
    const skinning::Triangles& triangles) {
  std::ostringstream out(std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\ncomment skelcd generate\nelement vertex "
      << positions.rows()
      << "\nproperty double x\nproperty double y\nproperty double z\nelement face "
      << triangles.rows() << "\nproperty list uchar int vertex_indices\nend_header\n";
  static_assert(
      std::endian::native == std::endian::little, "the PLY writer assumes a little-endian host");
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    for (int k = 0; k < 3; ++k) {
      const double c = positions(v, k);
      out.write(reinterpret_cast<const char*>(&c), sizeof c);
    }
  }
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    out.put(3);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t i = triangles(f, k);
      out.write(reinterpret_cast<const char*>(&i), sizeof i);
    }
  }
  std::ofstream file_out(file, std::ios::binary);
  file_out << out.str();
  if (!file_out.flush()) throw IoError(file.string() + ": cannot write");
}

// Everything is written into a sibling temporary folder first and renamed at the end, so a
// failure leaves no half-written output.
void write_frames(const skinning::GeneratedRig& g, const fs::path& out) {
  std::error_code ec;
  if (fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec))) {
    throw IoError(out.string() + ": exists and is not an empty folder (not overwritten)");
  }
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) throw IoError(parent.string() + ": no such folder");
  const fs::path tmp = parent / (out.filename().string() + ".tmp-" + std::to_string(::getpid()));
  fs::remove_all(tmp, ec);
  if (!fs::create_directory(tmp, ec))
    throw IoError(tmp.string() + ": cannot create folder: " + ec.message());
  try {
    auto rig = std::make_shared<const skinning::Rig>(g.rig);
    skinning::RigMotionOptions options;
    options.clip = 0;
    const skinning::RigMotion motion(rig, options);
    const int width = static_cast<int>(std::to_string(motion.num_samples() - 1).size());
    Progress progress("writing frames", motion.num_samples());
    skinning::Positions p;
    for (int i = 0; i < motion.num_samples(); ++i) {
      motion.positions(i, p);
      std::ostringstream name;
      name << "frame_" << std::setw(width) << std::setfill('0') << i << ".ply";
      write_ply(tmp / name.str(), p, g.rig.mesh.triangles);
      progress.update(i + 1);
    }
    progress.finish();
    if (fs::exists(out, ec)) fs::remove(out, ec);  // the empty folder it may replace
    fs::rename(tmp, out, ec);
    if (ec) throw IoError(out.string() + ": cannot move the frames into place: " + ec.message());
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

nlohmann::json answer_json(const skinning::KnownAnswer& a) {
  return {
      {"last_free_frame", a.last_free_frame},
      {"first_intersecting_frame", a.first_intersecting_frame},
      {"rule", a.rule}};
}

std::string answer_text(const skinning::KnownAnswer& a, int frames) {
  std::ostringstream s;
  s << "known answer: frames 0-" << a.last_free_frame << " free";
  if (a.first_intersecting_frame >= 0) {
    s << ", frames " << a.first_intersecting_frame << "-" << frames - 1 << " self-intersecting";
  }
  s << "\n  (" << a.rule << ")\n";
  return s.str();
}

void run_list(bool json) {
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const skinning::GeneratorInfo& g : skinning::generator_list()) {
      list.push_back(
          {{"name", g.name},
           {"description", g.description},
           {"default_triangles", g.default_triangles},
           {"default_frames", g.default_frames},
           {"closed", g.closed},
           {"known_answer", g.known_answer}});
    }
    print_json(nlohmann::json{{"generators", list}});
    return;
  }
  for (const skinning::GeneratorInfo& g : skinning::generator_list()) {
    std::cout << std::left << std::setw(11) << g.name << g.description << "\n"
              << std::setw(11) << "" << (g.closed ? "closed" : "open") << ", "
              << (g.default_triangles > 0
                      ? "default " + std::to_string(g.default_triangles) + " triangles, "
                      : "fixed size, ")
              << g.default_frames << " frames; " << g.known_answer << "\n";
  }
}

void run_generate(const GenerateArgs& args) {
  if (args.list) {
    run_list(args.json);
    return;
  }
  if (args.name.empty()) throw skelcd::InvalidInput("generate: give a generator NAME (see --list)");
  if (args.output.empty())
    throw skelcd::InvalidInput(
        "generate: give -o OUT (a folder for PLY frames, or .csv for the Panda)");
  skinning::GeneratorSpec spec;
  spec.name = args.name;
  spec.triangles = args.triangles;
  spec.frames = args.frames;
  // The spec string path validates names and ranges with the messages users see elsewhere.
  std::string text = "gen:" + spec.name + "?";
  if (spec.triangles != 0) text += "triangles=" + std::to_string(spec.triangles) + "&";
  if (spec.frames != 0) text += "frames=" + std::to_string(spec.frames) + "&";
  text.pop_back();
  const skinning::GeneratorSpec parsed = skinning::parse_generator_spec(text);

  const fs::path out(args.output);
  const bool csv = out.extension() == ".csv";
  skinning::GeneratedRig g;
  std::string format;
  if (csv) {
    if (parsed.name != "panda" && parsed.name != "panda-free") {
      throw skelcd::InvalidInput(
          out.string() + ": a .csv output is the Panda's joint trajectory; " + parsed.name +
          " is written as a folder of PLY frames");
    }
    g = skinning::generate(parsed);
    const skinning::Robot panda = skinning::load_bundled_panda();
    const auto trajectory =
        skinning::panda_trajectory(panda, g.spec.frames, parsed.name == "panda");
    const fs::path tmp = out.string() + ".tmp-" + std::to_string(::getpid());
    skinning::write_joint_trajectory(tmp, panda, trajectory);
    std::error_code ec;
    fs::rename(tmp, out, ec);
    if (ec) {
      fs::remove(tmp, ec);
      throw IoError(out.string() + ": cannot write");
    }
    format = "joint trajectory CSV";
  } else {
    if (out.has_extension()) {
      throw skelcd::InvalidInput(
          out.string() +
          ": write a folder of PLY frames (a path without extension) or, for the Panda, a .csv");
    }
    g = skinning::generate(parsed);
    write_frames(g, out);
    format = "PLY frames";
  }
  if (args.json) {
    print_json(
        {{"spec", g.rig.source},
         {"name", g.spec.name},
         {"triangles", g.rig.mesh.num_triangles()},
         {"vertices", g.rig.mesh.num_vertices()},
         {"bones", g.rig.skeleton.num_bones()},
         {"frames", g.spec.frames},
         {"output", out.string()},
         {"format", format},
         {"known_answer", answer_json(g.answer)}});
    return;
  }
  std::cout << "wrote " << g.rig.source << " (" << g.rig.mesh.num_triangles() << " triangles, "
            << g.rig.mesh.num_vertices() << " vertices, " << g.rig.skeleton.num_bones()
            << " bones, " << g.spec.frames << " frames) to " << out.string() << " as " << format
            << "\n"
            << answer_text(g.answer, g.spec.frames);
}

}  // namespace

void add_generate_command(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  auto* cmd = app.add_subcommand(
      "generate",
      "rigs with known answers (rope, octopus, hand, pipe, cloth, panda, panda-free); also usable "
      "as MODEL "
      "'gen:NAME?triangles=N&frames=N'");
  cmd->add_option("name", args->name, "generator name (see --list)");
  cmd->add_option(
      "--triangles",
      args->triangles,
      "about this many triangles (100 to 5,000,000; default per generator)");
  cmd->add_option(
      "--frames", args->frames, "frames of the clip, at 30 per second (default per generator)");
  cmd->add_option(
      "-o,--output",
      args->output,
      "a new folder for per-frame PLY files, or a .csv for the Panda's trajectory");
  cmd->add_flag("--list", args->list, "list the generators and their known answers");
  cmd->add_flag("--json", args->json, "print one JSON object");
  cmd->callback([args] { run_generate(*args); });
}

}  // namespace skelcd::tools
