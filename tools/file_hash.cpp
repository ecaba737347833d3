#include "tools/file_hash.hpp"

#include <array>
#include <cstdio>
#include <fstream>
#include <vector>

#include "skinning/errors.hpp"

namespace skelcd::tools {

std::uint64_t fnv1a64(std::span<const unsigned char> bytes, std::uint64_t state) {
  constexpr std::uint64_t kPrime = 0x100000001b3ULL;
  for (const unsigned char byte : bytes) {
    state ^= byte;
    state *= kPrime;
  }
  return state;
}

std::string file_content_hash(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open for reading");
  std::vector<char> buffer(1 << 20);
  std::uint64_t state = kFnv1a64Offset;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    state = fnv1a64(
        std::span<const unsigned char>(reinterpret_cast<const unsigned char*>(buffer.data()), n),
        state);
  }
  if (in.bad()) throw IoError(path.string() + ": read error while hashing");
  std::array<char, 17> hex{};
  std::snprintf(hex.data(), hex.size(), "%016llx", static_cast<unsigned long long>(state));
  return std::string("fnv1a64:") + hex.data();
}

}  // namespace skelcd::tools
