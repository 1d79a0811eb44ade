// A bounding-volume hierarchy over a fixed set of boxes, walked front to back from a region
// with whole subtrees culled, and along segments.
// Seed: 000 HDoV thesis §5.5.1 (occluders are selected per cell, near and large first; here a
// hierarchy does the selecting, so a cell touches only the occluders that can still matter)
// and 001 vLOD §5.2.2 (occluders rendered front to back into the depth buffer). A median-split
// tree: built once per engine, read by any number of threads.
#pragma once

#include <cstdint>
#include <vector>

#include "cellwalk/core/geometry.hpp"

namespace cellwalk::visibility {

class BoxTree {
 public:
  // The tree over `boxes` (items are their indices). REQUIRES: no box empty.
  explicit BoxTree(const std::vector<Aabb>& boxes);

  // Visits items front to back from `region` (at each node the child nearer to the region
  // first): `enter(node_box)` false skips a subtree, `item(index)` is called for each item
  // of a subtree entered. Items of one leaf come in their stored order.
  template <class Enter, class Item>
  void front_to_back(const Aabb& region, Enter&& enter, Item&& item) const {
    walk([&](const Aabb& a, const Aabb& b) { return gap(region, a) <= gap(region, b); }, enter, item);
  }

  // The same without an order among children, for a walk whose answer does not depend on it.
  template <class Enter, class Item>
  void depth_first(Enter&& enter, Item&& item) const {
    walk([](const Aabb&, const Aabb&) { return true; }, enter, item);
  }

  // Renumbers the items by their place in the leaves, so that the items of a subtree are
  // numbered together and a walk reads the caller's data about them from one stretch of
  // memory. Returns, for each new number, the old one: the caller reorders its data by it.
  std::vector<uint32_t> number_in_leaf_order();

  // Squared distance between two boxes (0 when they overlap).
  static float gap(const Aabb& a, const Aabb& b);

 private:
  struct Node {
    Aabb box;
    uint32_t first = 0;  // leaf: first of items_; internal: index of the first child
    uint32_t count = 0;  // leaf: number of items (> 0); internal: 0
  };
  std::vector<Node> nodes_;
  std::vector<uint32_t> items_;

  // Depth first; `first(a, b)` says whether the child with box a goes before the one with b.
  template <class First, class Enter, class Item>
  void walk(First&& first, Enter& enter, Item& item) const {
    if (nodes_.empty()) return;
    uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!enter(n.box)) continue;
      if (n.count > 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i) item(items_[i]);
        continue;
      }
      const uint32_t a = n.first, b = n.first + 1;  // children are adjacent
      const bool a_first = first(nodes_[a].box, nodes_[b].box);
      stack[top++] = a_first ? b : a;  // pushed first, visited second
      stack[top++] = a_first ? a : b;
    }
  }

  void build(uint32_t node, uint32_t begin, uint32_t end, const std::vector<Aabb>& boxes, int depth);
};

}  // namespace cellwalk::visibility
