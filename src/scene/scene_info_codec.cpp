#include "scene/scene_info_codec.hpp"

namespace cellwalk {

void put_box(ByteWriter& w, const Aabb& b) {
  w.put(b.min);
  w.put(b.max);
}

Aabb get_box(ByteReader& r) {
  Aabb b;
  b.min = r.get<Vec3>("box min");
  b.max = r.get<Vec3>("box max");
  return b;
}

void encode_scene_info(ByteWriter& w, const SceneInfo& info) {
  w.put(info.seed);
  w.put_string(info.generator);
  put_box(w, info.bounds);
  w.put(static_cast<uint32_t>(info.nav.nodes.size()));
  w.put_array(std::span<const Vec3>(info.nav.nodes));
  w.put(static_cast<uint32_t>(info.nav.edges.size()));
  for (auto [a, b] : info.nav.edges) {
    w.put(a);
    w.put(b);
  }
}

SceneInfo decode_scene_info(ByteReader& r) {
  SceneInfo info;
  info.seed = r.get<uint64_t>("seed");
  info.generator = r.get_string("generator");
  info.bounds = get_box(r);
  info.nav.nodes = r.get_array<Vec3>(r.get<uint32_t>("nav node count"), "nav nodes");
  const uint32_t edges = r.get<uint32_t>("nav edge count");
  auto flat = r.get_array<uint32_t>(uint64_t{edges} * 2, "nav edges");
  for (uint32_t i = 0; i < edges; ++i) {
    if (flat[2 * i] >= info.nav.nodes.size() || flat[2 * i + 1] >= info.nav.nodes.size())
      r.error("nav edge " + std::to_string(i) + " names a node that does not exist");
    info.nav.edges.emplace_back(flat[2 * i], flat[2 * i + 1]);
  }
  return info;
}

}  // namespace cellwalk
