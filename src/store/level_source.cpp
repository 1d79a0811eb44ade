#include "cellwalk/store/level_source.hpp"

#include "cellwalk/store/object_database.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk {
namespace {

class WorldLevelSource final : public LevelSource {
 public:
  explicit WorldLevelSource(const World& world) : world_(world) {}
  std::vector<uint8_t> read_level(ObjectId id, uint32_t level) const override {
    return world_.read_level(id, level);
  }
  uint64_t resident_bound() const override { return 0; }  // its tables are the world's directory
  const std::string& path() const override { return world_.file().path(); }

 private:
  const World& world_;
};

}  // namespace

std::unique_ptr<LevelSource> world_level_source(const World& world) {
  return std::make_unique<WorldLevelSource>(world);
}

std::unique_ptr<LevelSource> open_level_source(const World& world, const std::string& objects_db) {
  if (objects_db.empty()) return world_level_source(world);
  return std::make_unique<ObjectDatabase>(world, objects_db);
}

uint64_t level_source_bound(const World& world, const std::string& objects_db) {
  return objects_db.empty() ? 0 : ObjectDatabase::bound(world);
}

}  // namespace cellwalk
