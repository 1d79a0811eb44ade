// The conservative from-region visibility engine.
// Seeds: 001 vLOD §5.2 (occluder shrinking: occluders eroded by the cell and rendered from one
// point of it hide, with fusion, only what is hidden from the whole cell; §5.2.2 conservative
// rasterisation) and 000 HDoV thesis §5.5.1 (occluders selected near the cell; a convex
// occluder hiding an object from the 8 cell vertices hides it from the cell). The guarantee
// and its proof: docs/conservative-visibility.md.
#include "cellwalk/precompute/conservative_visibility.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>

#include "precompute/box_tree.hpp"
#include "precompute/depth_buffer.hpp"
#include "precompute/occluders.hpp"
#include "precompute/surface_occluders.hpp"
#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

using visibility::CubeDepthBuffer;

// How far a grounded occluder reaches below the floor (any depth beyond the world works).
constexpr float kBelowFloor = 1.0e5f;

// The object and component of occluders that have none.
constexpr ObjectId kNoObject = std::numeric_limits<ObjectId>::max();
constexpr uint32_t kNoComponent = std::numeric_limits<uint32_t>::max();

// A box inside the solid of `object`, or inside the union of the solids of `object` and
// `other` (a bridge between two boxes that touch), or (object = other = kNoObject) inside the
// free voxels of `component` of the surface source. `grounded` is the box reaching down
// without end when it stands on the floor (below which there is no geometry), else the box.
// The objects' bounds are kept beside it: every cell reads them for each occluder it meets.
struct Occluder {
  Aabb box;
  Aabb grounded;
  ObjectId object;
  ObjectId other;
  Aabb object_bounds;
  Aabb other_bounds;
  uint32_t component = kNoComponent;
};

// A segment between two points at or above the floor never passes below it, so a box whose
// bottom is at or below the floor hides from such viewpoints exactly what the box reaching
// down to -infinity hides; the deeper box survives shrinking by the cell's height.
Aabb reaching_down(const Aabb& box, const Aabb& raw, float floor) {
  if (raw.min.y > floor) return box;
  Aabb out = box;
  out.min.y = floor - kBelowFloor;
  return out;
}

// Splits along every axis at least half as long as the longest: a flat 2D cell in x and z,
// a cube in all three.
std::vector<Aabb> children_of(const Aabb& box) {
  const Vec3 size = box.size();
  const float longest = std::max({size.x, size.y, size.z});
  std::vector<Aabb> out{box};
  for (int axis = 0; axis < 3; ++axis) {
    if (size[axis] < 0.5f * longest) continue;
    std::vector<Aabb> split;
    for (const Aabb& b : out) {
      const float mid = 0.5f * (b.min[axis] + b.max[axis]);
      Aabb lower = b, upper = b;
      lower.max[axis] = mid;
      upper.min[axis] = mid;
      split.push_back(lower);
      split.push_back(upper);
    }
    out.swap(split);
  }
  return out;
}

// The geometry drawn is the decoded one: positions within half a quantisation step of the
// box the directory records, plus float rounding. Grow the box by a full step and more.
Aabb occludee_box(const Aabb& bounds) {
  const Vec3 magnitude = glm::max(glm::abs(bounds.min), glm::abs(bounds.max));
  const Vec3 grow = bounds.size() / 65535.0f + magnitude * 1e-6f + Vec3(1e-5f);
  return {bounds.min - grow, bounds.max + grow};
}

double distance_between(const Aabb& a, const Aabb& b) {
  const Vec3 gap = glm::max(glm::max(a.min - b.max, b.min - a.max), Vec3(0.0f));
  return glm::length(gap);
}

// Occluder faces may lie exactly on the surface; pulling them in by this keeps float
// rounding in the slab tests from letting a ray that grazes past count as a hit.
Aabb pulled_in(const Aabb& box) {
  const Vec3 magnitude = glm::max(glm::abs(box.min), glm::abs(box.max));
  const Vec3 eps = magnitude * 1e-6f + Vec3(1e-6f);
  return {box.min + eps, box.max - eps};
}

