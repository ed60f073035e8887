#include "reduce.hpp"

namespace handshare::fem::detail {

DofMap MakeDofMap(const TetMesh& mesh, std::span<const std::int32_t> held) {
  const std::int64_t ndof = 3 * static_cast<std::int64_t>(mesh.num_nodes());
  std::vector<bool> constrained(static_cast<std::size_t>(mesh.num_nodes()), false);
  for (std::int32_t v : held) constrained[v] = true;
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    if (!mesh.used_nodes()[v]) constrained[v] = true;
  }
  DofMap m;
  m.free_of_dof.assign(static_cast<std::size_t>(ndof), -1);
  for (std::int64_t d = 0; d < ndof; ++d) {
    if (!constrained[d / 3]) {
      m.free_of_dof[d] = static_cast<std::int64_t>(m.free_dofs.size());
      m.free_dofs.push_back(d);
    }
  }
  return m;
}

Eigen::SparseMatrix<double> FreeBlock(const Eigen::SparseMatrix<double>& K, const DofMap& map) {
  const auto nf = static_cast<Eigen::Index>(map.free_dofs.size());
  Eigen::SparseMatrix<double> Kff(nf, nf);
  std::int64_t nnz = 0;
  for (std::int64_t d : map.free_dofs) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, d); it; ++it) {
      if (map.free_of_dof[it.row()] >= 0) ++nnz;
    }
  }
  Kff.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = Kff.outerIndexPtr();
  int* inner = Kff.innerIndexPtr();
  double* val = Kff.valuePtr();
  std::int64_t pos = 0;
  for (Eigen::Index c = 0; c < nf; ++c) {
    outer[c] = static_cast<int>(pos);
    // Rows keep their order: the free numbering is monotone in the global one.
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, map.free_dofs[c]); it; ++it) {
      const std::int64_t r = map.free_of_dof[it.row()];
      if (r >= 0) {
        inner[pos] = static_cast<int>(r);
        val[pos] = it.value();
        ++pos;
      }
    }
  }
  outer[nf] = static_cast<int>(pos);
  return Kff;
}

}  // namespace handshare::fem::detail
