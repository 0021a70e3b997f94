#include "aia/scenario/config.h"

#include <string>

namespace aia {

bool DynamicsConfig::IsStatic() const {
  // Exact comparisons on purpose: these are values from the file, and a
  // target with A = I + 1e-12 does move, however slowly.
  return A == Eigen::MatrixXd::Identity(A.rows(), A.cols()) && b.isZero(0.0) &&
         q == 0.0;
}

int Scenario::LineOf(const std::string& key) const {
  std::string k = key;
  while (!k.empty()) {
    const auto it = lines.find(k);
    if (it != lines.end()) return it->second;
    // Up one level: "a.b[2]" -> "a.b", "a[1].c" -> "a[1]".
    const std::string::size_type cut = k.find_last_of(".[");
    if (cut == std::string::npos) break;
    k.resize(cut);
  }
  return 0;
}

}  // namespace aia
