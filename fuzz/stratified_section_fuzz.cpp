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
#include "experiments/common/bench_world.hpp"

namespace {

using namespace cellwalk;
using namespace cellwalk::stratified;

constexpr int kResolution = 8;

// A face showing the far objects' ids in turn, at depths beyond the box.
CellFarField pattern_field(CellId c, uint64_t objects, float b) {
  CellFarField field;
  for (int face = 0; face < 4; face += 1 + int(c % 2)) {
    FaceImage f;
    f.face = face;
    f.color = {kResolution, kResolution, std::vector<uint8_t>(kResolution * kResolution * 4, 0)};
    f.ids = {kResolution, kResolution, std::vector<uint32_t>(kResolution * kResolution, 0)};
    f.depth.assign(kResolution * kResolution, 0.0f);
    for (size_t t = 0; t < f.depth.size(); t += 3) {
      f.ids.ids[t] = uint32_t(1 + (t + c) % objects);
      f.color.rgba[t * 4 + 3] = 255;
      f.depth[t] = b * (0.5f + 0.1f * float(t % 7));
    }
    field.faces.push_back(std::move(f));
  }
  return field;
}

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
                                [&](CellId c) { return pattern_field(c, plain.object_count(), b); });
    world = std::make_unique<World>(stratified_file);
    sections[0] = world->file().read_all(kStratifiedSection);
    sections[1] = world->file().read_all(kFarFieldSection);
  }
  ~Base() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

std::vector<uint8_t> edited(const std::vector<uint8_t>& section, const uint8_t* data, size_t size) {
  if (data[0] < 2) return {data + 1, data + size};
  std::vector<uint8_t> out = section;
  if (size >= 3) out.resize((data[1] | size_t(data[2]) << 8) % (section.size() + 1));
  for (size_t i = 3; i + 2 < size && !out.empty(); i += 3)
    out[(data[i] | size_t(data[i + 1]) << 8) % out.size()] ^= data[i + 2];
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Base base;
  if (size == 0) return 0;
  static const std::string path = base.dir + "/input.cww";
  const int which = data[0] & 1;
  const char* name = which == 0 ? kStratifiedSection : kFarFieldSection;
  visibility::write_world_sections(*base.world, path, {{name, edited(base.sections[which], data, size), {}}});
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
