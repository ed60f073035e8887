#pragma once
// Shared by the fem benchmark programs: relative error of a list of vectors against a reference,
// ||a - b|| / ||b|| over all entries.

#include <cmath>
#include <vector>

#include <Eigen/Core>

namespace handshare::fem::bench {

inline double RelError(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - b[i]).squaredNorm();
    den += b[i].squaredNorm();
  }
  return std::sqrt(num / den);
}

}  // namespace handshare::fem::bench