// vLOD §5.2 for a box cell rendered from its centre: the occluder eroded by the cell's
// half-extent (the set s with s + (cell − centre) inside the occluder). Empty when the
// occluder is not larger than the cell along some axis.
Aabb shrunk(const Aabb& occluder, const Aabb& cell) {
  const Vec3 half = cell.size() * 0.5f;
  return {occluder.min + half, occluder.max - half};
}

// A box that cannot cover one whole pixel of the cube buffer needs no rendering: a pixel
// spans at least about (2 / resolution) / 3 radians (at the cube's corners).
bool too_small(const Aabb& box, const Vec3& eye, int resolution) {
  const double distance = distance_between(box, Aabb{eye, eye});
  return glm::length(box.size()) < distance * 0.6 / resolution;
}

// The box less `margin` on every side (empty when it is not wider than 2 · margin).
Aabb eroded(const Aabb& box, float margin) {
  return margin > 0.0f ? Aabb{box.min + Vec3(margin), box.max - Vec3(margin)} : box;
}

double volume(const Aabb& b) {
  const Vec3 s = glm::max(b.size(), Vec3(0.0f));
  return double(s.x) * s.y * s.z;
}

double largest_fill(const std::vector<Aabb>& boxes, const Aabb& bounds) {
  double largest = 0.0;
  for (const Aabb& b : boxes) largest = std::max(largest, volume(b));
  return volume(bounds) > 0.0 ? largest / volume(bounds) : 0.0;
}

