// Not from one seed [ours]: the HDoV thesis (000) §3.3 builds its worlds by duplicating base
// models, and the other seeds' scanned models are tested the same way. This generator does
// only that — nx × ny × nz copies of one imported model on a lattice with walkable lanes
// between the columns and rows — as a controlled stress scene for every strategy.
#include <cmath>
#include <string>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/generators.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/core/random.hpp"
#include "scene/shapes.hpp"

namespace cellwalk {
namespace {

// Lane centre lines between the columns and rows of the lattice, at mid-height of the bottom
// layer: a grid graph, connected by construction.
NavGraph lane_graph(const GridParams& p, const Aabb& model, double spacing) {
  NavGraph g;
  const float y = model.min.y + model.size().y * 0.5f;
  const auto node = [&](int i, int j) { return static_cast<uint32_t>(j * (p.nx + 1) + i); };
  for (int j = 0; j <= p.nz; ++j)
    for (int i = 0; i <= p.nx; ++i) {
      g.nodes.emplace_back(float((i - 0.5) * spacing), y, float((j - 0.5) * spacing));
      if (i > 0) g.edges.emplace_back(node(i - 1, j), node(i, j));
      if (j > 0) g.edges.emplace_back(node(i, j - 1), node(i, j));
    }
  return g;
}

}  // namespace

SceneInfo generate_grid(const GridParams& params, ObjectSink& sink) {
  if (params.nx < 1 || params.ny < 1 || params.nz < 1)
    fail("grid", "nx, ny and nz must be at least 1");
  if (params.mesh.empty()) fail("grid", "no model given (--mesh FILE)");
  const Mesh model = shapes::unit_model(import_model(params.mesh).objects, params.mesh);
  const Aabb bounds = bounds_of(model);
  const double largest = std::max({bounds.size().x, bounds.size().y, bounds.size().z});
  const double spacing = params.spacing > 0.0 ? params.spacing : 1.5 * largest;
  // Lanes need a gap between neighbours in plan; layers may touch.
  if (spacing <= std::max(bounds.size().x, bounds.size().z))
    fail("grid", "spacing " + std::to_string(spacing) +
                     " leaves no lane between instances of size " +
                     std::to_string(std::max(bounds.size().x, bounds.size().z)) +
                     " (after scaling to unit size)");

  SceneInfo info{"grid:" + params.mesh, params.seed, {}, lane_graph(params, bounds, spacing)};
  shapes::ObjectEmitter out(sink, info);
  Random rng(params.seed);
  Mesh mesh;
  for (int y = 0; y < params.ny; ++y)
    for (int z = 0; z < params.nz; ++z)
      for (int x = 0; x < params.nx; ++x) {
        mesh = model;
        transform(mesh, shapes::Assembly::translate(
                            Vec3(float(x * spacing), float(y * spacing), float(z * spacing))));
        const Rgba8 colour = rgba8(uint8_t(rng.integer(80, 240)), uint8_t(rng.integer(80, 240)),
                                   uint8_t(rng.integer(80, 240)));
        out.emit("grid/" + std::to_string(x) + "_" + std::to_string(y) + "_" + std::to_string(z),
                 colour, mesh);
      }
  return info;
}

}  // namespace cellwalk
