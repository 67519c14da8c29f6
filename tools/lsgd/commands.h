// The lsgd subcommands: each registers itself on the application.
#pragma once

namespace CLI {
class App;
}

namespace lsgd::cli {

void register_run(CLI::App& app);   // lsgd run: detect loops in a sequence, CSV out
void register_eval(CLI::App& app);  // lsgd eval: detect and score against ground truth
void register_match(CLI::App& app);  // lsgd match: top-k places of one traverse in another
void register_demo(CLI::App& app);  // lsgd demo: the built-in synthetic world
void register_sweep(CLI::App& app);  // lsgd sweep: a grid of configurations on datasets, one table
void register_bench(CLI::App& app);  // lsgd bench: per-stage timing on a generated sequence
void register_gt(CLI::App& app);     // lsgd gt: convert ground-truth formats, print statistics
void register_db(CLI::App& app);     // lsgd db info: what a detector database holds
void register_options(CLI::App& app);  // lsgd options: every detector option, documented

}  // namespace lsgd::cli
