// Scenes are streamed: generators and importers push objects one at a time into an
// ObjectSink, so no stage ever holds the whole world in memory.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cellwalk/core/geometry.hpp"
#include "cellwalk/scene/mesh.hpp"
#include "cellwalk/scene/texture.hpp"

namespace cellwalk {

// Where a walker may stand: a graph whose nodes are eye positions and whose edges are
// straight, unobstructed segments between them (street centre lines, walkway axes).
// Every point on an edge is navigable; paths are generated on this graph.
struct NavGraph {
  std::vector<Vec3> nodes;
  std::vector<std::pair<uint32_t, uint32_t>> edges;
};

// What a scene says about itself besides its objects.
struct SceneInfo {
  std::string generator;  // "city", "plant", "import:<file>", ...
  uint64_t seed = 0;
  Aabb bounds;            // of all objects
  NavGraph nav;
};

// Receives objects one at a time. add() assigns nothing: ids are the producer's, dense from 0
// in the order objects are added. Textures are numbered the same way, and a texture is added
// before the first object whose mesh samples it.
class ObjectSink {
 public:
  virtual ~ObjectSink() = default;
  virtual void add(const Object& object) = 0;
  // Sinks that keep geometry only (an OBJ for inspection, counters) ignore textures.
  virtual void add_texture(const TextureImage& texture) { (void)texture; }
};

// Counts what passes through, for the "objects, triangles, bytes" every producer prints.
struct SceneCounts {
  uint64_t objects = 0;
  uint64_t triangles = 0;
  uint64_t vertices = 0;
  uint64_t bytes = 0;  // Mesh::byte_size() summed
  void count(const Object& object) {
    ++objects;
    triangles += object.mesh.triangle_count();
    vertices += object.mesh.vertex_count();
    bytes += object.mesh.byte_size();
  }
};

// Forwards each object to several sinks (e.g. the scene file and an OBJ for inspection).
class TeeSink : public ObjectSink {
 public:
  explicit TeeSink(std::vector<ObjectSink*> sinks) : sinks_(std::move(sinks)) {}
  void add(const Object& object) override {
    for (ObjectSink* s : sinks_) s->add(object);
  }
  void add_texture(const TextureImage& texture) override {
    for (ObjectSink* s : sinks_) s->add_texture(texture);
  }

 private:
  std::vector<ObjectSink*> sinks_;
};

}  // namespace cellwalk
