// The subcommands of the one cellwalk binary. Each registers itself on the root app; the
// command files only parse arguments, call the library and print.
#pragma once

#include <CLI/CLI.hpp>

namespace cellwalk::app {

void register_generate(CLI::App& root);
void register_import(CLI::App& root);
void register_path(CLI::App& root);
void register_walk(CLI::App& root);
void register_compare(CLI::App& root);
void register_view(CLI::App& root);
void register_info(CLI::App& root);
void register_render(CLI::App& root);
void register_build(CLI::App& root);
void register_verify(CLI::App& root);
void register_db(CLI::App& root);
void register_serve(CLI::App& root);
void register_connect(CLI::App& root);
void register_pvs(CLI::App& root);
void register_bench(CLI::App& root);
void register_visual_build(CLI::App& root);
void register_stratify(CLI::App& root);
void register_vdr_build(CLI::App& root);
// Subcommands of `cellwalk bench`, called by register_bench.
void register_bench_scene_tree(CLI::App& bench, std::string (*command_line)());
void register_bench_review(CLI::App& bench, std::string (*command_line)());
void register_bench_visual(CLI::App& bench, std::string (*command_line)());
void register_bench_visibility(CLI::App& bench, std::string (*command_line)());
void register_bench_vlod(CLI::App& bench, std::string (*command_line)());
void register_bench_disk_order(CLI::App& bench, std::string (*command_line)());
void register_bench_import(CLI::App& bench, std::string (*command_line)());
void register_bench_pvs_stream(CLI::App& bench, std::string (*command_line)());
void register_bench_stratified(CLI::App& bench, std::string (*command_line)());
void register_bench_lichiang(CLI::App& bench, std::string (*command_line)());
void register_bench_vdr(CLI::App& bench, std::string (*command_line)());

}  // namespace cellwalk::app
