// Where the dynamic-node search spends its similarities, and how much of it an
// exact lower bound on L1 from coarser histograms could skip.
//
//   build/bench/lsgd_nodes_study [frames] [--timing-only]
//     (default 4541 frames; ~2 min, or ~1 min with --timing-only, which
//     skips the bound analysis)
//
// The sequence is `lsgd bench`'s: 1241x376 frames of the synthetic street,
// frame i showing route frame i % 1090, default detector options (S_p = 40,
// 80 cells, reference metric and thresholds, min_gap 50). It runs Algorithm 1
// exactly as DynamicNodes::assign does and, for every node whose members are
// scored, also computes for every member an upper bound on its similarity from
// histograms merged into 32, 16 or 8 coarse bins (merging bins never increases
// L1, so the bound is exact). A node whose bound on the mean stays at or below
// beta * base could be rejected without scoring its members. It prints the
// similarities spent per query and the share a bound would have saved, then
// runs DynamicNodes::assign itself on the same frames in exact and compact
// storage and prints its median time per query.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/eval/synthetic.h"
#include "lsgd/frame_store.h"
#include "lsgd/image.h"
#include "lsgd/search.h"
#include "lsgd/segmentation.h"
#include "lsgd/similarity.h"

namespace {

constexpr int kGroups[] = {8, 16, 32};  // intensities per coarse bin: 32, 16, 8 bins

std::vector<std::uint32_t> coarse(const lsgd::Descriptor& d, int group) {
  const int cells = d.grid.cells(), bins = lsgd::kBins / group;
  std::vector<std::uint32_t> out(static_cast<std::size_t>(cells) * bins, 0);
  for (int k = 0; k < cells; ++k) {
    for (int b = 0; b < lsgd::kBins; ++b) {
      out[static_cast<std::size_t>(k) * bins + b / group] +=
          d.hist[static_cast<std::size_t>(k) * lsgd::kBins + b];
    }
  }
  return out;
}

// The reference metric on coarse histograms: >= the exact similarity.
double upper_bound(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b,
                   int cells) {
  const std::size_t bins = a.size() / static_cast<std::size_t>(cells);
  double sum = 0;
  for (int k = 0; k < cells; ++k) {
    std::int64_t l1 = 0;
    for (std::size_t i = 0; i < bins; ++i) {
      const std::size_t at = static_cast<std::size_t>(k) * bins + i;
      l1 += std::llabs(static_cast<std::int64_t>(a[at]) - static_cast<std::int64_t>(b[at]));
    }
    sum += std::sqrt(static_cast<double>(l1)) / lsgd::kBins;
  }
  return 1.0 / (1.0 + sum / cells);
}

}  // namespace

