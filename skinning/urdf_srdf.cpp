#include "skinning/urdf_srdf.hpp"

#include <fstream>
#include <sstream>

#include <tinyxml.h>

#include "skinning/errors.hpp"

namespace skelcd::skinning {

std::vector<DisabledCollisionPair> read_srdf_disabled_collisions(
    const std::filesystem::path& srdf_file) {
  std::ifstream in(srdf_file, std::ios::binary);
  if (!in) throw IoError(srdf_file.string() + ": cannot open SRDF file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(srdf_file.string() + ": cannot read SRDF file");
  return parse_srdf_disabled_collisions(text.str(), srdf_file.string());
}

std::vector<DisabledCollisionPair> parse_srdf_disabled_collisions(
    const std::string& text,
    const std::string& source) {
  // tinyxml (urdfdom's own XML parser) reads the document; we only walk its elements.
  // TinyXML 2.6.2 in UTF-8 mode (any document with an <?xml?> declaration) steps over the whole
  // length a multi-byte lead byte announces even when a NUL cuts the sequence short, and reads on
  // behind it: past the end of the text (a heap over-read found by fuzz/fuzz_srdf), or into what
  // follows a NUL inside it. A step is at most 4 bytes, so the parsed text ends in 4 NULs, and a
  // NUL inside the file is refused.
  if (const auto nul = text.find('\0'); nul != std::string::npos) {
    throw IoError(source + ": not well-formed XML: a NUL byte at offset " + std::to_string(nul));
  }
  const std::string padded = text + std::string(4, '\0');
  TiXmlDocument doc;
  doc.Parse(padded.c_str());
  if (doc.Error()) {
    throw IoError(source + ": not well-formed XML at row " + std::to_string(doc.ErrorRow()) +
                  ", column " + std::to_string(doc.ErrorCol()) + ": " + doc.ErrorDesc());
  }
  const TiXmlElement* root = doc.RootElement();
  if (root == nullptr || root->ValueStr() != "robot") {
    throw InvalidInput(source + ": SRDF root element is not <robot>");
  }
  std::vector<DisabledCollisionPair> pairs;
  for (const TiXmlElement* e = root->FirstChildElement("disable_collisions"); e != nullptr;
       e = e->NextSiblingElement("disable_collisions")) {
    const char* link1 = e->Attribute("link1");
    const char* link2 = e->Attribute("link2");
    if (link1 == nullptr || link2 == nullptr) {
      throw InvalidInput(source + ": <disable_collisions> at row " + std::to_string(e->Row()) +
                         " lacks link1 or link2");
    }
    const char* reason = e->Attribute("reason");
    pairs.push_back({link1, link2, reason != nullptr ? reason : ""});
  }
  return pairs;
}

}  // namespace skelcd::skinning
