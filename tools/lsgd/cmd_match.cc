// lsgd match --reference R --query Q [--top-k K] [--output FILE] [--query-offset N]
//
// Place recognition between two traverses (winter against summer, a second
// drive against a map): each query image is described as the detector would
// (its options' segmentation and descriptor) and scored against every
// reference image; its K best are written, one row each:
//   query,match,score,similarity,rank
// query: N + the query image's index (N = --query-offset, default the number
// of reference images, so that one ground truth numbers both traverses in
// one sequence: reference 0 .. N-1, then the queries); match: the reference
// image's index; score: the similarity in standard deviations of the query's
// similarities to the whole reference (comparable across queries, as the
// detector's single-frame evidence); similarity: the metric's raw value;
// rank: 1 for the best. `lsgd eval --detections FILE --gt GT --min-gap 0`
// scores it (R@N from the ranks).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "commands.h"
#include "internal/check.h"
#include "common.h"
#include "files.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/results_csv.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/layouts.h"
#include "lsgd/limits.h"
#include "lsgd/similarity.h"

namespace lsgd::cli {
namespace {

struct MatchArgs {
  std::string reference, query, output;
  int top_k = 1;
  std::optional<std::int64_t> query_offset;
  DetectorFlags detector;
  SequenceFlags layout;
};

// Every image's descriptor and its index in the traverse. An image that
// cannot be read, or has another size than the first, is skipped and
// reported (its index keeps its number: no match names it, no row is
// written for it), or with --strict an error naming it.
struct Described {
  std::vector<Descriptor> descriptors;
  std::vector<std::int64_t> index;  // of each descriptor in the traverse
  std::int64_t skipped = 0;
};

Described describe_all(Detector& detector, const io::Sequence& sequence, const char* flag, bool strict,
                       int& width, int& height) {
  Described out;
  const eval::FrameSource source = eval::sequence_source(sequence);
  const auto skip = [&](std::int64_t i, const std::string& why) {
    const std::string message = std::string(flag) + " image " + std::to_string(i) + ": " + why;
    if (strict) throw InvalidArgument(message);
    // The first kListedSkips of a traverse each get a line (as run's); the
    // summary counts them all.
    if (out.skipped < kListedSkips) {
      std::cerr << "lsgd match: skipping " << message << " (--strict stops here instead)\n";
    } else if (out.skipped == kListedSkips) {
      std::cerr << "lsgd match: more " << flag << " images skipped; only the first " << kListedSkips
                << " are listed (the count is in the summary)\n";
    }
    ++out.skipped;
  };
  for (std::int64_t i = 0; i < source.frames; ++i) {
    cv::Mat image;
    try {
      // After the first image, another size is refused from its header,
      // before it is decoded (an 8192x6144 PNG cost 313 MB and 1.5 s).
      image = width == 0 ? source.load(i) : source.load_sized(i, width, height);
    } catch (const InvalidArgument& e) {
      skip(i, "(" + source.name(i) + ") " + e.what() +
                  "; the traverses must have one frame size (the descriptor's grid follows it)");
      continue;
    } catch (const Error& e) {
      skip(i, e.what());
      continue;
    }
    if (width == 0) width = image.cols, height = image.rows;
    if (image.cols != width || image.rows != height) {
      skip(i, "(" + source.name(i) + ") is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                  ", the first image " + std::to_string(width) + "x" + std::to_string(height) +
                  ": the traverses must have one frame size (the descriptor's grid follows it)");
      continue;
    }
    out.descriptors.push_back(detector.describe(image));
    out.index.push_back(i);
  }
  return out;
}

// Only the description's options matter here: a flag that would be ignored
// is an error rather than a silent no-op.
void check_flags(const DetectorFlags& flags) {
  const auto refuse = [](const std::string& flag) {
    throw InvalidArgument(flag + " has no effect on lsgd match: it describes and compares frames "
                          "(segmentation, descriptor and similarity options), with no search or decision");
  };
  if (!flags.mode.empty()) refuse("--mode");
  if (flags.min_gap) refuse("--min-gap");
  if (flags.threshold) refuse("--threshold");
  if (!flags.verify.empty()) refuse("--verify");
  for (const std::string& o : flags.options) {
    const std::string key = o.substr(0, o.find('='));
    if (key.rfind("segmentation.", 0) != 0 && key.rfind("descriptor.", 0) != 0 &&
        key.rfind("similarity.", 0) != 0) {
      refuse("--option " + internal::shown_value(key));
    }
  }
}

void match(const MatchArgs& args) {
  check_flags(args.detector);
  const DetectorOptions options = args.detector.resolve();
  const io::Sequence reference = io::open_sequence(args.reference, args.layout.resolve());
  const io::Sequence query = io::open_sequence(args.query, args.layout.resolve());
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.reference, "--reference");
  files.input(args.query, "--query");
  files.sequence(reference, "--reference", "reference image");
  files.sequence(query, "--query", "query image");
  files.output_or_stdout(args.output, "--output");
  files.check();
  if (reference.images.empty()) throw InvalidArgument("--reference " + args.reference + " holds no image");
  if (query.images.empty()) throw InvalidArgument("--query " + args.query + " holds no image");
  const auto references = static_cast<std::int64_t>(reference.images.size());
  const std::int64_t offset = args.query_offset.value_or(references);
  if (offset > kMaxFrameId - static_cast<std::int64_t>(query.images.size())) {
    throw InvalidArgument("--query-offset " + std::to_string(offset) + " leaves no room for the query ids");
  }
  const auto start = std::chrono::steady_clock::now();
  Detector detector(options);
  int width = 0, height = 0;
  const bool strict = args.layout.strict;
  const Described refs = describe_all(detector, reference, "--reference", strict, width, height);
  const Described queries = describe_all(detector, query, "--query", strict, width, height);
  if (refs.descriptors.empty()) {
    throw InvalidArgument("--reference " + args.reference + ": no image could be read (see above)");
  }
  if (queries.descriptors.empty()) {  // nothing to match: no CSV of a header alone
    throw InvalidArgument("--query " + args.query + ": no image could be read (see above); " +
                          std::to_string(queries.skipped) + " skipped");
  }
  std::vector<DescriptorView> views;
  for (const Descriptor& d : refs.descriptors) views.push_back(d.view());

