// cellwalk: interactive walkthroughs of worlds larger than memory. One binary, subcommands.
#include <cstdio>
#include <string>

#include "cellwalk/core/error.hpp"
#include "commands.hpp"

namespace {

// The leading words of the command line that name no subcommand of the app they follow, said
// plainly (CLI11 would only say "A subcommand is required"): "unknown subcommand 'x' of
// cellwalk; expected one of: generate, import, ...". Empty when every word is known.
std::string unknown_subcommand(const CLI::App& root, int argc, char** argv) {
  const CLI::App* app = &root;
  for (int i = 1; i < argc && argv[i][0] != '-' && !app->get_subcommands({}).empty(); ++i) {
    const CLI::App* next = nullptr;
    for (const CLI::App* sub : app->get_subcommands({}))
      if (sub->get_name() == argv[i]) next = sub;
    if (!next) {
      std::string names;
      for (const CLI::App* sub : app->get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
      return "unknown subcommand '" + std::string(argv[i]) + "' of " + app->get_display_name() +
             "; expected one of: " + names + " (see " + app->get_display_name() + " --help)";
    }
    app = next;
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App root{"cellwalk: walkthroughs of 3D worlds larger than memory", "cellwalk"};
  root.require_subcommand(1);
  root.set_version_flag("--version", "cellwalk 0.1.0");
  // One line like every other error (set before the subcommands, which copy it).
  root.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "cellwalk: " + std::string(e.what()) + "; see cellwalk --help\n";
  });
  cellwalk::app::register_generate(root);
  cellwalk::app::register_import(root);
  cellwalk::app::register_build(root);
  cellwalk::app::register_info(root);
  cellwalk::app::register_verify(root);
  cellwalk::app::register_db(root);
  cellwalk::app::register_pvs(root);
  cellwalk::app::register_visual_build(root);
  cellwalk::app::register_stratify(root);
  cellwalk::app::register_vdr_build(root);
  cellwalk::app::register_path(root);
  cellwalk::app::register_walk(root);
  cellwalk::app::register_compare(root);
  cellwalk::app::register_render(root);
  cellwalk::app::register_view(root);
  cellwalk::app::register_serve(root);
  cellwalk::app::register_connect(root);
  cellwalk::app::register_bench(root);
  if (const std::string unknown = unknown_subcommand(root, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "cellwalk: %s\n", unknown.c_str());
    return 1;
  }
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
