// cellwalk build: a scene file into a world file (LOD chains, encoded, paged, checksummed).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cellwalk/index/rtree.hpp"
#include "cellwalk/store/world.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "json_output.hpp"

namespace cellwalk::app {

void register_build(CLI::App& root) {
  auto* cmd = root.add_subcommand("build", "Build a world file from a scene file: LOD chains, compressed, paged");
  struct Args {
    std::string scene, out;
    BuildParams params;
    RTreeParams rtree;
    bool str = false;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("scene", args->scene, "Scene file (.cwscene) from generate or import")->required();
  cmd->add_option("-o,--output", args->out, "World file to write (.cww)")->required();
  cmd->add_option("--page-size", args->params.page_size, "Page size in bytes (a power of two, 512 to 1 MiB)")->capture_default_str()->check(page_size_check());
  cmd->add_option("--lod-ratio", args->params.lod.ratio, "Triangles of each level relative to the previous")->capture_default_str()->check(number_in(0.05, 0.95));
  cmd->add_option("--lod-min-triangles", args->params.lod.min_triangles, "Stop making levels at this many triangles")->capture_default_str()->check(integer_in(1, 1000000000));
  cmd->add_option("--position-bits", args->params.codec.position_bits, "Quantisation of positions, bits per axis")->capture_default_str()->check(integer_in(1, 16));
  cmd->add_flag("--zstd", args->params.codec.zstd, "Compress encoded geometry with zstd as well");
  cmd->add_option("--threads", args->params.threads, "Worker threads (0 = all cores)")->capture_default_str()->check(thread_count());
  cmd->add_option("--rtree-fanout", args->rtree.max_entries, "R-tree node fan-out M (0 = as many as fit a page)")->capture_default_str()->check(integer_in(0, 65536));
  cmd->add_flag("--rtree-str", args->str, "Pack the R-tree with Sort-Tile-Recursive instead of inserting (Ang-Tan split)");
  cmd->add_flag("--json", args->json, "Print the report as JSON");
  cmd->callback([args] {
    refuse_same_files({args->scene}, {args->out});
    if (args->str) args->rtree.method = RTreeMethod::kStr;
    build_rtree({}, args->rtree, args->params.page_size);  // bad R-tree parameters fail before the build
    std::unique_ptr<Progress> progress;
    BuildReport r = build_world(args->scene, args->out, args->params,
                                [&](uint64_t done, uint64_t total) {
                                  if (!progress) progress = std::make_unique<Progress>("build", total);
                                  progress->update(done);
                                },
                                [&](WorldWriter& writer, std::span<const Aabb> bounds) {
                                  write_rtree_section(build_rtree(bounds, args->rtree, writer.page_size()), writer);
                                });
    progress.reset();
    if (args->json) {
      nlohmann::ordered_json j = {{"input", args->scene}, {"output", args->out}, {"objects", r.objects}, {"triangles", r.triangles},
                                  {"levels", r.levels}, {"stored_triangles", r.stored_triangles},
                                  {"raw_bytes", r.raw_bytes}, {"level0_bytes", r.level0_bytes},
                                  {"geometry_bytes", r.geometry_bytes}, {"file_bytes", r.file_bytes},
                                  {"seconds", r.seconds}, {"triangles_per_second", r.triangles / std::max(r.seconds, 1e-9)},
                                  {"peak_rss_bytes", r.peak_rss_bytes}};
      print_json("build", j);
      return;
    }
    std::printf("build: %llu objects, %llu triangles (%llu levels, %llu triangles in all levels)\n"
                "  level 0: %.2f bytes/triangle encoded vs %.2f raw (%.1fx smaller); file %.1f MiB\n"
                "  %.1f s, %.2f M triangles/s, peak memory %.0f MiB; wrote %s\n",
                (unsigned long long)r.objects, (unsigned long long)r.triangles, (unsigned long long)r.levels,
                (unsigned long long)r.stored_triangles, double(r.level0_bytes) / std::max<uint64_t>(r.triangles, 1),
                double(r.raw_bytes) / std::max<uint64_t>(r.triangles, 1),
                double(r.raw_bytes) / std::max<uint64_t>(r.level0_bytes, 1), r.file_bytes / 1048576.0, r.seconds,
                r.triangles / std::max(r.seconds, 1e-9) / 1e6, r.peak_rss_bytes / 1048576.0, args->out.c_str());
  });
}

}  // namespace cellwalk::app
