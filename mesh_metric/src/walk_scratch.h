// Per-thread scratch space for the vertex walks (a stack and an O(1)-reset visited set). Internal.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace qm3d::mesh::detail {

/// A stack and a visited stamp per vertex; start() begins a new walk without clearing.
struct WalkScratch {
  std::vector<std::uint32_t> stack;
  std::vector<std::uint32_t> stamp;
  std::uint32_t current = 0;

  void start(std::size_t num_vertices) {
    if (stamp.size() != num_vertices) stamp.assign(num_vertices, 0);
    if (++current == 0) {  // wrapped: reset
      std::fill(stamp.begin(), stamp.end(), 0);
      current = 1;
    }
    stack.clear();
  }
  bool visit(std::uint32_t v) {
    if (stamp[v] == current) return false;
    stamp[v] = current;
    return true;
  }
};

}  // namespace qm3d::mesh::detail
