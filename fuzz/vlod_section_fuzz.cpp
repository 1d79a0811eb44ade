// libFuzzer target for the vlod section reader (StoredVlod; docs/format.md, "The vlod
// section"). The section is a real one, of a small generated city's vLODs, edited by the
// input: the first byte 0 takes the rest of the input as the section itself; otherwise the
// input is a truncation (u16, modulo the section's size + 1) and then (u16 offset, u8 xor)
// edits. Opening the section and reading every key cell and every Δ must give ids or a
// cellwalk::Error, never a crash, another exception or an id past the piece count.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/precompute/engine.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/visibility/stored_vlod.hpp"
#include "edits.hpp"
#include "experiments/common/bench_world.hpp"
#include "precompute/embree_scene.hpp"
#include "precompute/pvs_builder.hpp"

namespace {

using namespace cellwalk;

// A world with a vlod section, made once per process, and that section's bytes.
struct Base {
  std::string dir = "/tmp/cellwalk-fuzz-vlod-" + std::to_string(getpid());
  std::string world_file = dir + "/city.cww", vlod_file = dir + "/city-vlod.cww";
  std::unique_ptr<World> world;
  std::vector<uint8_t> section;

  Base() {
    std::filesystem::create_directories(dir);
    bench::make_bench_world(CityParams{.objects = 12, .seed = 3}, bench::WorldBuild{}, dir + "/city.cwscene", world_file);
    const World plain(world_file);
    EngineOptions options;
    options.lod_rule.lens.viewport_height_px = 72;
    const auto engine = make_engine("vlod", plain, options);
    const visibility::EmbreeScene scene(plain);
    const auto partition = visibility::make_partition("grid:40", plain, scene);
    const visibility::PvsRun run = visibility::make_pvs_run(*engine, "grid:40", options, "", 1);
    const visibility::CellSets sets = visibility::compute_cell_sets(plain, *engine, *partition, run, vlod_file + ".checkpoint");
    visibility::write_world_with_vlod(plain, vlod_file, *partition, sets, options.lod_rule);
    world = std::make_unique<World>(vlod_file);
    section = world->file().read_all(visibility::kVlodSection);
  }
  ~Base() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

void check(const std::vector<uint32_t>& ids, uint64_t pieces) {
  for (uint32_t id : ids)
    if (id >= pieces) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Base base;
  if (size == 0) return 0;
  static const std::string path = base.dir + "/input.cww";
  visibility::write_world_sections(*base.world, path, {{visibility::kVlodSection, fuzz::edited(base.section, data, size, data[0] == 0), {}}});
  try {
    const World world(path);
    const visibility::StoredVlod stored(world);
    const uint64_t pieces = stored.pieces().count();
    for (CellId c = 0; c < stored.partition().cell_count(); ++c) {
      if (stored.is_key(c)) check(stored.key_vlod(c), pieces);
      for (CellId n : stored.neighbours(c))
        if (const auto d = stored.delta(c, n)) check(d->added, pieces), check(d->removed, pieces);
    }
  } catch (const Error&) {
  }
  return 0;
}
