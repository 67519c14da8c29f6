// lsgd bench --distractors N: a sequence hidden among N distractor frames,
// so that searches over large maps are measured without rendering millions
// of images (tools/lsgd/bench_distractors.cc says how distractors are made).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common.h"

namespace lsgd::cli::bench {

struct DistractorSetup {
  std::int64_t distractors = 0;  // N
  std::int64_t run = 1;          // distractors per run (one layout and lighting; 1: each its own)
  std::string sequence;          // empty: the synthetic street
  std::string gt;                // --sequence's loop ground truth (any lsgd eval format); empty: none
  io::SequenceOptions layout;    // how `sequence` is read
  std::int64_t frames = 1090;    // synthetic street: frames (route frame i % 1090)
  int width = 1241, height = 376;
  std::uint64_t seed = 1;
  std::vector<std::string> modes;  // empty: every registered mode but nodes
  std::string json;
};

// Runs every mode over the same distractors and sequence (exhaustive first,
// the reference of recall_vs_exhaustive), prints a table, writes the JSON.
void run_distractors(const DistractorSetup& setup, const DetectorOptions& options);

}  // namespace lsgd::cli::bench
