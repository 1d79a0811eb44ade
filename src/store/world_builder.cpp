// `cellwalk build`: a scene file streamed into a world file. Objects are read in order, their
// LOD chains built and encoded in parallel a bounded batch at a time, and written in order, so
// memory holds one batch of meshes plus the directory (40 + 24 × levels bytes per object) and
// the names (4 bytes plus the name per object).
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <filesystem>
#include <thread>

#include <nlohmann/json.hpp>

#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"
#include "core/bytes.hpp"
#include "core/stopwatch.hpp"
#include "scene/scene_info_codec.hpp"
#include "store/world_sections.hpp"

namespace cellwalk {
namespace {

struct EncodedObject {
  ObjectRecord record;
  std::vector<LodRecord> levels;  // offsets filled in when written
  std::vector<std::vector<uint8_t>> blobs;
};

EncodedObject encode_object(const Object& object, const BuildParams& params) {
  EncodedObject out;
  out.record.bounds = object.bounds;
  out.record.color = object.color;
  LodChain chain = build_lod_chain(object.mesh, params.lod);
  for (const LodLevel& level : chain.levels) {
    out.blobs.push_back(encode_mesh(level.mesh, params.codec));
    if (out.blobs.back().size() > UINT32_MAX)
      fail("object " + object.name, "one level encodes to more than 4 GiB, the world format's limit per level");
    out.levels.push_back({0, static_cast<uint32_t>(out.blobs.back().size()),
                          static_cast<uint32_t>(level.triangle_count), level.error});
  }
  return out;
}

// Runs fn(i) for i in [0, n) on `threads` threads. The first exception any call throws stops
// the others from starting new work and is rethrown here once every thread has joined.
template <typename Fn>
void parallel_for(size_t n, int threads, Fn fn) {
  std::atomic<size_t> next{0};
  std::mutex mutex;
  std::exception_ptr failure;
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!failure) failure = std::current_exception();
        next = n;
      }
    }
  };
  {
    std::vector<std::jthread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
  }
  if (failure) std::rethrow_exception(failure);
}

std::string params_json(const BuildParams& p, const std::string& scene_file) {
  nlohmann::ordered_json j = {
      {"source", scene_file},
      {"page_size", p.page_size},
      {"lod", {{"ratio", p.lod.ratio}, {"min_triangles", p.lod.min_triangles}, {"stall_fraction", p.lod.stall_fraction}}},
      {"codec", {{"position_bits", p.codec.position_bits}, {"normal_bits", p.codec.normal_bits},
                 {"zstd", p.codec.zstd}, {"zstd_level", p.codec.zstd_level}}}};
  return j.dump(2);
}

std::span<const uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

// The scene's textures, each as its levels' image files (texture_levels), one after another,
// and their table. A world without textures has neither section (a section of no bytes has no
// page).
void write_textures(const SceneReader& scene, WorldWriter& writer) {
  if (scene.texture_count() == 0) return;
  ByteWriter textures, levels;
  uint32_t level_count = 0;
  writer.begin_section(world_sections::kTextures);
  for (uint32_t i = 0; i < scene.texture_count(); ++i) {
    const TextureImage texture = scene.read_texture(i);
    const std::vector<TextureLevel> made =
        texture_levels(texture.encoded, scene.path() + ": texture " + std::to_string(i) + " (" + texture.name + ")");
    textures.put(level_count);
    textures.put(uint32_t(made.size()));
    level_count += uint32_t(made.size());
    for (const TextureLevel& level : made) {
      levels.put(writer.section_offset());
      levels.put(uint32_t(level.encoded.size()));
      levels.put(level.width);
      levels.put(level.height);
      levels.put(uint32_t{0});
      writer.write(level.encoded);
    }
  }
  writer.end_section();
  ByteWriter table;
  table.put(uint32_t(scene.texture_count()));
  table.put(level_count);
  table.put_array(std::span<const uint8_t>(textures.bytes()));
  table.put_array(std::span<const uint8_t>(levels.bytes()));
  writer.begin_section(world_sections::kTextureTable);
  writer.write(table.bytes());
  writer.end_section();
}

}  // namespace

