// A median-split bounding-volume hierarchy over boxes (HDoV thesis §5.5.1 occluder selection,
// vLOD §5.2.2 front-to-back rendering; see box_tree.hpp).
#include "precompute/box_tree.hpp"

#include <algorithm>
#include <numeric>

namespace cellwalk::visibility {
namespace {

constexpr uint32_t kLeafItems = 4;
constexpr int kMaxDepth = 60;  // the walk's stack holds 64; median splits stay far below

}  // namespace

BoxTree::BoxTree(const std::vector<Aabb>& boxes) {
  if (boxes.empty()) return;
  items_.resize(boxes.size());
  std::iota(items_.begin(), items_.end(), 0u);
  nodes_.emplace_back();
  build(0, 0, uint32_t(items_.size()), boxes, 0);
}

void BoxTree::build(uint32_t node, uint32_t begin, uint32_t end, const std::vector<Aabb>& boxes, int depth) {
  Aabb bounds, centres;
  for (uint32_t i = begin; i < end; ++i) {
    bounds.extend(boxes[items_[i]]);
    centres.extend(boxes[items_[i]].center());
  }
  nodes_[node].box = bounds;
  if (end - begin <= kLeafItems || depth >= kMaxDepth) {
    nodes_[node].first = begin, nodes_[node].count = end - begin;
    return;
  }
  const Vec3 extent = centres.size();
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                   [&](uint32_t a, uint32_t b) { return boxes[a].center()[axis] < boxes[b].center()[axis]; });
  const uint32_t child = uint32_t(nodes_.size());
  nodes_[node].first = child, nodes_[node].count = 0;
  nodes_.emplace_back();
  nodes_.emplace_back();
  build(child, begin, mid, boxes, depth + 1);
  build(child + 1, mid, end, boxes, depth + 1);
}

std::vector<uint32_t> BoxTree::number_in_leaf_order() {
  std::vector<uint32_t> old = std::move(items_);
  items_.resize(old.size());
  std::iota(items_.begin(), items_.end(), 0u);
  return old;
}

float BoxTree::gap(const Aabb& a, const Aabb& b) {
  const Vec3 g = glm::max(glm::max(a.min - b.max, b.min - a.max), Vec3(0.0f));
  return glm::dot(g, g);
}

}  // namespace cellwalk::visibility
