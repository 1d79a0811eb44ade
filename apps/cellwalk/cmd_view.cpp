// PLACEHOLDER: replaced by the real command before the first commit.
#include "commands.hpp"
namespace cellwalk::app {
void register_view(CLI::App& root) { root.add_subcommand("view", "(not yet built)"); }
}  // namespace cellwalk::app
