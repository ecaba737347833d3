#include "tools/io/file_hash.hpp"

#include <array>
#include <cstdio>
#include <fstream>
#include <vector>

#include "skinning/errors.hpp"
#include "skinning/frame_sequence.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"

namespace skelcd::tools {

std::uint64_t fnv1a64(std::span<const unsigned char> bytes, std::uint64_t state) {
  constexpr std::uint64_t kPrime = 0x100000001b3ULL;
  for (const unsigned char byte : bytes) {
    state ^= byte;
    state *= kPrime;
  }
  return state;
}

namespace {

/// Bytes read at a time: the hash streams each file through this much. The buffer is zero-filled
/// when made, so all of it is resident: 1 MiB was that much of a logged run's memory.
constexpr std::size_t kHashBufferBytes = std::size_t{64} << 10;

std::uint64_t hash_file_into(const std::filesystem::path& path, std::uint64_t state) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open for reading");
  std::vector<char> buffer(kHashBufferBytes);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    state = fnv1a64(
        std::span<const unsigned char>(reinterpret_cast<const unsigned char*>(buffer.data()), n),
        state);
  }
  if (in.bad()) throw IoError(path.string() + ": read error while hashing");
  return state;
}

std::string hash_text(std::uint64_t state) {
  std::array<char, 17> hex{};
  std::snprintf(hex.data(), hex.size(), "%016llx", static_cast<unsigned long long>(state));
  return std::string("fnv1a64:") + hex.data();
}

}  // namespace

std::string file_content_hash(const std::filesystem::path& path) {
  return hash_text(hash_file_into(path, kFnv1a64Offset));
}

std::string model_identity(const std::string& model) {
  if (skinning::is_generator_spec(model)) {
    return skinning::to_string(skinning::parse_generator_spec(model));
  }
  if (skinning::classify_model_path(model) != skinning::ModelKind::frame_sequence) {
    return file_content_hash(model);
  }
  // A frame sequence: renaming, reordering, adding or editing a frame changes the hash.
  std::uint64_t state = kFnv1a64Offset;
  for (const auto& file : skinning::list_frame_files(model)) {
    const std::string name = file.filename().string() + '\0';
    state = fnv1a64(
        std::span<const unsigned char>(
            reinterpret_cast<const unsigned char*>(name.data()), name.size()),
        state);
    state = hash_file_into(file, state);
  }
  return hash_text(state);
}

}  // namespace skelcd::tools