  const auto k = static_cast<std::size_t>(
      std::min<std::int64_t>(args.top_k, static_cast<std::int64_t>(refs.descriptors.size())));
  std::vector<DescriptorView> query_views;
  for (const Descriptor& d : queries.descriptors) query_views.push_back(d.view());
  std::vector<TopMatch> rows =
      query_views.empty() ? std::vector<TopMatch>{}
                          : match_top_k(views, query_views, args.top_k, options.similarity.metric, 0);
  for (TopMatch& m : rows) {  // positions among the images read -> the traverses' own numbers
    m.query = offset + queries.index[static_cast<std::size_t>(m.query)];
    m.match = refs.index[static_cast<std::size_t>(m.match)];
  }
  // Written whole (a temporary file renamed over it), as lsgd.match writes
  // it: a second lsgd match given the same --output, or an interrupted one,
  // cannot leave rows of two runs or half a table.
  if (!args.output.empty()) {
    io::write_output_file(args.output, eval::match_csv(rows), "matches CSV");
  } else {
    std::cout << eval::match_csv(rows);
    std::cout.flush();
    if (!std::cout) throw IoError("error while writing standard output");
  }
  std::cerr << "matched " << queries.descriptors.size() << " query images against " << refs.descriptors.size()
            << " reference images (" << width << "x" << height << "), top " << k << " each, in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s"
            << (args.output.empty() ? "" : "; rows in " + args.output) << "; query ids from " << offset
            << (refs.skipped + queries.skipped > 0
                    ? "; skipped " + std::to_string(refs.skipped) + " reference and " +
                          std::to_string(queries.skipped) + " query images"
                    : std::string())
            << "\n";
}

}  // namespace

void register_match(CLI::App& app) {
  auto args = std::make_shared<MatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "match", "place recognition between two traverses: the top-k reference images of each query image, as CSV");
  cmd->add_option("--reference", args->reference, "the reference traverse: folder of images, list file or layout")
      ->required()
      ->check(kNonEmptyPath);
  cmd->add_option("--query", args->query, "the query traverse, the same way")->required()->check(kNonEmptyPath);
  cmd->add_option("--top-k", args->top_k, "reference images written per query image")
      ->check(CLI::Range(1, kMaxTopK))
      ->capture_default_str();
  cmd->add_option("--query-offset", args->query_offset,
                  "id of the first query image (default: the number of reference images, so one "
                  "ground truth numbers both traverses)")
      ->check(CLI::Range(std::int64_t{0}, kMaxFrameId));
  cmd->add_option("--output", args->output, "CSV file to write (default: standard output)")->check(kNonEmptyPath);
  args->detector.add_to(*cmd);
  args->layout.add_to(*cmd);
  cmd->callback([args] { match(*args); });
}

}  // namespace lsgd::cli
