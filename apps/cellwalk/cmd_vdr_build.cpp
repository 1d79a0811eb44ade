// cellwalk vdr-build: one model's progressive mesh and vsplit DAG (seed 004, §3.2–§3.4) into a
// VDR model file (docs/format.md "VDR model file"; docs/vdr.md).
#include <cstdio>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "cellwalk/core/byte_size.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/core/process_memory.hpp"
#include "cellwalk/scene/import.hpp"
#include "cellwalk/systems/vdr/vdr_file.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "json_output.hpp"

namespace cellwalk::app {
namespace {

struct VdrBuildArgs {
  std::string model, out, dag = "mini";
  vdr::PmBuildOptions pm;
  bool json = false;
};

// Every object of the model in one mesh: the PM is of the whole model.
Mesh vdr_merged_model(const std::string& file) {
  Mesh all;
  for (const Object& o : import_model(file).objects) append(all, o.mesh);
  if (all.triangle_count() == 0) fail(file, "holds no triangle to simplify");
  return all;
}

template <typename F>
auto vdr_with_progress(const char* label, F&& build) {
  std::unique_ptr<Progress> progress;
  auto result = build([&](uint64_t done, uint64_t total) {
    if (!progress) progress = std::make_unique<Progress>(label, total);
    progress->update(done);
  });
  if (progress) progress->finish();
  return result;
}

void run_vdr_build(const VdrBuildArgs& a) {
  const std::string out = a.out.empty() ? std::filesystem::path(a.model).replace_extension(".cwvdr").string() : a.out;
  refuse_same_files({a.model}, {out});
  const vdr::DagKind kind = vdr::parse_dag_kind(a.dag);
  const Mesh input = vdr_merged_model(a.model);
  Stopwatch clock;
  const vdr::ProgressiveMesh pm = vdr_with_progress("progressive mesh", [&](const vdr::PmProgress& p) {
    return vdr::build_progressive_mesh(input, a.pm, a.model, p);
  });
  const double pm_s = clock.lap_ms() / 1000;
  const vdr::VsplitDag dag = vdr_with_progress("vsplit DAG", [&](const vdr::DagProgress& p) { return vdr::build_vsplit_dag(pm, kind, p); });
  const double dag_s = clock.lap_ms() / 1000;
  vdr::write_vdr_file(out, pm, dag);
  const uint64_t file_bytes = std::filesystem::file_size(out);
  nlohmann::ordered_json j = {{"output", out},
                              {"input_triangles", input.triangle_count()},
                              {"vertices", pm.vertex_count()},
                              {"base_vertices", pm.base_vertex_count},
                              {"base_triangles", pm.base_triangle_count},
                              {"vsplits", pm.vsplit_count()},
                              {"dag", vdr::dag_kind_name(kind)},
                              {"edges", dag.edge_count()},
                              {"dag_bytes", dag.byte_size()},
                              {"file_bytes", file_bytes},
                              {"pm_seconds", pm_s},
                              {"dag_seconds", dag_s},
                              {"peak_rss_bytes", peak_rss_bytes()}};
  if (a.json) {
    print_json("vdr-build", j);
    return;
  }
  std::printf("%s: %u vertices, base %u vertices / %u triangles, %u vsplits\n", out.c_str(), pm.vertex_count(),
              pm.base_vertex_count, pm.base_triangle_count, pm.vsplit_count());
  std::printf("  %s DAG: %llu edges, %s; file %s\n", vdr::dag_kind_name(kind).c_str(),
              static_cast<unsigned long long>(dag.edge_count()), byte_size_text(dag.byte_size()).c_str(),
              byte_size_text(file_bytes).c_str());
  std::printf("  progressive mesh %.2f s, DAG %.2f s, peak resident %s\n", pm_s, dag_s, byte_size_text(peak_rss_bytes()).c_str());
}

}  // namespace

void register_vdr_build(CLI::App& root) {
  auto* cmd = root.add_subcommand("vdr-build", "Build a model's progressive mesh and vsplit DAG for view-dependent streaming (.cwvdr)");
  auto a = std::make_shared<VdrBuildArgs>();
  cmd->add_option("model", a->model, "Model file (.obj .ply .off .gltf .glb); all its objects become one mesh")->required();
  cmd->add_option("-o,--output", a->out, "VDR model file (default: MODEL with the extension .cwvdr)");
  cmd->add_option("--dag", a->dag, "DAG builder: mini (Fig. 3.10), non (Fig. 3.9, quadratic) or full")->capture_default_str()
      ->check(CLI::IsMember({"mini", "non", "full"}));
  cmd->add_option("--base-triangles", a->pm.base_triangles, "Stop collapsing at this many triangles")->capture_default_str()
      ->check(integer_in(1, 100'000'000));
  cmd->add_option("--max-valence", a->pm.max_valence, "Most neighbours a collapse may leave a vertex")->capture_default_str()
      ->check(integer_in(6, 1000));
  cmd->add_flag("--json", a->json, "Print the report as JSON");
  cmd->callback([a] { run_vdr_build(*a); });
}

}  // namespace cellwalk::app
