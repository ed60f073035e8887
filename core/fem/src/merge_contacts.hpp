#pragma once
// Internal: merging repeated touches of one node, shared by the two real-time solvers
// (ContactSolver and ElementaryDisplacementSolver). No allocation, no exceptions.

#include <cstdint>

#include <Eigen/Core>

namespace handshare::fem::detail {

// Adds one touch of compliance slot `slot` with imposed displacement u_m to the distinct
// touched nodes: slots[0..count), their touch counts and the sums of their imposed
// displacements. A new node is appended (count grows; the arrays must have room). Returns the
// node's index; multiplicity[j] == 1 tells the caller it is new. The caller averages d_m by
// multiplicity once every touch is in. Without index_of_slot a linear scan (a few tens of
// touches); with it (one entry per compliance slot, -1 where the slot is not among slots[0..count))
// a lookup, which the caller keeps: it must reset the entries of slots[0..count) to -1 when done.
inline std::int32_t MergeTouch(std::int32_t slot, const Eigen::Vector3d& u_m, std::int32_t* slots,
                               std::int32_t* multiplicity, Eigen::Vector3d* d_m,
                               std::int32_t& count, std::int32_t* index_of_slot = nullptr) noexcept {
  std::int32_t j = 0;
  if (index_of_slot != nullptr) {
    j = index_of_slot[slot] >= 0 ? index_of_slot[slot] : count;
  } else {
    while (j < count && slots[j] != slot) ++j;
  }
  if (j == count) {
    if (index_of_slot != nullptr) index_of_slot[slot] = j;
    slots[j] = slot;
    multiplicity[j] = 0;
    d_m[j].setZero();
    ++count;
  }
  ++multiplicity[j];
  d_m[j] += u_m;
  return j;
}

}  // namespace handshare::fem::detail
