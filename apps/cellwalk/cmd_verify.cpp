// cellwalk verify: check every checksum of a world file.
#include <cstdio>
#include <memory>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "commands.hpp"
#include "core/progress.hpp"

namespace cellwalk::app {

void register_verify(CLI::App& root) {
  auto* cmd = root.add_subcommand("verify", "Check every page checksum and the directory of a world file");
  auto file = std::make_shared<std::string>();
  cmd->add_option("world", *file, "World file (.cww)")->required();
  cmd->callback([file] {
    World world(*file);  // header, tables and directory are checked on open
    std::unique_ptr<Progress> progress;
    const uint64_t pages = world.file().verify([&](uint64_t done, uint64_t total) {
      if (!progress) progress = std::make_unique<Progress>("verify", total);
      progress->update(done);
    });
    progress.reset();
    if (world.file().has_section(kRTreeSection))
      std::printf("verify: R-tree of %llu nodes checked: boxes, levels, every object once\n",
                  (unsigned long long)DiskRTree(world).check());
    std::printf("verify: %s is intact: header, tables and %llu data pages of %u bytes checked (%llu pages in all), "
                "%zu sections, %zu objects\n",
                file->c_str(), (unsigned long long)(pages - 1), world.file().page_size(),
                (unsigned long long)world.file().page_count(), world.file().sections().size(), world.object_count());
  });
}

}  // namespace cellwalk::app
