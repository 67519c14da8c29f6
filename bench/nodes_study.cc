// Where the dynamic-node search spends its similarities, and how much of it an
// exact lower bound on L1 from coarser histograms could skip; then how long
// DynamicNodes::assign takes depending on what the CPU did between queries.
//
//   build/bench/lsgd_nodes_study [frames] [--timing-only]
//       [--between none,flush,render,busy,sleep] [--storage exact,compact]
//     (default 4541 frames, --between none,flush, both storages: ~2 min, or
//     ~1 min with --timing-only, which skips the bound analysis; render adds
//     ~100 s per storage)
//
// The sequence is `lsgd bench`'s: 1241x376 frames of the synthetic street,
// frame i showing route frame i % 1090, default detector options (S_p = 40,
// 80 cells, reference metric and thresholds, min_gap 50). It runs Algorithm 1
// as DynamicNodes::assign does (written out, to see inside it; checked: the
// study fails unless assign() then builds the very same nodes) and, for every
// node whose members are
// scored, also computes for every member an upper bound on its similarity from
// histograms merged into 32, 16 or 8 coarse bins (merging bins never increases
// L1, so the bound is exact). A node whose bound on the mean stays at or below
// beta * base could be rejected without scoring its members. It prints the
// similarities spent per query and the share a bound would have saved, then
// runs DynamicNodes::assign itself on the same frames, storing each frame in
// its node's group as the detector does, and prints its median time per
// query for each storage and each of these, done (untimed) before every query:
//   none    nothing: the node scanned last may still be in the caches;
//   flush   64 MiB written: the stored frames come from memory;
//   render  render, convert and segment the next frame, as `lsgd bench` does
//           between two queries (~22 ms);
//   busy    flush, then 20 ms of arithmetic that touches no memory;
//   sleep   flush, then 20 ms asleep.
// busy and sleep separate the cache contents from time without memory
// traffic, which on some machines lowers the read rate of the next query.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>
#include <vector>

#include "lsgd/descriptor.h"
#include "synthetic/synthetic.h"
#include "lsgd/frame_store.h"
#include "lsgd/image.h"
#include "lsgd/search.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"
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

enum class Between { kNone, kFlush, kRender, kBusy, kSleep };

const char* name(Between b) {
  switch (b) {
    case Between::kNone:
      return "none (back to back)";
    case Between::kFlush:
      return "flush (64 MiB written)";
    case Between::kRender:
      return "render (render + segment the next frame)";
    case Between::kBusy:
      return "busy (flush, 20 ms arithmetic)";
    case Between::kSleep:
      return "sleep (flush, 20 ms asleep)";
  }
  return "?";
}

// Splits "a,b,c" and maps each item through `parse`; false on an unknown one.
template <typename T, typename Parse>
bool parse_list(const std::string& list, Parse parse, std::vector<T>& out) {
  out.clear();
  std::size_t at = 0;
  while (at <= list.size()) {
    const std::size_t end = std::min(list.find(',', at), list.size());
    T value{};
    if (!parse(list.substr(at, end - at), value)) return false;
    out.push_back(value);
    at = end + 1;
  }
  return !out.empty();
}

bool parse_between(const std::string& s, Between& b) {
  const std::pair<const char*, Between> names[] = {{"none", Between::kNone},
                                                   {"flush", Between::kFlush},
                                                   {"render", Between::kRender},
                                                   {"busy", Between::kBusy},
                                                   {"sleep", Between::kSleep}};
  for (const auto& [n, v] : names) {
    if (s == n) return b = v, true;
  }
  return false;
}

bool parse_storage(const std::string& s, lsgd::HistogramStorage& storage) {
  if (s != "exact" && s != "compact") return false;
  storage = lsgd::parse_histogram_storage(s.c_str());
  return true;
}

// The study's settings, from the command line.
struct Settings {
  std::int64_t frames = 4541;
  bool timing_only = false;
  std::vector<Between> between = {Between::kNone, Between::kFlush};
  std::vector<lsgd::HistogramStorage> storages = {lsgd::HistogramStorage::kExact,
                                                  lsgd::HistogramStorage::kCompact};
};

