// The tree of boxes behind grid, octree and k-d view-cell partitions: point location and face
// neighbours across levels, and the "cells" section (docs/format.md, "Visibility sections").
// HDoV thesis §5.2; vLOD §2.1, §2.3 (Δs between face-adjacent cells of different sizes).
#include "visibility/cell_tree.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "cellwalk/core/error.hpp"
#include "core/bytes.hpp"

namespace cellwalk::visibility {

namespace {

constexpr uint32_t kNoCell = 0xFFFFFFFFu;
constexpr uint32_t kCellsVersion = 1;

struct FlatNode {
  Aabb box;
  uint32_t first_child = 0;
  uint32_t child_count = 0;
  CellId cell = kNoCell;
  uint32_t depth = 0;
  bool solid = false;
  bool skipped = false;
};

// The node flags of the "cells" section (docs/format.md).
constexpr uint32_t kSolidFlag = 1, kSkippedFlag = 2;

// Boundary points belong to the child with the larger coordinate, except on the parent's own
// upper faces, which close the box.
bool child_contains(const Aabb& child, const Aabb& parent, const Vec3& p) {
  for (int a = 0; a < 3; ++a) {
    if (p[a] < child.min[a]) return false;
    if (p[a] >= child.max[a] && child.max[a] != parent.max[a]) return false;
    if (p[a] > child.max[a]) return false;
  }
  return true;
}

// Whether two boxes overlap with positive extent on both axes other than `axis`.
bool overlaps_across(const Aabb& a, const Aabb& b, int axis) {
  for (int t = 0; t < 3; ++t) {
    if (t == axis) continue;
    if (!(a.min[t] < b.max[t] && b.min[t] < a.max[t])) return false;
  }
  return true;
}

class CellTree : public ViewCellPartition {
 public:
  CellTree(std::string kind, RootGrid grid, std::vector<FlatNode> nodes)
      : kind_(std::move(kind)), grid_(grid), nodes_(std::move(nodes)) {
    for (uint32_t n = 0; n < nodes_.size(); ++n) {
      if (nodes_[n].cell == kNoCell) continue;
      if (nodes_[n].cell >= cells_.size()) cells_.resize(nodes_[n].cell + 1);
      cells_[nodes_[n].cell] = ViewCell{nodes_[n].cell, nodes_[n].box, nodes_[n].depth, nodes_[n].solid, nodes_[n].skipped};
    }
  }

  std::string kind() const override { return kind_; }
  size_t cell_count() const override { return cells_.size(); }
  const ViewCell& cell(CellId id) const override { return cells_.at(id); }

  std::optional<CellId> locate(const Vec3& p) const override {
    if (!grid_.bounds.contains(p)) return std::nullopt;
    glm::ivec3 r;
    for (int a = 0; a < 3; ++a) r[a] = root_index(a, p[a]);
    uint32_t n = uint32_t((r.z * grid_.dims.y + r.y) * grid_.dims.x + r.x);
    while (nodes_[n].child_count > 0) {
      const FlatNode& parent = nodes_[n];
      uint32_t next = kNoCell;
      for (uint32_t c = parent.first_child; c < parent.first_child + parent.child_count; ++c)
        if (child_contains(nodes_[c].box, parent.box, p)) next = c;
      if (next == kNoCell) return std::nullopt;  // unreachable for children that tile the parent
      n = next;
    }
    return nodes_[n].cell;
  }

  std::vector<CellId> face_neighbours(CellId id) const override {
    const Aabb& box = cells_.at(id).box;
    std::vector<CellId> out;
    const size_t roots = size_t(grid_.dims.x) * grid_.dims.y * grid_.dims.z;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side)
        for (uint32_t r = 0; r < roots; ++r) collect_face(r, box, axis, side, out);
    return out;
  }

  const RootGrid& grid() const { return grid_; }

  // The root row holding coordinate v on axis a; the division may round across a root's
  // face, so the neighbouring row is checked against the rows' exact bounds.
  int root_index(int a, float v) const {
    int i = std::clamp(int(std::floor((v - grid_.bounds.min[a]) / grid_.step[a])), 0, grid_.dims[a] - 1);
    glm::ivec3 at{0};
    at[a] = i;
    const Aabb box = grid_.root_box(at.x, at.y, at.z);
    if (v < box.min[a] && i > 0) --i;
    else if (v >= box.max[a] && i + 1 < grid_.dims[a]) ++i;
    return i;
  }
  const std::vector<FlatNode>& nodes() const { return nodes_; }

 private:
  // Leaves under node n whose face touches `box`'s face (axis, side) with positive area.
  void collect_face(uint32_t n, const Aabb& box, int axis, int side, std::vector<CellId>& out) const {
    const FlatNode& node = nodes_[n];
    const float plane = side == 0 ? box.min[axis] : box.max[axis];
    if (node.box.min[axis] > plane || node.box.max[axis] < plane) return;
    if (!overlaps_across(node.box, box, axis)) return;
    if (node.child_count == 0) {
      const float touching = side == 0 ? node.box.max[axis] : node.box.min[axis];
      if (touching == plane) out.push_back(node.cell);
      return;
    }
    for (uint32_t c = node.first_child; c < node.first_child + node.child_count; ++c)
      collect_face(c, box, axis, side, out);
  }

