// cellwalk: interactive walkthroughs of worlds larger than memory. One binary, subcommands.
#include <cstdio>

#include "cellwalk/core/error.hpp"
#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App root{"cellwalk: walkthroughs of 3D worlds larger than memory", "cellwalk"};
  root.require_subcommand(1);
  root.set_version_flag("--version", "cellwalk 0.1.0");
  cellwalk::app::register_generate(root);
  cellwalk::app::register_import(root);
  cellwalk::app::register_build(root);
  cellwalk::app::register_info(root);
  cellwalk::app::register_verify(root);
  cellwalk::app::register_pvs(root);
  cellwalk::app::register_visual_build(root);
  cellwalk::app::register_path(root);
  cellwalk::app::register_walk(root);
  cellwalk::app::register_compare(root);
  cellwalk::app::register_render(root);
  cellwalk::app::register_view(root);
  cellwalk::app::register_bench(root);
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return root.exit(e);
  } catch (const cellwalk::Error& e) {
    std::fprintf(stderr, "cellwalk: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cellwalk: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