bool parse_settings(int argc, char** argv, Settings& s) {
  bool ok = true;
  for (int i = 1; i < argc && ok; ++i) {
    const std::string arg = argv[i];
    if (arg == "--timing-only") {
      s.timing_only = true;
    } else if (arg == "--between" && i + 1 < argc) {
      ok = parse_list<Between>(argv[++i], parse_between, s.between);
    } else if (arg == "--storage" && i + 1 < argc) {
      ok = parse_list<lsgd::HistogramStorage>(argv[++i], parse_storage, s.storages);
    } else if (i == 1 && std::atoll(argv[1]) >= 1) {
      s.frames = std::atoll(argv[1]);
    } else {
      ok = false;
    }
  }
  return ok;
}

// The route's distinct frames described once (frame i repeats route frame
// i % 1090), with their coarse histograms unless only timing.
struct Route {
  std::vector<lsgd::Descriptor> frames;
  std::vector<std::vector<std::uint32_t>> coarse[3];
  std::int64_t distinct = 0;
  std::size_t at(std::int64_t i) const { return static_cast<std::size_t>(i % distinct); }
  double sim(std::int64_t a, std::int64_t b) const {
    return lsgd::similarity(frames[at(a)].view(), frames[at(b)].view(),
                            lsgd::SimilarityMetric::kReference);
  }
};

Route describe_route(const lsgd::eval::SyntheticWorld& world, lsgd::Segmenter& segmenter,
                     const Settings& s) {
  Route r;
  r.distinct = std::min<std::int64_t>(s.frames, world.frames());
  r.frames.resize(static_cast<std::size_t>(r.distinct));
  for (std::int64_t i = 0; i < r.distinct; ++i) {
    cv::Mat gray;
    cv::cvtColor(world.render(i), gray, cv::COLOR_BGR2GRAY);
    const lsgd::GrayImage image = lsgd::to_gray(gray);
    r.frames[static_cast<std::size_t>(i)] = lsgd::describe(image, segmenter.segment(image));
    for (int g = 0; g < 3 && !s.timing_only; ++g) {
      r.coarse[g].push_back(coarse(r.frames[static_cast<std::size_t>(i)], kGroups[g]));
    }
  }
  return r;
}