  std::string kind_;
  RootGrid grid_;
  std::vector<FlatNode> nodes_;
  std::vector<ViewCell> cells_;
};

// Appends the subtree's children after their parent, contiguously (breadth-first per node).
void flatten(BoxNode& node, uint32_t index, std::vector<FlatNode>& nodes) {
  if (node.children.empty()) return;
  nodes[index].first_child = uint32_t(nodes.size());
  nodes[index].child_count = uint32_t(node.children.size());
  for (BoxNode& c : node.children) nodes.push_back(FlatNode{c.box, 0, 0, kNoCell, c.depth, c.solid});
  for (size_t i = 0; i < node.children.size(); ++i)
    flatten(node.children[i], nodes[index].first_child + uint32_t(i), nodes);
}

void number_leaves(std::vector<FlatNode>& nodes, uint32_t n, CellId& next) {
  if (nodes[n].child_count == 0) {
    nodes[n].cell = next++;
    return;
  }
  for (uint32_t c = nodes[n].first_child; c < nodes[n].first_child + nodes[n].child_count; ++c)
    number_leaves(nodes, c, next);
}

}  // namespace

Aabb RootGrid::root_box(int i, int j, int k) const {
  Aabb b;
  const glm::ivec3 at{i, j, k};
  for (int a = 0; a < 3; ++a) {
    b.min[a] = bounds.min[a] + float(at[a]) * step[a];
    b.max[a] = at[a] + 1 == dims[a] ? bounds.max[a] : bounds.min[a] + float(at[a] + 1) * step[a];
  }
  return b;
}

namespace {
// "0.001", "192.6": a size in a message, not "0.001000".
std::string short_number(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", double(v));
  return text;
}
}  // namespace

RootGrid root_grid(const CellRegion& region, float size) {
  if (!(size > 0.0f) || !std::isfinite(size)) fail("view cells", "the cell size must be a finite positive number of metres");
  RootGrid g;
  double total = 1.0;  // cells so far, in double so a tiny size cannot overflow the count
  g.bounds = region.bounds;
  if (region.two_d) {
    g.bounds.min.y = region.eye_min;
    g.bounds.max.y = region.eye_max;
  }
  for (int a = 0; a < 3; ++a) {
    const float extent = std::max(g.bounds.max[a] - g.bounds.min[a], 0.0f);
    const bool whole = region.two_d && a == 1;
    const double cells = whole ? 1.0 : std::max(1.0, double(std::ceil(extent / size - 1e-4f)));
    total *= cells;
    if (total > double(kMaxGridCells))
      fail("view cells", "cells of " + short_number(size) + " m over a region of " + short_number(region.bounds.size().x) +
                             " x " + short_number(region.bounds.size().z) + " m make more than " +
                             std::to_string(kMaxGridCells) + " cells; use larger cells");
    g.dims[a] = int(cells);
    g.step[a] = whole ? std::max(extent, 1e-6f) : size;
  }
  return g;
}

std::vector<Aabb> split_box(const Aabb& box, bool x, bool y, bool z, const Vec3& at) {
  std::vector<Aabb> out;
  const bool split[3] = {x, y, z};
  for (int k = 0; k < (split[2] ? 2 : 1); ++k)
    for (int j = 0; j < (split[1] ? 2 : 1); ++j)
      for (int i = 0; i < (split[0] ? 2 : 1); ++i) {
        const int half[3] = {i, j, k};
        Aabb c = box;
        for (int a = 0; a < 3; ++a) {
          if (!split[a]) continue;
          if (half[a] == 0) c.max[a] = at[a];
          else c.min[a] = at[a];
        }
        out.push_back(c);
      }
  return out;
}

std::unique_ptr<ViewCellPartition> make_cell_tree(std::string kind, const RootGrid& grid,
                                                  std::vector<BoxNode> roots) {
  std::vector<FlatNode> nodes;
  for (const BoxNode& r : roots) nodes.push_back(FlatNode{r.box, 0, 0, kNoCell, r.depth, r.solid});
  for (size_t i = 0; i < roots.size(); ++i) flatten(roots[i], uint32_t(i), nodes);
  CellId next = 0;
  for (uint32_t r = 0; r < roots.size(); ++r) number_leaves(nodes, r, next);
  return std::make_unique<CellTree>(std::move(kind), grid, std::move(nodes));
}

}  // namespace cellwalk::visibility