int main(int argc, char** argv) {
  const std::int64_t frames = argc > 1 ? std::atoll(argv[1]) : 4541;
  const bool timing_only = argc > 2 && std::strcmp(argv[2], "--timing-only") == 0;
  if (frames < 1 || (argc > 2 && !timing_only) || argc > 3) {
    std::fprintf(stderr, "usage: %s [frames >= 1] [--timing-only]\n", argv[0]);
    return 2;
  }
  lsgd::eval::SyntheticOptions world_options;
  world_options.width = 1241;
  world_options.height = 376;
  const lsgd::eval::SyntheticWorld world(world_options);
  const lsgd::SearchOptions search;  // defaults: reference thresholds, min_gap 50
  lsgd::Segmenter segmenter{lsgd::SegmentationOptions{}};
  // Frame i repeats route frame i % 1090: describe each route frame once.
  const std::int64_t distinct = std::min<std::int64_t>(frames, world.frames());
  std::vector<lsgd::Descriptor> route(static_cast<std::size_t>(distinct));
  std::vector<std::vector<std::uint32_t>> coarse_route[3];
  for (std::int64_t i = 0; i < distinct; ++i) {
    cv::Mat gray;
    cv::cvtColor(world.render(i), gray, cv::COLOR_BGR2GRAY);
    const lsgd::GrayImage image = lsgd::to_gray(gray);
    route[static_cast<std::size_t>(i)] = lsgd::describe(image, segmenter.segment(image));
    for (int g = 0; g < 3 && !timing_only; ++g) {
      coarse_route[g].push_back(coarse(route[static_cast<std::size_t>(i)], kGroups[g]));
    }
  }
  const int cells = route[0].grid.cells();
  const auto at = [&](std::int64_t i) { return static_cast<std::size_t>(i % distinct); };
  const auto sim = [&](std::int64_t a, std::int64_t b) {
    return lsgd::similarity(route[at(a)].view(), route[at(b)].view(),
                            lsgd::SimilarityMetric::kReference);
  };

  const double n = static_cast<double>(frames);
  if (!timing_only) {
    std::vector<std::vector<std::int64_t>> nodes;
    std::int64_t first_sims = 0, member_sims = 0, scanned_nodes = 0, accepting_members = 0;
    std::int64_t saved[3] = {0, 0, 0};
    for (std::int64_t q = 0; q < frames; ++q) {
      const double base = search.nodes.threshold_0 * (q > 0 ? sim(q, q - 1) : 1.0);
      bool joined = false;
      for (auto& node : nodes) {
        if (q - node.front() <= search.min_gap) continue;
        const double first = sim(q, node.front());
        ++first_sims;
        if (!(first > search.nodes.alpha * base)) continue;
        ++scanned_nodes;
        double sum = first, bound[3] = {first, first, first};
        for (std::size_t m = 1; m < node.size(); ++m) {
          sum += sim(q, node[m]);
          for (int g = 0; g < 3; ++g) {
            bound[g] += upper_bound(coarse_route[g][at(q)], coarse_route[g][at(node[m])], cells);
          }
        }
        const auto members = static_cast<std::int64_t>(node.size()) - 1;
        member_sims += members;
        const double size = static_cast<double>(node.size());
        for (int g = 0; g < 3; ++g) {
          if (!(bound[g] / size > search.nodes.beta * base)) saved[g] += members;
        }
        if (sum / size > search.nodes.beta * base) {
          accepting_members += members;
          node.push_back(q);
          joined = true;
          break;
        }
      }
      if (!joined) nodes.push_back({q});
    }
    std::printf("frames %lld, nodes %zu\n", static_cast<long long>(frames), nodes.size());
    std::printf(
        "per query: %.1f first-frame similarities, %.1f nodes scanned, %.1f member "
        "similarities (%.1f of them in the node the query joins)\n",
        static_cast<double>(first_sims) / n, static_cast<double>(scanned_nodes) / n,
        static_cast<double>(member_sims) / n, static_cast<double>(accepting_members) / n);
    for (int g = 0; g < 3; ++g) {
      std::printf("bound from %d coarse bins: %.1f %% of member similarities skippable\n",
                  lsgd::kBins / kGroups[g],
                  member_sims ? 100.0 * static_cast<double>(saved[g]) / member_sims : 0.0);
    }
  }

  // DynamicNodes itself in both storages: similarities spent per query and
  // wall time of assign() alone (no segmentation, no verification), once
  // with the queries back to back (the node scanned last is still in cache)
  // and once "cold": 64 MiB written before every query (untimed), so the
  // stored frames come from memory, as in a pipeline where segmentation and
  // the rest of the robot's work run between two queries.
  std::vector<char> flush(std::size_t{64} << 20);
  for (const bool cold : {false, true})
    for (const lsgd::HistogramStorage storage :
         {lsgd::HistogramStorage::kExact, lsgd::HistogramStorage::kCompact}) {
      std::vector<lsgd::Descriptor> stored(route.size());
      for (std::size_t i = 0; i < route.size(); ++i) {
        if (storage == lsgd::HistogramStorage::kCompact) {
          lsgd::compact(route[i], stored[i]);
        } else {
          stored[i] = route[i];
        }
      }
      lsgd::SearchOptions o = search;
      o.mode = lsgd::SearchMode::kDynamicNodes;
      lsgd::FrameStore store;
      lsgd::DynamicNodes dn;
      std::vector<lsgd::Candidate> scratch, out;
      std::int64_t spent = 0;
      std::vector<double> ms;
      for (std::int64_t q = 0; q < frames; ++q) {
        const lsgd::DescriptorView query = stored[at(q)].view();
        if (cold) std::fill(flush.begin(), flush.end(), static_cast<char>(q));
        const auto t0 = std::chrono::steady_clock::now();
        const auto outcome =
            dn.assign(store, query, q, o, lsgd::SimilarityMetric::kReference, scratch, out);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        spent += outcome.similarities;
        store.add(stored[at(q)], outcome.node);  // as the detector does
      }
      std::sort(ms.begin(), ms.end());
      std::printf(
          "DynamicNodes, %s storage, %s: %lld nodes, %.1f similarities per query, "
          "assign() median %.3f ms\n",
          lsgd::to_string(storage), cold ? "cold caches" : "back to back",
          static_cast<long long>(dn.size()), static_cast<double>(spent) / n, ms[ms.size() / 2]);
    }
  return 0;
}
