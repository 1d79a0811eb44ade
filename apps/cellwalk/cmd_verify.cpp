// cellwalk verify: check every checksum of a world file.
#include <cstdio>
#include <memory>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_verify(CLI::App& root) {
  auto* cmd = root.add_subcommand("verify", "Check every page checksum and the directory of a world file");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("world", *file, "World file (.cww)")->required();
  cmd->add_flag("--json", *json, "Print what was checked as JSON");
  cmd->callback([file, json] {
    World world(*file);  // header, tables and directory are checked on open
    std::unique_ptr<Progress> progress;
    const uint64_t pages = world.file().verify([&](uint64_t done, uint64_t total) {
      if (!progress) progress = std::make_unique<Progress>("verify", total);
      progress->update(done);
    });
    progress.reset();
    const uint64_t rtree_nodes = world.file().has_section(kRTreeSection) ? DiskRTree(world).check() : 0;
    if (*json) {
      print_json("verify", {{"input", *file},
                            {"intact", true},
                            {"data_pages", pages - 1},
                            {"pages", world.file().page_count()},
                            {"page_size", world.file().page_size()},
                            {"sections", world.file().sections().size()},
                            {"objects", world.object_count()},
                            {"rtree_nodes", rtree_nodes}});
      return;
    }
    if (rtree_nodes > 0)
      std::printf("verify: R-tree of %llu nodes checked: boxes, levels, every object once\n", (unsigned long long)rtree_nodes);
    std::printf("verify: %s is intact: header, tables and %llu data pages of %u bytes checked (%llu pages in all), "
                "%zu sections, %zu objects\n",
                file->c_str(), (unsigned long long)(pages - 1), world.file().page_size(),
                (unsigned long long)world.file().page_count(), world.file().sections().size(), world.object_count());
  });
}

}  // namespace cellwalk::app
