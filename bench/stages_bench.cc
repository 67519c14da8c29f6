// Per-stage micro-benchmarks of the lsgd pipeline (Google Benchmark).
//
//   cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
//   cmake --build build -j2 --target lsgd_stages_bench
//   build/bench/lsgd_stages_bench --benchmark_min_time=0.2
//
// Images are generated in code with fixed seeds: a smooth procedural texture
// (low-frequency sinusoids, soft blobs and hard-edged "facades" with windows)
// plus Gaussian sensor noise, never pure noise. Stored frames for the search
// benchmarks are built from a few real descriptors (segmented and described
// images of distinct procedural "places") interpolated along a looping route
// and perturbed per frame, so the store has realistic, non-identical
// histograms without segmenting thousands of images during setup.
//
// Large stores are off by default (memory and setup time). Add them with
//   build/bench/lsgd_stages_bench --lsgd_large --benchmark_filter=SearchExhaustive
// which registers BM_SearchExhaustive/cells20_320x240 at 20000 and 100000
// frames (20-cell descriptors of 10,320 bytes: 206 MB and 1.03 GB; compact:
// 2,560 bytes) and cells80_1241x376 at 20000 frames (41,280 bytes each:
// 826 MB; compact 10,240 bytes); it also adds
// BM_DynamicNodes/cells80_1241x376 at 1000 and 5000 frames (node setup takes
// about a minute, see below). Select any subset with --benchmark_filter=REGEX.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/evidence.h"
#include "lsgd/frame_store.h"
#include "lsgd/geometric.h"
#include "lsgd/image.h"
#include "lsgd/search.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/segmentation.h"
#include "lsgd/similarity.h"
#include "lsgd/verification.h"
#include "search/index_key.h"
#include "stages_bench_data.h"

