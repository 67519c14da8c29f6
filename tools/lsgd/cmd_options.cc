// lsgd options [--markdown] [--config F] [--option KEY=VALUE ...]: every
// detector option with its value, unit, range and documentation.
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "common.h"
#include "lsgd/io/config.h"

namespace lsgd::cli {
namespace {

struct OptionsArgs {
  DetectorFlags detector;
  bool markdown = false;
  bool yaml = false;
};

}  // namespace

void register_options(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "options",
      "list every detector option: key, value (the defaults, or after --config and the "
      "flags), unit, range and what it does");
  auto args = std::make_shared<OptionsArgs>();
  args->detector.add_to(*cmd);
  cmd->add_flag("--markdown", args->markdown, "as the Markdown table of docs/options.md");
  cmd->add_flag("--yaml", args->yaml, "as a YAML config (for --config)")->excludes("--markdown");
  cmd->callback([args] {
    const DetectorOptions options = args->detector.resolve();
    std::cout << (args->yaml ? io::to_yaml(options) : io::options_reference(options, args->markdown));
  });
}

}  // namespace lsgd::cli
