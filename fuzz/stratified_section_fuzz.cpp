// libFuzzer target for the stratified sections' reader (StoredStratified; docs/format.md,
// "`stratified` and `farfield`"). The sections are real ones — the viewcells and near lists of a small
// generated city, with far faces of 8² texels made without GL (a pattern of the cell's far
// objects) — edited by the input: its first byte picks the section (even: "stratified", odd:
// "farfield") and, when it is 0 or 1, the rest of the input is that section itself; otherwise a
// truncation (u16, modulo the section's size + 1) and then (u16 offset, u8 xor) edits. Opening
// and reading every cell's near list and far field must give data or a cellwalk::Error, never a
// crash, another exception, or an id past the objects.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cellwalk/core/error.hpp"
#include "cellwalk/store/world.hpp"
#include "cellwalk/systems/stratified/stored_stratified.hpp"
#include "cellwalk/visibility/stored_pvs.hpp"
#include "edits.hpp"
#include "experiments/common/bench_world.hpp"
#include "far_field_pattern.hpp"

namespace {

using namespace cellwalk;
using namespace cellwalk::stratified;

constexpr int kResolution = 8;

struct Base {
  std::string dir = "/tmp/cellwalk-fuzz-stratified-" + std::to_string(getpid());
  std::string world_file = dir + "/city.cww", stratified_file = dir + "/city-stratified.cww";
  std::unique_ptr<World> world;
  std::vector<uint8_t> sections[2];

  Base() {
    std::filesystem::create_directories(dir);
    bench::make_bench_world(CityParams{.objects = 12, .seed = 3}, bench::WorldBuild{}, dir + "/city.cwscene", world_file);
    const World plain(world_file);
    std::vector<Aabb> bounds(plain.object_count());
    for (ObjectId id = 0; id < plain.object_count(); ++id) bounds[id] = plain.object(id).bounds;
    const float b = 40.0f;
    const Viewcells cells = build_viewcells(default_cell_region(plain.info().bounds, plain.info().nav, true), 12.0f, b, bounds);
    write_world_with_stratified(plain, stratified_file, cells, {0.1f, 12.0f, b, "eq22", kResolution},
                                [&](CellId c) {
                                  StratifiedSizes unused;
                                  return encode_far_field(fuzz::far_field_pattern(c, plain.object_count(), b, kResolution), b, unused);
                                });
    world = std::make_unique<World>(stratified_file);
    sections[0] = world->file().read_all(kStratifiedSection);
    sections[1] = world->file().read_all(kFarFieldSection);
  }
  ~Base() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Base base;
  if (size == 0) return 0;
  static const std::string path = base.dir + "/input.cww";
  const int which = data[0] & 1;
  const char* name = which == 0 ? kStratifiedSection : kFarFieldSection;
  visibility::write_world_sections(*base.world, path, {{name, fuzz::edited(base.sections[which], data, size, data[0] < 2), {}}});
  try {
    const World world(path);
    const StoredStratified stored(world);
    for (CellId c = 0; c < stored.partition().cell_count(); ++c) {
      for (const ObjectId id : stored.near(c))
        if (id >= world.object_count()) std::abort();
      if (!stored.partition().cell(c).computed()) continue;
      for (const FaceImage& f : stored.far_field(c).faces)
        for (const uint32_t id : f.ids.ids)
          if (id > world.object_count()) std::abort();
    }
  } catch (const Error&) {
  }
  return 0;
}