class ConservativeEngineImpl final : public VisibilityEngine {
 public:
  ConservativeEngineImpl(const World& world, const ConservativeParams& params)
      : world_(world), params_(params) {
    const auto start = std::chrono::steady_clock::now();
    occludees_.reserve(world.object_count());
    Aabb everything;
    for (ObjectId id = 0; id < world.object_count(); ++id) {
      occludees_.push_back(occludee_box(world.object(id).bounds));
      everything.extend(occludees_.back());
    }
    if (params.smallest_hole > 0.0) {
      if (params.occluder_margin)
        fail("--smallest-hole", "surface occluders hold for level 0 only; use them with --engine conservative");
      voxels_ = std::make_unique<visibility::SurfaceVoxels>(
          everything, visibility::SurfaceOccluderParams{params.smallest_hole, params.smallest_occluder});
    }
    derive_occluders();
    std::vector<Aabb> bounds;
    bounds.reserve(occluders_.size());
    for (const Occluder& o : occluders_) bounds.push_back(o.grounded);  // holds o.box too
    tree_ = std::make_unique<visibility::BoxTree>(bounds);
    std::vector<Occluder> in_leaf_order;
    in_leaf_order.reserve(occluders_.size());
    for (uint32_t old : tree_->number_in_leaf_order()) in_leaf_order.push_back(occluders_[old]);
    occluders_.swap(in_leaf_order);
    stats_.objects = world.object_count();
    stats_.occluder_boxes = occluders_.size() - stats_.bridges;
    stats_.occluder_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::string name() const override { return "conservative"; }
  bool conservative() const override { return true; }
  const ConservativeStats& stats() const { return stats_; }

  // The objects visible from some sub-cell of a refinement of the cell (a box is the union
  // of its children, so hidden from the cell = hidden from every leaf it reaches).
  VisibleSet compute(const ViewCell& cell) const override {
    VisibleSet out;
    if (cell.solid) return out;
    Pass pass{cell.box, std::vector<uint8_t>(occludees_.size(), 0), {},
               std::vector<float>(params_.occluder_margin ? occludees_.size() : 0, -1.0f)};
    std::vector<ObjectId> candidates;
    for (ObjectId id = 0; id < occludees_.size(); ++id) {
      if (occludees_[id].overlaps(cell.box))
        pass.visible[id] = 1;  // around a viewpoint: nothing can hide it
      else
        candidates.push_back(id);
    }
    refine(cell.box, 0, std::move(candidates), pass);
    for (ObjectId id = 0; id < occludees_.size(); ++id)
      if (pass.visible[id]) out.objects.push_back(id);
    return out;
  }

 private:
  const World& world_;
  ConservativeParams params_;
  std::vector<Aabb> occludees_;    // per object, the drawn geometry's box
  std::vector<Occluder> occluders_;  // in the tree's leaf order
  std::unique_ptr<visibility::BoxTree> tree_;  // over occluders_' grounded boxes
  std::unique_ptr<visibility::SurfaceVoxels> voxels_;  // the surface source; null when off
  float floor_ = 0.0f;               // no decoded geometry lies below this height
  ConservativeStats stats_;

  // One depth buffer per refinement level, re-aimed for each box of the level: the walk is
  // depth first, so a level's buffer is done with before the next box of that level.
  using Buffers = std::vector<std::unique_ptr<CubeDepthBuffer>>;

  // One compute(): the cell, what is visible so far, the buffers, and each object's occluder
  // margin from the cell (-1 until asked for; empty without ConservativeParams::occluder_margin).
  struct Pass {
    Aabb cell;
    std::vector<uint8_t> visible;
    Buffers buffers;
    std::vector<float> margin;
  };

  float margin_of(ObjectId id, Pass& pass) const {
    if (pass.margin.empty() || id == kNoObject) return 0.0f;
    if (pass.margin[id] < 0.0f) pass.margin[id] = std::max(0.0f, params_.occluder_margin(pass.cell, id));
    return pass.margin[id];
  }

  // The occluder as the levels drawn from the cell hold it (ConservativeParams::occluder_margin).
  Aabb drawn(const Occluder& o, const Aabb& shape, Pass& pass) const {
    return eroded(shape, std::max(margin_of(o.object, pass), margin_of(o.other, pass)));
  }

  CubeDepthBuffer& buffer_for(Buffers& buffers, size_t level, const Vec3& eye) const {
    if (buffers.size() <= level) buffers.resize(level + 1);
    if (!buffers[level])
      buffers[level] = std::make_unique<CubeDepthBuffer>(eye, params_.face_resolution);
    else
      buffers[level]->aim(eye);
    return *buffers[level];
  }

  // A region of viewpoints and the components of the surface source they may lie in, whose
  // boxes are therefore no occluders for it.
  struct Region {
    Aabb box;
    std::vector<uint32_t> components;  // sorted
  };

  // Tests the candidates from `box`; those not hidden from it are visible when the box is a
  // leaf of the refinement, else they are tested from each child, minus those an earlier
  // child already showed to be visible.
  void refine(const Aabb& box, int level, std::vector<ObjectId> candidates, Pass& pass) const {
    std::erase_if(candidates, [&](ObjectId id) { return pass.visible[id] != 0; });
    if (candidates.empty()) return;
    const std::vector<uint32_t> near = voxels_ ? voxels_->components_near(box) : std::vector<uint32_t>{};
    if (near.size() <= 1) {
      candidates = not_hidden(Region{box, near}, level, std::move(candidates), pass);
    } else {
      // Each viewpoint of the box lies in one of the components near it, and from there every
      // other component's boxes are occluders: one pass per component, and an object is hidden
      // from the box only when every pass hides it. (One pass excluding them all would lose
      // every surface occluder for a box across a wall.)
      std::vector<uint8_t> shown(occludees_.size(), 0);
      for (uint32_t component : near)
        for (ObjectId id : not_hidden(Region{box, {component}}, level, candidates, pass)) shown[id] = 1;
      std::erase_if(candidates, [&](ObjectId id) { return !shown[id]; });
    }
    if (level >= params_.refine_levels) {
      for (ObjectId id : candidates) pass.visible[id] = 1;
      return;
    }
    for (const Aabb& child : children_of(box)) refine(child, level + 1, candidates, pass);
  }

  // The candidates not hidden from every viewpoint of the region.
  std::vector<ObjectId> not_hidden(const Region& region, int level, std::vector<ObjectId> candidates, Pass& pass) const {
    CubeDepthBuffer& depth = buffer_for(pass.buffers, size_t(level), region.box.center());
    for (ObjectId id : candidates) depth.demand(occludees_[id]);
    if (params_.occluder_shrinking) render_occluders(region, depth, pass);
    std::erase_if(candidates, [&](ObjectId id) { return hidden(id, region, depth, pass); });
    return candidates;
  }

  // Viewpoints must lie outside the occluder's solid (or free component) for its crossing
  // argument.
  bool usable(const Occluder& o, const Region& region) const {
    if (o.component != kNoComponent)
      return !std::binary_search(region.components.begin(), region.components.end(), o.component);
    return !o.object_bounds.overlaps(region.box) && !o.other_bounds.overlaps(region.box);
  }

  // Renders the shrunk occluders usable from `box` into the buffer, front to back. Groups of
  // occluders that can lower no wanted pixel (behind what is already rendered, or outside
  // every candidate's projection) are skipped whole: the buffer is the same as rendering all
  // (each pixel keeps the minimum), only cheaper.
  void render_occluders(const Region& region, CubeDepthBuffer& depth, Pass& pass) const {
    const Aabb& box = region.box;
    const bool above_floor = box.min.y >= floor_;
    tree_->front_to_back(
        box, [&](const Aabb& group) { return depth.may_lower(group); },
        [&](uint32_t i) {
          const Occluder& o = occluders_[i];
          const Aabb shape = drawn(o, above_floor ? o.grounded : o.box, pass);
          if (!shape.empty() && usable(o, region) && !too_small(shape, box.center(), params_.face_resolution) && depth.may_lower(shape))
            render_shrunk(shape, box, depth);
        });
  }

  // Two sound shrinkings, each better where the other is weak: the erosion by the whole cell
  // (seen from any direction), and the per-face lateral one (no loss along the view axis,
  // so thin and deep occluders survive, but a larger loss at oblique pixels).
  void render_shrunk(const Aabb& occluder, const Aabb& cell, CubeDepthBuffer& depth) const {
    const Aabb s = shrunk(occluder, cell);
    if (!s.empty()) depth.add_occluder(s);
    depth.add_occluder_for_cell(occluder, cell.size() * 0.5f);
  }

  bool hidden(ObjectId id, const Region& region, const CubeDepthBuffer& depth, Pass& pass) const {
    const Aabb& box = occludees_[id];
    if (params_.occluder_shrinking && depth.hidden(box)) return true;
    return params_.corner_test && corner_test_hides(id, region, pass);
  }

  // HDoV §5.5.1 with each usable occluder within corner_test_radius of the cell whose box the
  // centre-to-centre segment meets (a cheap necessary condition), found through the tree.
  bool corner_test_hides(ObjectId id, const Region& region, Pass& pass) const {
    const Aabb& cell = region.box;
    const Aabb& box = occludees_[id];
    const Vec3 eye = cell.center(), target = box.center();
    const visibility::SegmentFilter segment(eye, target);
    const float radius2 = float(params_.corner_test_radius * params_.corner_test_radius);
    bool found = false;
    tree_->depth_first(
        [&](const Aabb& group) {
          return !found && visibility::BoxTree::gap(group, cell) <= radius2 && segment.may_meet(group);
        },
        [&](uint32_t i) {
          const Occluder& o = occluders_[i];
          if (found || o.object == id || o.other == id || distance_between(o.box, cell) > params_.corner_test_radius ||
              !usable(o, region))
            return;
          const Aabb shape = drawn(o, o.box, pass);
          found = !shape.empty() && visibility::segment_meets_box(eye, target, shape) &&
                  visibility::occluder_hides(cell, shape, box);
        });
    return found;
  }

  // Decodes level 0 of every object, in parallel, and keeps its inscribed boxes.
  void derive_occluders() {
    const visibility::OccluderParams op{params_.occluder_grid, params_.max_boxes_per_object,
                                        params_.min_box_gain};
    const size_t count = world_.object_count();
    std::vector<visibility::InscribedBoxes> per_object(count);
    std::vector<float> lowest(count, std::numeric_limits<float>::max());
    std::atomic<size_t> next{0};
    std::mutex failure_mutex;
    std::exception_ptr failure;
    auto work = [&] {
      try {
        for (size_t id; (id = next++) < count;) {
          const std::vector<uint8_t> bytes = world_.read_level(ObjectId(id), 0);
          const Mesh mesh = world_.decode_level(ObjectId(id), 0, bytes);
          lowest[id] = bounds_of(mesh).min.y;
          per_object[id] = visibility::inscribed_boxes(mesh, op);
          if (voxels_) voxels_->add_mesh(mesh);
        }
      } catch (...) {
        std::lock_guard lock(failure_mutex);
        failure = std::current_exception();
        next = count;
      }
    };
    const unsigned threads =
        params_.threads > 0 ? unsigned(params_.threads) : std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(work);
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
    floor_ = count ? *std::min_element(lowest.begin(), lowest.end()) : 0.0f;
    for (size_t id = 0; id < count; ++id) {
      stats_.closed_objects += per_object[id].closed;
      stats_.occluder_objects += !per_object[id].boxes.empty();
      stats_.mean_fill += largest_fill(per_object[id].boxes, world_.object(ObjectId(id)).bounds) /
                          double(count);
      for (const Aabb& b : per_object[id].boxes)
        add_occluder(b, ObjectId(id), ObjectId(id));
    }
    add_bridges(per_object);
    if (voxels_) add_surface_occluders();
  }

  void add_surface_occluders() {
    voxels_->finish();
    for (const visibility::SurfaceOccluder& o : voxels_->occluders()) {
      add_occluder(o.box, kNoObject, kNoObject);
      occluders_.back().component = o.component;
    }
    const visibility::SurfaceVoxelStats& s = voxels_->stats();
    stats_.voxel_edge = s.voxel_edge;
    stats_.voxels = s.voxels;
    stats_.surface_voxels = s.surface_voxels;
    stats_.free_components = s.components;
    stats_.surface_boxes = s.boxes;
  }

  // One level of bridges between touching boxes (sweep along x over the boxes sorted by
  // their lower x): fusion across seams that erosion would open.
  void add_bridges(const std::vector<visibility::InscribedBoxes>& per_object) {
    struct Box {
      Aabb box;
      ObjectId object;
    };
    std::vector<Box> boxes;
    for (ObjectId id = 0; id < per_object.size(); ++id)
      for (const Aabb& b : per_object[id].boxes) boxes.push_back({b, id});
    std::sort(boxes.begin(), boxes.end(),
              [](const Box& a, const Box& b) { return a.box.min.x < b.box.min.x; });
    for (size_t i = 0; i < boxes.size(); ++i)
      for (size_t j = i + 1; j < boxes.size() && boxes[j].box.min.x <= boxes[i].box.max.x; ++j)
        for (const Aabb& bridge : visibility::bridge_boxes(boxes[i].box, boxes[j].box)) {
          add_occluder(bridge, boxes[i].object, boxes[j].object);
          ++stats_.bridges;
        }
  }

  void add_occluder(const Aabb& raw, ObjectId object, ObjectId other) {
    const Aabb box = pulled_in(raw);
    auto bounds = [&](ObjectId id) { return id == kNoObject ? Aabb{} : world_.object(id).bounds; };
    occluders_.push_back({box, params_.grounded_occluders ? reaching_down(box, raw, floor_) : box, object, other,
                          bounds(object), bounds(other)});
  }
};

}  // namespace

std::unique_ptr<VisibilityEngine> make_conservative_engine(const World& world,
                                                           const ConservativeParams& params) {
  return std::make_unique<ConservativeEngineImpl>(world, params);
}

const ConservativeStats* conservative_stats(const VisibilityEngine& engine) {
  const auto* impl = dynamic_cast<const ConservativeEngineImpl*>(&engine);
  return impl ? &impl->stats() : nullptr;
}

}  // namespace cellwalk