namespace cellwalk {

using visibility::CellTree;
using visibility::FlatNode;

std::unique_ptr<ViewCellPartition> skip_cells(const ViewCellPartition& partition,
                                              const std::function<bool(const ViewCell&)>& keep) {
  const auto* tree = dynamic_cast<const CellTree*>(&partition);
  if (!tree) fail("view cells", "only cellwalk's own partitions can skip cells");
  std::vector<FlatNode> nodes = tree->nodes();
  for (FlatNode& n : nodes)
    if (n.cell != visibility::kNoCell && !n.solid) n.skipped = !keep(partition.cell(n.cell));
  return std::make_unique<CellTree>(tree->kind(), tree->grid(), std::move(nodes));
}

void fail_in_skipped_cell(const std::string& system, const ViewCell& cell, const Vec3& p) {
  char where[96];
  std::snprintf(where, sizeof where, "the camera at (%.1f, %.1f, %.1f)", p.x, p.y, p.z);
  fail(system, std::string(where) + " is in view cell " + std::to_string(cell.id) +
                   ", which `cellwalk pvs --along` left out; rerun pvs with the path it walks, a larger " +
                   "--along-margin, or without --along");
}

std::vector<uint8_t> serialize_partition(const ViewCellPartition& partition) {
  const auto* tree = dynamic_cast<const CellTree*>(&partition);
  if (!tree) fail("view cells", "only cellwalk's own partitions can be stored");
  ByteWriter w;
  w.put(visibility::kCellsVersion);
  w.put_string(tree->kind());
  const visibility::RootGrid& g = tree->grid();
  w.put(g.bounds);
  w.put(g.dims);
  w.put(g.step);
  w.put(uint32_t(tree->nodes().size()));
  w.put(uint32_t(tree->cell_count()));
  for (const FlatNode& n : tree->nodes()) {
    w.put(n.box);
    w.put(n.first_child);
    w.put(n.child_count);
    w.put(n.cell);
    w.put(n.depth);
    w.put((n.solid ? visibility::kSolidFlag : 0) | (n.skipped ? visibility::kSkippedFlag : 0));
  }
  return std::move(w.bytes());
}

std::unique_ptr<ViewCellPartition> deserialize_partition(std::span<const uint8_t> bytes,
                                                         const std::string& where) {
  ByteReader r(bytes, where);
  if (r.get<uint32_t>("version") != visibility::kCellsVersion) r.error("unknown cells version");
  std::string kind = r.get_string("kind");
  if (kind != "grid" && kind != "octree" && kind != "kd") r.error("unknown partition kind '" + kind + "'");
  visibility::RootGrid g;
  g.bounds = r.get<Aabb>("bounds");
  g.dims = r.get<glm::ivec3>("root dims");
  g.step = r.get<Vec3>("root step");
  const uint32_t node_count = r.get<uint32_t>("node count");
  const uint32_t cell_count = r.get<uint32_t>("cell count");
  const uint64_t roots = uint64_t(std::max(g.dims.x, 0)) * std::max(g.dims.y, 0) * std::max(g.dims.z, 0);
  if (roots == 0 || roots > node_count) r.error("root grid does not match the node count");
  if (node_count > r.remaining() / 44) r.error("truncated: node table");
  for (int a = 0; a < 3; ++a)
    if (!(g.step[a] > 0.0f) || g.bounds.empty()) r.error("bad root grid");
  std::vector<FlatNode> nodes(node_count);
  std::vector<bool> seen(cell_count, false);
  for (uint32_t i = 0; i < node_count; ++i) {
    FlatNode& n = nodes[i];
    n.box = r.get<Aabb>("node box");
    n.first_child = r.get<uint32_t>("first child");
    n.child_count = r.get<uint32_t>("child count");
    n.cell = r.get<uint32_t>("cell");
    n.depth = r.get<uint32_t>("depth");
    const uint32_t flags = r.get<uint32_t>("flags");
    if (flags & ~(visibility::kSolidFlag | visibility::kSkippedFlag)) r.error("node " + std::to_string(i) + " has unknown flags " + std::to_string(flags));
    n.solid = flags & visibility::kSolidFlag;
    n.skipped = flags & visibility::kSkippedFlag;
    // Children after their parent keeps descent finite; leaves own exactly one cell.
    if (n.child_count > 8 || (n.child_count > 0 && (n.first_child <= i || uint64_t(n.first_child) + n.child_count > node_count)))
      r.error("node " + std::to_string(i) + " has bad children");
    if ((n.child_count == 0) != (n.cell != visibility::kNoCell)) r.error("node " + std::to_string(i) + " leaf/cell mismatch");
    if (n.cell != visibility::kNoCell) {
      if (n.cell >= cell_count || seen[n.cell]) r.error("node " + std::to_string(i) + " has a bad cell id");
      seen[n.cell] = true;
    }
  }
  for (bool s : seen)
    if (!s) r.error("cell ids are not dense");
  return std::make_unique<CellTree>(std::move(kind), g, std::move(nodes));
}

}  // namespace cellwalk