// The study's Algorithm 1 over the route, counting the similarities it spends
// and those a bound from coarse bins would skip; returns its nodes.
std::vector<std::vector<std::int64_t>> study_algorithm1(const Route& route, const lsgd::SearchOptions& search,
                                                        std::int64_t frames) {
  const int cells = route.frames[0].grid.cells();
  const double n = static_cast<double>(frames);
  std::vector<std::vector<std::int64_t>> nodes;
  std::int64_t first_sims = 0, member_sims = 0, scanned_nodes = 0, accepting_members = 0;
  std::int64_t saved[3] = {0, 0, 0};
  for (std::int64_t q = 0; q < frames; ++q) {
    const double base = search.nodes.threshold_0 * (q > 0 ? route.sim(q, q - 1) : 1.0);
    bool joined = false;
    for (auto& node : nodes) {
      if (q - node.front() <= search.min_gap) continue;
      const double first = route.sim(q, node.front());
      ++first_sims;
      if (!(first > search.nodes.alpha * base)) continue;
      ++scanned_nodes;
      double sum = first, bound[3] = {first, first, first};
      for (std::size_t m = 1; m < node.size(); ++m) {
        sum += route.sim(q, node[m]);
        for (int g = 0; g < 3; ++g) {
          bound[g] += upper_bound(route.coarse[g][route.at(q)], route.coarse[g][route.at(node[m])], cells);
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
  return nodes;
}

// What runs before every query outside the timed part.
struct BeforeQuery {
  const lsgd::eval::SyntheticWorld& world;
  lsgd::Segmenter& segmenter;
  std::vector<char> flush = std::vector<char>(std::size_t{64} << 20);
  std::size_t sink = 0;  // keeps the untimed work from being optimised away

  void operator()(Between b, std::int64_t q) {
    if (b == Between::kNone) return;
    if (b == Between::kRender) {
      cv::Mat gray;
      cv::cvtColor(world.render(q % world.frames()), gray, cv::COLOR_BGR2GRAY);
      sink += segmenter.segment(lsgd::to_gray(gray)).labels.size();
      return;
    }
    std::fill(flush.begin(), flush.end(), static_cast<char>(q));
    if (b == Between::kBusy) {
      const auto t0 = std::chrono::steady_clock::now();
      double x = 1.0;
      while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(20)) {
        for (int r = 0; r < 1000; ++r) x = x * 1.0000001 + 1e-9;
      }
      sink += static_cast<std::size_t>(x);
    } else if (b == Between::kSleep) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
};

// DynamicNodes itself: similarities spent per query and wall time of
// assign() alone (no segmentation, no verification), with `between` done
// before every query outside the timed part. Returns false when its nodes
// are not the study's (`nodes`, when given).
bool time_dynamic_nodes(const Route& route, const lsgd::SearchOptions& search, std::int64_t frames,
                        Between b, lsgd::HistogramStorage storage, BeforeQuery& before_query,
                        const std::vector<std::vector<std::int64_t>>* nodes) {
  std::vector<lsgd::Descriptor> stored(route.frames.size());
  for (std::size_t i = 0; i < route.frames.size(); ++i) {
    if (storage == lsgd::HistogramStorage::kCompact) {
      lsgd::compact(route.frames[i], stored[i]);
    } else {
      stored[i] = route.frames[i];
    }
  }
  lsgd::SearchOptions o = search;
  o.mode = lsgd::kNodesSearch;
  lsgd::FrameStore store;
  lsgd::DynamicNodes dn;
  std::vector<lsgd::Candidate> scratch, out;
  std::int64_t spent = 0;
  std::vector<double> ms;
  for (std::int64_t q = 0; q < frames; ++q) {
    const lsgd::DescriptorView query = stored[route.at(q)].view();
    before_query(b, q);
    const auto t0 = std::chrono::steady_clock::now();
    const auto outcome = dn.assign(store, query, q, o, lsgd::SimilarityMetric::kReference, scratch, out);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    spent += outcome.similarities;
    store.add(stored[route.at(q)], outcome.node);  // as the detector does
  }
  if (nodes != nullptr) {
    bool same = dn.size() == static_cast<std::int64_t>(nodes->size());
    for (std::int64_t k = 0; same && k < dn.size(); ++k) {
      same = dn.members(k) == (*nodes)[static_cast<std::size_t>(k)];
    }
    if (!same) {
      std::fprintf(stderr, "the study's Algorithm 1 (%zu nodes) is not DynamicNodes::assign's "
                   "(%lld nodes): its counts above are wrong\n", nodes->size(),
                   static_cast<long long>(dn.size()));
      return false;
    }
  }
  std::sort(ms.begin(), ms.end());
  std::printf(
      "DynamicNodes, %s storage, between queries %s: %lld nodes, %.1f similarities per "
      "query, assign() median %.3f ms\n",
      lsgd::to_string(storage), name(b), static_cast<long long>(dn.size()),
      static_cast<double>(spent) / static_cast<double>(frames), ms[ms.size() / 2]);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(0);  // as lsgd bench: OpenCV sequential
  Settings s;
  if (!parse_settings(argc, argv, s)) {
    std::fprintf(stderr,
                 "usage: %s [frames >= 1] [--timing-only] [--between "
                 "none,flush,render,busy,sleep] [--storage exact,compact]\n",
                 argv[0]);
    return 2;
  }
  lsgd::eval::SyntheticOptions world_options;
  world_options.width = 1241;
  world_options.height = 376;
  const lsgd::eval::SyntheticWorld world(world_options);
  const lsgd::SearchOptions search;  // defaults: reference thresholds, min_gap 50
  lsgd::Segmenter segmenter{lsgd::SegmentationOptions{}};
  const Route route = describe_route(world, segmenter, s);
  std::vector<std::vector<std::int64_t>> nodes;  // the study's Algorithm 1
  if (!s.timing_only) nodes = study_algorithm1(route, search, s.frames);
  BeforeQuery before_query{world, segmenter};
  for (const Between b : s.between) {
    for (const lsgd::HistogramStorage storage : s.storages) {
      const bool compare = !s.timing_only && storage == lsgd::HistogramStorage::kExact;
      if (!time_dynamic_nodes(route, search, s.frames, b, storage, before_query, compare ? &nodes : nullptr)) {
        return 1;
      }
    }
  }
  std::fprintf(stderr, "%s", before_query.sink == 1 ? " " : "");
  return 0;
}