BuildReport build_world(const std::string& scene_file, const std::string& world_file,
                        const BuildParams& params, const std::function<void(uint64_t, uint64_t)>& progress,
                        const ExtraSections& extra_sections) {
  Stopwatch watch;
  SceneReader scene(scene_file);
  WorldWriter writer(world_file, params.page_size);
  const int threads = params.threads > 0 ? params.threads : std::max(1u, std::thread::hardware_concurrency());
  const size_t batch_size = static_cast<size_t>(threads) * 4;
  BuildReport report;
  std::vector<ObjectRecord> objects;
  std::vector<LodRecord> lods;
  objects.reserve(scene.object_count());
  ByteWriter names;  // of the objects, for a user who asks what a cell sees (pvs --show)

  writer.begin_section(world_sections::kGeometry);
  for (size_t begin = 0; begin < scene.object_count(); begin += batch_size) {
    const size_t n = std::min(batch_size, scene.object_count() - begin);
    std::vector<EncodedObject> batch(n);
    std::vector<std::string> batch_names(n);
    parallel_for(n, threads, [&](size_t i) {
      const Object object = scene.read_object(static_cast<ObjectId>(begin + i));
      batch[i] = encode_object(object, params);
      batch_names[i] = object.name;
    });
    for (const std::string& name : batch_names) names.put_string(name);
    for (EncodedObject& e : batch) {
      e.record.first_lod = lods.size();
      e.record.lod_count = static_cast<uint32_t>(e.levels.size());
      for (size_t l = 0; l < e.levels.size(); ++l) {
        e.levels[l].offset = writer.section_offset();
        writer.write(e.blobs[l]);
        lods.push_back(e.levels[l]);
        report.stored_triangles += e.levels[l].triangles;
        report.geometry_bytes += e.blobs[l].size();
      }
      report.level0_bytes += e.blobs[0].size();
      report.triangles += e.levels[0].triangles;
      objects.push_back(e.record);
    }
    if (progress) progress(begin + n, scene.object_count());
  }
  writer.end_section();
  for (ObjectId id = 0; id < scene.object_count(); ++id) {
    // Raw storage as the scene file holds it: float positions and normals, u32 indices.
    report.raw_bytes += scene.entry(id).size;
  }

  ByteWriter w;
  for (const ObjectRecord& o : objects) {
    put_box(w, o.bounds);
    w.put(o.color);
    w.put(o.lod_count);
    w.put(o.first_lod);
  }
  writer.begin_section(world_sections::kObjects);
  writer.write(w.bytes());
  writer.end_section();
  w.clear();
  for (const LodRecord& l : lods) {
    w.put(l.offset);
    w.put(l.bytes);
    w.put(l.triangles);
    w.put(l.error);
    w.put(uint32_t{0});
  }
  writer.begin_section(world_sections::kLods);
  writer.write(w.bytes());
  writer.end_section();
  w.clear();
  encode_scene_info(w, scene.info());
  writer.begin_section(world_sections::kScene);
  writer.write(w.bytes());
  writer.end_section();
  writer.begin_section(world_sections::kParams);
  writer.write(as_bytes(params_json(params, scene_file)));
  writer.end_section();
  write_textures(scene, writer);
  if (!objects.empty()) {  // a section of no bytes has no page: the format has none
    writer.begin_section(world_sections::kNames);
    writer.write(names.bytes());
    writer.end_section();
  }
  if (extra_sections) {
    std::vector<Aabb> bounds;
    bounds.reserve(objects.size());
    for (const ObjectRecord& o : objects) bounds.push_back(o.bounds);
    extra_sections(writer, bounds);
  }
  writer.finish();

  report.objects = objects.size();
  report.levels = lods.size();
  report.file_bytes = std::filesystem::file_size(world_file);
  report.seconds = watch.ms() / 1000.0;
  report.peak_rss_bytes = peak_rss_bytes();
  return report;
}

}  // namespace cellwalk
