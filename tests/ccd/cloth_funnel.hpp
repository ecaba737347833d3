#pragma once
// The ground-truthed cloth-funnel CCD queries (assets/cloth-funnel/, step 227 -> 228): CSV rows
// x_num,x_den,y_num,y_den,z_num,z_den (8 rows per query) and the truth per query in JSON. Read
// exactly; converted to the `skelcd ccd-queries` file format (docs/ccd-queries.md).

#include <array>
#include <string>
#include <vector>

#include <gmpxx.h>

#include "ccd/edge_edge.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd::test {

struct ClothFunnelQuery {
  bool vertex_face = true;
  std::array<mpq_class, 24> exact;  ///< 8 points x, y, z in the file order
  bool truth = false;               ///< the dataset's ground truth (touching counts)

  [[nodiscard]] RationalVertexFaceQuery rational_vf() const;
  [[nodiscard]] RationalEdgeEdgeQuery rational_ee() const;
  /// The doubles nearest to the exact values (these queries' values are all doubles).
  [[nodiscard]] VertexFaceQuery vf() const;
  [[nodiscard]] EdgeEdgeQuery ee() const;
};

/// Loads "vf" or "ee" queries from assets/cloth-funnel/. Throws std::runtime_error on a missing or
/// malformed file.
[[nodiscard]] std::vector<ClothFunnelQuery> load_cloth_funnel(const std::string& kind);

/// The queries as lines of a `skelcd ccd-queries` file: "vf p/q ... 0|1".
[[nodiscard]] std::string to_query_file(const std::vector<ClothFunnelQuery>& queries);

}  // namespace skelcd::ccd::test
