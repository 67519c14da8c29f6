// The lsgd subcommands: each registers itself on the application.
#pragma once

namespace CLI {
class App;
}

namespace lsgd::cli {

void register_run(CLI::App& app);   // lsgd run: detect loops in a sequence, CSV out
void register_eval(CLI::App& app);  // lsgd eval: detect and score against ground truth
void register_demo(CLI::App& app);  // lsgd demo: the built-in synthetic world

}  // namespace lsgd::cli
