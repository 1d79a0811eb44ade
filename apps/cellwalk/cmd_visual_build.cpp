// cellwalk visual-build: the HDoV-tree of a world (HDoV thesis ch. 5, Fig. 5.13) from the DoVs
// `cellwalk pvs --engine dov` stored in it, written to WORLD.hdov (docs/visual.md).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cellwalk/systems/visual/visual_strategy.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_visual_build(CLI::App& root) {
  auto* cmd = root.add_subcommand("visual-build", "Build the HDoV-tree of VISUAL (WORLD.hdov) from the world's stored DoVs");
  struct Args {
    std::string world, out;
    HdovBuildParams params;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("world", a->world, "World file (.cww) with DoVs (cellwalk pvs WORLD --engine dov)")->required();
  cmd->add_option("-o,--output", a->out, "Tree file (default: WORLD.hdov)");
  cmd->add_option("--fanout", a->params.max_entries, "R-tree fan-out M")->capture_default_str()->check(integer_in(4, 140));
  cmd->add_option("--lod-levels", a->params.lods.levels, "Internal LODs per node")->capture_default_str()->check(integer_in(1, 8));
  cmd->add_option("--lod-ratio", a->params.lods.ratio, "Triangles of each internal LOD / the previous")->capture_default_str()->check(number_in(0.05, 0.95));
  cmd->add_flag("--json", a->json, "Print the report as JSON");
  cmd->callback([a] {
    const std::string out = a->out.empty() ? default_hdov_path(a->world) : a->out;
    refuse_same_files({a->world}, {out});
    const World world(a->world);
    std::unique_ptr<Progress> progress;
    const HdovTreeBuild built = build_visual_tree(world, out, a->params, [&](uint64_t done, uint64_t total) {
      if (!progress) progress = std::make_unique<Progress>("HDoV-tree", total);
      progress->update(done);
    });
    if (progress) progress->finish();
    const HdovTree tree(world, out);
    nlohmann::ordered_json j = {{"input", a->world}, {"output", out}, {"nodes", tree.node_count()}, {"cells", tree.cell_count()},
                                {"height", tree.height()}, {"fanout", tree.max_entries()},
                                {"visible_nodes", built.visible_nodes()}};
    for (VPageScheme s : {VPageScheme::kHorizontal, VPageScheme::kVertical, VPageScheme::kIndexedVertical})
      j["storage"][vpage_scheme_name(s)] = tree.storage(s).total();
    j["storage"]["naive"] = tree.naive_bytes();
    if (a->json) {
      print_json("visual-build", j);
      return;
    }
    std::printf("%s: %u nodes, height %u, M %u, %u cells, %llu visible (node, cell) pairs\n", out.c_str(), tree.node_count(),
                tree.height(), tree.max_entries(), tree.cell_count(), static_cast<unsigned long long>(built.visible_nodes()));
    for (const auto& [k, v] : j["storage"].items()) std::printf("  %-17s %12llu bytes\n", k.c_str(), static_cast<unsigned long long>(v.get<uint64_t>()));
  });
}

}  // namespace cellwalk::app