namespace {

using stages_bench::describe_image;
using stages_bench::kKitti;
using stages_bench::kSmall;
using stages_bench::make_bgr;
using stages_bench::places;
using stages_bench::route_query;
using stages_bench::route_store;
using stages_bench::Size;
using stages_bench::size_label;

// ---------------------------------------------------------------- image stages

void BM_ToGray(benchmark::State& state, Size size) {
  const cv::Mat bgr = make_bgr(size.width, size.height, 1);
  lsgd::GrayImage gray;
  for (auto _ : state) {
    lsgd::to_gray(bgr, gray);
    benchmark::DoNotOptimize(gray.pixels.data());
    benchmark::ClobberMemory();
  }
  const std::int64_t pixels = static_cast<std::int64_t>(size.width) * size.height;
  state.SetItemsProcessed(state.iterations() * pixels);
  state.SetBytesProcessed(state.iterations() * pixels * 3);
}

void BM_Segment(benchmark::State& state, Size size) {
  const lsgd::GrayImage gray = lsgd::to_gray(make_bgr(size.width, size.height, 1));
  lsgd::Segmenter segmenter;  // default options: S_p 40, 3 iterations
  lsgd::Segmentation seg;     // reused across frames, as the detector does
  for (auto _ : state) {
    segmenter.segment(gray, seg);
    benchmark::DoNotOptimize(seg.labels.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * size.width * size.height);
  state.counters["cells"] = seg.grid.cells();
}

void BM_Describe(benchmark::State& state, Size size) {
  const lsgd::GrayImage gray = lsgd::to_gray(make_bgr(size.width, size.height, 1));
  lsgd::Segmenter segmenter;
  const lsgd::Segmentation seg = segmenter.segment(gray);
  lsgd::Descriptor desc;
  for (auto _ : state) {
    lsgd::describe(gray, seg, desc);
    benchmark::DoNotOptimize(desc.hist.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * size.width * size.height);
  state.counters["cells"] = desc.grid.cells();
}

// The detector's path: histograms counted in the segmentation's last pass.
void BM_SegmentAndDescribe(benchmark::State& state, Size size) {
  const lsgd::GrayImage gray = lsgd::to_gray(make_bgr(size.width, size.height, 1));
  lsgd::Segmenter segmenter;
  lsgd::Segmentation seg;
  lsgd::Descriptor desc;
  lsgd::DescribeScratch scratch;
  for (auto _ : state) {
    lsgd::segment_and_describe(segmenter, gray, seg, desc, scratch);
    benchmark::DoNotOptimize(desc.hist.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * size.width * size.height);
  state.counters["cells"] = desc.grid.cells();
}

// ---------------------------------------------------------------- similarity

void BM_Similarity(benchmark::State& state, lsgd::SimilarityMetric metric,
                   lsgd::HistogramStorage storage) {
  const auto& base = places(kKitti);  // two real 80-cell descriptors
  lsgd::Descriptor ca, cb;
  if (storage == lsgd::HistogramStorage::kCompact) {
    lsgd::compact(base[0], ca);
    lsgd::compact(base[1], cb);
  }
  const bool compact = storage == lsgd::HistogramStorage::kCompact;
  const lsgd::DescriptorView a = compact ? ca.view() : base[0].view();
  const lsgd::DescriptorView b = compact ? cb.view() : base[1].view();
  double score = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(a.hist);
    score = lsgd::similarity(a, b, metric);
    benchmark::DoNotOptimize(score);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(
      state.iterations() * 2 *
      static_cast<std::int64_t>(lsgd::Descriptor::bytes_per_frame(storage, a.cells)));
}

// similarities(): 64 stored route frames (in cache) scored against one query
// in a single call, per frame; beside BM_Similarity's one call per pair.
void BM_Similarities(benchmark::State& state, lsgd::HistogramStorage storage) {
  constexpr std::int64_t kFrames = 64;
  const lsgd::FrameStore& store = route_store(kKitti, kFrames, storage);
  const lsgd::Descriptor query = route_query(kKitti, kFrames, storage);
  std::vector<lsgd::DescriptorView> views;
  for (std::int64_t j = 0; j < kFrames; ++j) views.push_back(store.view(j));
  std::vector<double> scores(views.size());
  for (auto _ : state) {
    lsgd::similarities(query.view(), views.data(), views.size(), lsgd::SimilarityMetric::kReference,
                       scores.data());
    benchmark::DoNotOptimize(scores.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kFrames);
  state.SetBytesProcessed(state.iterations() * kFrames *
                          static_cast<std::int64_t>(store.bytes_per_frame()));
}

// ---------------------------------------------------------------- memory

// The ceiling for a search: a single core reading 10,240-byte blocks (one
// compact KITTI-size frame) out of a 186 MB buffer (4 x 4541 blocks, far
// beyond the L3 cache), summed with no other work. /sequential reads all of
// it in order; /scattered reads 1784 sorted random blocks per iteration (a
// dynamic-node query's member count), from a fresh draw each time, so they
// come from DRAM. Bytes per second = the bandwidth a search can hope for.
void BM_MemoryRead(benchmark::State& state, bool scattered) {
  constexpr std::size_t kBlock = 10240, kBlocks = 4 * 4541, kPicked = 1784;
  static std::vector<std::uint64_t> buffer(kBlock * kBlocks / 8, 1);
  std::mt19937 rng(7);
  std::vector<std::uint32_t> all(kBlocks), picked(kPicked);
  for (std::size_t i = 0; i < kBlocks; ++i) all[i] = static_cast<std::uint32_t>(i);
  std::uint64_t total = 0;
  const auto sum_block = [&](std::size_t block, std::size_t count) {
    const std::uint64_t* p = buffer.data() + block * (kBlock / 8);
    std::uint64_t a = 0, b = 0, c = 0, d = 0;
    for (std::size_t i = 0; i < count * (kBlock / 8); i += 4) {
      a += p[i], b += p[i + 1], c += p[i + 2], d += p[i + 3];
    }
    return a + b + c + d;
  };
  std::int64_t bytes = 0;
  for (auto _ : state) {
    if (scattered) {
      state.PauseTiming();
      for (std::size_t i = 0; i < kPicked; ++i) {
        std::swap(all[i], all[i + rng() % (kBlocks - i)]);
      }
      std::copy(all.begin(), all.begin() + kPicked, picked.begin());
      std::sort(picked.begin(), picked.end());
      state.ResumeTiming();
      for (std::uint32_t block : picked) total += sum_block(block, 1);
      bytes += static_cast<std::int64_t>(kPicked * kBlock);
    } else {
      total += sum_block(0, kBlocks);
      bytes += static_cast<std::int64_t>(kBlocks * kBlock);
    }
    benchmark::DoNotOptimize(total);
  }
  state.SetBytesProcessed(bytes);
}

// ---------------------------------------------------------------- search

void BM_SearchExhaustive(benchmark::State& state, Size size, lsgd::HistogramStorage storage) {
  const std::int64_t frames = state.range(0);
  const lsgd::FrameStore& store = route_store(size, frames, storage);
  const lsgd::Descriptor query = route_query(size, frames / 2, storage);
  lsgd::SearchOptions options;  // defaults: min_gap 50, top_n 10
  // query_id = frames + min_gap: exactly the first `frames` frames are scanned.
  const std::int64_t query_id = frames + options.min_gap;
  std::vector<lsgd::Candidate> scratch, out;
  for (auto _ : state) {
    lsgd::search_exhaustive(store, query.view(), query_id, options,
                            lsgd::SimilarityMetric::kReference, scratch, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * frames);
  state.SetBytesProcessed(state.iterations() * frames *
                          static_cast<std::int64_t>(store.bytes_per_frame()));
  state.counters["MB_stored"] =
      static_cast<double>(frames) * static_cast<double>(store.bytes_per_frame()) / 1e6;
}

// The node structure the detector would build over the first `frames` route
// frames: assign() run over every frame in order, each frame stored after its
// assignment. Built once per size, incrementally (the 1000-frame setup is a
// prefix of the 5000-frame one), and snapshotted per frame count, so Google
// Benchmark's repeated calls of the benchmark function do not rebuild it.
struct NodesSetup {
  lsgd::FrameStore store;  // exactly `frames` frames: the query is frame `frames`
  lsgd::DynamicNodes nodes;
};

const NodesSetup& nodes_setup(Size size, std::int64_t frames, const lsgd::SearchOptions& options,
                              lsgd::SimilarityMetric metric, lsgd::HistogramStorage storage) {
  struct Builder {
    NodesSetup state;
    std::map<std::int64_t, NodesSetup> snapshots;
  };
  static std::map<std::pair<int, lsgd::HistogramStorage>, Builder> builders;
  Builder& b = builders[{size.width * 100000 + size.height, storage}];
  auto it = b.snapshots.find(frames);
  if (it != b.snapshots.end()) return it->second;
  const lsgd::FrameStore& full = route_store(size, frames, storage);
  std::vector<lsgd::Candidate> scratch, out;
  lsgd::Descriptor d;
  d.grid = full.grid();
  d.storage = storage;
  for (std::int64_t j = b.state.store.size(); j < frames; ++j) {
    const lsgd::DescriptorView v = full.view(j);
    const auto outcome = b.state.nodes.assign(b.state.store, v, j, options, metric, scratch, out);
    if (storage == lsgd::HistogramStorage::kCompact) {
      d.compact.assign(v.compact,
                       v.compact + static_cast<std::size_t>(v.cells) * lsgd::kCompactBins);
      d.cell_pixels = v.cell_pixels;
    } else {
      d.hist.assign(v.hist, v.hist + static_cast<std::size_t>(v.cells) * lsgd::kBins);
      d.pixels.assign(v.pixels, v.pixels + v.cells);
    }
    b.state.store.add(d, outcome.node);  // a node's frames together, as the detector does
  }
  return b.snapshots.emplace(frames, b.state).first->second;
}

void BM_DynamicNodes(benchmark::State& state, Size size, lsgd::HistogramStorage storage) {
  const std::int64_t frames = state.range(0);
  lsgd::SearchOptions options;  // defaults: min_gap 50, top_n 10, reference thresholds
  options.mode = lsgd::kNodesSearch;
  const auto metric = lsgd::SimilarityMetric::kReference;
  const NodesSetup& setup = nodes_setup(size, frames, options, metric, storage);  // untimed
  // The query continues the route: its previous frame is the last stored one.
  const lsgd::Descriptor query = route_query(size, frames, storage);
  std::vector<lsgd::Candidate> scratch, out;
  lsgd::DynamicNodes::Outcome outcome;
  for (auto _ : state) {
    state.PauseTiming();
    lsgd::DynamicNodes trial = setup.nodes;  // assign() mutates the nodes: start fresh
    state.ResumeTiming();
    outcome = trial.assign(setup.store, query.view(), frames, options, metric, scratch, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["nodes"] = static_cast<double>(setup.nodes.size());
  state.counters["sims"] = static_cast<double>(outcome.similarities);
  state.counters["created"] = outcome.created ? 1 : 0;
}

// The temporal stage's per-query work in exhaustive search (evidence.h):
// standardising the similarity row of a query over `frames` stored frames,
// updating the 16- and 48-frame diagonal sums, the sequence statistics and
// the best distinct places. The similarity row itself (the search) is not
// timed.
void BM_AppearanceEvidence(benchmark::State& state) {
  const std::int64_t frames = state.range(0);
  lsgd::FrameStore store;
  lsgd::SearchOptions options;
  const auto metric = lsgd::SimilarityMetric::kReference;
  std::vector<lsgd::Candidate> scratch, raw, out;
  std::vector<std::vector<double>> rows;
  {
    const lsgd::FrameStore& route = route_store(kKitti, frames + 1);  // untimed
    lsgd::Descriptor d;
    for (std::int64_t j = 0; j <= frames; ++j) {
      const lsgd::DescriptorView v = route.view(j);
      d.grid = route.grid();
      d.hist.assign(v.hist, v.hist + static_cast<std::ptrdiff_t>(v.cells) * lsgd::kBins);
      d.pixels.assign(v.pixels, v.pixels + v.cells);
      rows.emplace_back();
      lsgd::search_exhaustive(store, d.view(), j, options, metric, scratch, raw, &rows.back());
      store.add(d);
    }
  }
  // Warm: every query but the last; each iteration adds the last one to a copy.
  lsgd::AppearanceEvidence warm({}, options.min_gap, false);
  lsgd::FrameStore prefix;
  for (std::int64_t j = 0; j < frames; ++j) {
    warm.add_query(prefix, store.view(j), j, metric, &rows[static_cast<std::size_t>(j)]);
    lsgd::Descriptor d;
    const lsgd::DescriptorView v = store.view(j);
    d.grid = store.grid();
    d.hist.assign(v.hist, v.hist + static_cast<std::ptrdiff_t>(v.cells) * lsgd::kBins);
    d.pixels.assign(v.pixels, v.pixels + v.cells);
    prefix.add(d);
  }
  for (auto _ : state) {
    state.PauseTiming();
    lsgd::AppearanceEvidence trial = warm;
    state.ResumeTiming();
    trial.add_query(prefix, store.view(frames), frames, metric, &rows.back());
    trial.best_places(options.top_n, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
}

// ---------------------------------------------------------------- index

// The index's graph distance between two frames' keys (search/index_key.h),
// the work of most of an insertion: keys of 4,096 route frames at KITTI size
// (80 cells, 1,280 bytes each, 5 MB: in cache, so this is its compute),
// each iteration one distance between consecutive pairs of a shuffled order.
void BM_IndexKeyDistance(benchmark::State& state) {
  constexpr std::int64_t kKeys = 4096;
  const lsgd::FrameStore& route = route_store(kKitti, kKeys, lsgd::HistogramStorage::kCompact);
  const int cells = route.view(0).cells;
  const std::size_t bytes = static_cast<std::size_t>(cells) * lsgd::internal::kKeyBins;
  std::vector<std::uint8_t> keys(bytes * kKeys);
  for (std::int64_t j = 0; j < kKeys; ++j) {
    lsgd::internal::make_key(route.view(j), keys.data() + static_cast<std::size_t>(j) * bytes);
  }
  std::vector<std::size_t> order(kKeys);
  for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  const lsgd::internal::KeySpaceParam param{cells, /*sqrt=*/true};  // the reference metric
  std::size_t k = 0;
  for (auto _ : state) {
    const float d = lsgd::internal::key_distance(keys.data() + order[k] * bytes,
                                                 keys.data() + order[(k + 1) % kKeys] * bytes, &param);
    benchmark::DoNotOptimize(d);
    k = (k + 1) % kKeys;
  }
  state.SetItemsProcessed(state.iterations());
}

// ---------------------------------------------------------------- geometric

void BM_GeometricAdd(benchmark::State& state) {
  const lsgd::GrayImage images[2] = {lsgd::to_gray(make_bgr(kSmall.width, kSmall.height, 5, 0)),
                                     lsgd::to_gray(make_bgr(kSmall.width, kSmall.height, 5, 12))};
  auto verifier = std::make_unique<lsgd::GeometricVerifier>();
  std::int64_t i = 0;
  for (auto _ : state) {
    verifier->add(images[i++ & 1]);
    if (verifier->size() >= 512) {  // bound memory over long runs
      state.PauseTiming();
      verifier = std::make_unique<lsgd::GeometricVerifier>();
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["keypoints"] = verifier->size() > 0 ? verifier->keypoints(0) : 0;
}

void BM_GeometricVerify(benchmark::State& state) {
  lsgd::GeometricVerifier verifier;
  verifier.add(lsgd::to_gray(make_bgr(kSmall.width, kSmall.height, 5, 0)));
  verifier.add(lsgd::to_gray(make_bgr(kSmall.width, kSmall.height, 5, 12)));  // 12 px pan
  lsgd::GeometricCheck check;
  for (auto _ : state) {
    check = verifier.verify(1, 0);
    benchmark::DoNotOptimize(check.inliers);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["matches"] = check.matches;
  state.counters["inliers"] = check.inliers;
  state.counters["accepted"] = check.accepted ? 1 : 0;
}

// Every benchmark and its arguments, one registration after another (95 lines:
// a table, read as the list of what is measured; nothing to split out).
void register_all(bool large) {
  for (Size s : {kKitti, kSmall}) {
    const std::string label = std::to_string(s.width) + "x" + std::to_string(s.height);
    benchmark::RegisterBenchmark(("BM_ToGray/" + label).c_str(), BM_ToGray, s)
        ->Unit(benchmark::kMicrosecond);
  }
  for (Size s : {kKitti, kSmall}) {
    const std::string label = std::to_string(s.width) + "x" + std::to_string(s.height);
    benchmark::RegisterBenchmark(("BM_Segment/" + label).c_str(), BM_Segment, s)
        ->Unit(benchmark::kMillisecond);
  }
  for (Size s : {kKitti, kSmall}) {
    const std::string label = std::to_string(s.width) + "x" + std::to_string(s.height);
    benchmark::RegisterBenchmark(("BM_Describe/" + label).c_str(), BM_Describe, s)
        ->Unit(benchmark::kMicrosecond);
  }
  for (Size s : {kKitti, kSmall}) {
    const std::string label = std::to_string(s.width) + "x" + std::to_string(s.height);
    benchmark::RegisterBenchmark(("BM_SegmentAndDescribe/" + label).c_str(), BM_SegmentAndDescribe,
                                 s)
        ->Unit(benchmark::kMillisecond);
  }
  using lsgd::HistogramStorage;
  for (auto metric : {lsgd::SimilarityMetric::kReference, lsgd::SimilarityMetric::kL1,
                      lsgd::SimilarityMetric::kNormalizedL1}) {
    benchmark::RegisterBenchmark(
        ("BM_Similarity/cells80/" + std::string(lsgd::to_string(metric))).c_str(), BM_Similarity,
        metric, HistogramStorage::kExact)
        ->Unit(benchmark::kMicrosecond);
  }
  for (auto metric : {lsgd::SimilarityMetric::kReference, lsgd::SimilarityMetric::kL1}) {
    benchmark::RegisterBenchmark(
        ("BM_Similarity/cells80/" + std::string(lsgd::to_string(metric)) + "/compact").c_str(),
        BM_Similarity, metric, HistogramStorage::kCompact)
        ->Unit(benchmark::kMicrosecond);
  }
  for (HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    const std::string suffix = storage == HistogramStorage::kCompact ? "/compact" : "";
    benchmark::RegisterBenchmark(
        ("BM_Similarities/cells80/reference" + suffix + "/64_frames").c_str(), BM_Similarities,
        storage)
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::RegisterBenchmark("BM_MemoryRead/sequential", BM_MemoryRead, false)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("BM_MemoryRead/scattered_10240B_blocks", BM_MemoryRead, true)
      ->Unit(benchmark::kMillisecond);
  // Exact and compact storage side by side (name suffix /compact).
  for (HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    const std::string suffix = storage == HistogramStorage::kCompact ? "/compact" : "";
    auto* exhaustive =
        benchmark::RegisterBenchmark(("BM_SearchExhaustive/" + size_label(kKitti) + suffix).c_str(),
                                     BM_SearchExhaustive, kKitti, storage);
    exhaustive->ArgName("frames")->Arg(1000)->Arg(5000)->Unit(benchmark::kMillisecond);
    if (large) {
      exhaustive->Arg(20000);
      benchmark::RegisterBenchmark(("BM_SearchExhaustive/" + size_label(kSmall) + suffix).c_str(),
                                   BM_SearchExhaustive, kSmall, storage)
          ->ArgName("frames")
          ->Arg(20000)
          ->Arg(100000)
          ->Unit(benchmark::kMillisecond);
    }
  }
  // 20-cell (320x240) descriptors: building the node structure is quadratic in
  // the number of frames (with the reference thresholds every node passes the
  // first-frame test at these cell sizes), ~4x cheaper than with 80 cells.
  for (HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    const std::string suffix = storage == HistogramStorage::kCompact ? "/compact" : "";
    benchmark::RegisterBenchmark(("BM_DynamicNodes/" + size_label(kSmall) + suffix).c_str(),
                                 BM_DynamicNodes, kSmall, storage)
        ->ArgName("frames")
        ->Arg(1000)
        ->Arg(5000)
        ->Unit(benchmark::kMicrosecond);
    if (large) {
      benchmark::RegisterBenchmark(("BM_DynamicNodes/" + size_label(kKitti) + suffix).c_str(),
                                   BM_DynamicNodes, kKitti, storage)
          ->ArgName("frames")
          ->Arg(1000)
          ->Arg(5000)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  benchmark::RegisterBenchmark(
      ("BM_AppearanceEvidence/" + size_label(kKitti)).c_str(), BM_AppearanceEvidence)
      ->Arg(1000)
      ->Arg(5000)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("BM_IndexKeyDistance/" + size_label(kKitti)).c_str(), BM_IndexKeyDistance);
  benchmark::RegisterBenchmark("BM_GeometricAdd/320x240", BM_GeometricAdd)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("BM_GeometricVerify/320x240", BM_GeometricVerify)
      ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  // Our own flag, removed before Google Benchmark parses the rest.
  bool large = false;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--lsgd_large") == 0) {
      large = true;
    } else {
      argv[kept++] = argv[i];
    }
  }
  argc = kept;
  register_all(large);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
