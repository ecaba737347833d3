#include "tests/ccd/cloth_funnel.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tests/support/test_support.hpp"

namespace skelcd::ccd::test {
namespace {

RationalPoint point(const std::array<mpq_class, 24>& c, std::size_t i) { return {c[3 * i], c[3 * i + 1], c[3 * i + 2]}; }

Eigen::Vector3d dpoint(const std::array<mpq_class, 24>& c, std::size_t i) {
  return {round_to_nearest(c[3 * i]), round_to_nearest(c[3 * i + 1]), round_to_nearest(c[3 * i + 2])};
}

}  // namespace

RationalVertexFaceQuery ClothFunnelQuery::rational_vf() const {
  return {point(exact, 0), point(exact, 1), point(exact, 2), point(exact, 3),
          point(exact, 4), point(exact, 5), point(exact, 6), point(exact, 7)};
}

RationalEdgeEdgeQuery ClothFunnelQuery::rational_ee() const {
  return {point(exact, 0), point(exact, 1), point(exact, 2), point(exact, 3),
          point(exact, 4), point(exact, 5), point(exact, 6), point(exact, 7)};
}

VertexFaceQuery ClothFunnelQuery::vf() const {
  return {dpoint(exact, 0), dpoint(exact, 1), dpoint(exact, 2), dpoint(exact, 3),
          dpoint(exact, 4), dpoint(exact, 5), dpoint(exact, 6), dpoint(exact, 7)};
}

EdgeEdgeQuery ClothFunnelQuery::ee() const {
  return {dpoint(exact, 0), dpoint(exact, 1), dpoint(exact, 2), dpoint(exact, 3),
          dpoint(exact, 4), dpoint(exact, 5), dpoint(exact, 6), dpoint(exact, 7)};
}

std::vector<ClothFunnelQuery> load_cloth_funnel(const std::string& kind) {
  const auto csv_path = skelcd::test::asset("cloth-funnel/queries/227" + kind + ".csv");
  const auto json_path = skelcd::test::asset("cloth-funnel/mma_bool/227" + kind + "_mma_bool.json");
  std::ifstream csv(csv_path);
  std::ifstream json(json_path);
  if (!csv || !json) throw std::runtime_error("cloth-funnel: cannot open " + csv_path.string());
  // Truth: a JSON array of true/false.
  std::stringstream js;
  js << json.rdbuf();
  std::vector<bool> truth;
  const std::string text = js.str();
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 4, "true") == 0) truth.push_back(true);
    if (text.compare(i, 5, "false") == 0) truth.push_back(false);
  }
  std::vector<ClothFunnelQuery> out;
  std::string line;
  int row = 0;
  ClothFunnelQuery q;
  q.vertex_face = kind == "vf";
  while (std::getline(csv, line)) {
    if (line.empty()) continue;
    std::stringstream ls(line);
    std::string field;
    std::array<std::string, 6> f;
    for (auto& x : f) {
      if (!std::getline(ls, x, ',')) throw std::runtime_error(csv_path.string() + ": short row " + std::to_string(row + 1));
    }
    for (std::size_t k = 0; k < 3; ++k) {
      mpq_class v(mpz_class(f[2 * k]), mpz_class(f[2 * k + 1]));
      v.canonicalize();
      q.exact[static_cast<std::size_t>(3 * (row % 8)) + k] = v;
    }
    if (++row % 8 == 0) out.push_back(q);
  }
  if (row % 8 != 0 || out.size() != truth.size()) {
    throw std::runtime_error(csv_path.string() + ": " + std::to_string(row) + " rows for " +
                             std::to_string(truth.size()) + " truth values");
  }
  for (std::size_t i = 0; i < out.size(); ++i) out[i].truth = truth[i];
  return out;
}

std::string to_query_file(const std::vector<ClothFunnelQuery>& queries) {
  std::ostringstream os;
  os << "# cloth-funnel step 227 -> 228 (assets/cloth-funnel), converted from the CSV + JSON ground truth\n";
  for (const auto& q : queries) {
    os << (q.vertex_face ? "vf" : "ee");
    for (const auto& c : q.exact) os << ' ' << c.get_str();
    os << ' ' << (q.truth ? 1 : 0) << '\n';
  }
  return os.str();
}

}  // namespace skelcd::ccd::test
