// Small helpers shared by the unit tests: a deterministic random generator,
// gray test images and a way to read the message of an expected exception.
// Header-only; every generator is deterministic, so tests stay reproducible.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/image.h"
#include "lsgd/segmentation.h"

namespace lsgd::test {

// SplitMix64: advances `state` and returns the next 64-bit pseudo-random value.
// A test program's scratch folder (or file), removed when the program ends
// (a global environment's TearDown, after the last test, passed or failed):
// one folder per process otherwise piles up in the build tree, a few hundred
// MB over a day of ctest runs. Call it at namespace scope:
//   const fs::path kTmp = test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ...);
inline std::filesystem::path removed_at_exit(std::filesystem::path path) {
  class Remove final : public ::testing::Environment {
   public:
    explicit Remove(std::filesystem::path p) : path_(std::move(p)) {}
    void TearDown() override {
      std::error_code ignored;  // nothing to remove, or already removed: fine
      std::filesystem::remove_all(path_, ignored);
    }

   private:
    std::filesystem::path path_;
  };
  ::testing::AddGlobalTestEnvironment(new Remove(path));  // gtest owns it
  return path;
}

// The lines of a CSV file split at its commas (the tests' tables hold no
// quoted fields); none when the file cannot be read.
inline std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::stringstream s(line);
    for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
    rows.push_back(std::move(fields));
  }
  return rows;
}

// The running test's full name as part of a file name ("Suite.Name", or
// "Prefix_Suite.Name_3" for a parameter): a file named with it is the test's
// own when ctest runs tests in parallel, each in its own process.
inline std::string test_file_tag() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  if (info == nullptr) return "no_test";
  std::string tag = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : tag) {
    if (c == '/') c = '_';
  }
  return tag;
}

inline std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Gray image of uniform noise: pixel i (row-major) is the low byte of the
// i-th splitmix64 value drawn from `seed`.
inline GrayImage random_image(int width, int height, std::uint64_t seed) {
  GrayImage g;
  g.width = width;
  g.height = height;
  g.pixels.resize(static_cast<std::size_t>(width) * height);
  std::uint64_t s = seed;
  for (auto& p : g.pixels) p = static_cast<std::uint8_t>(splitmix64(s) & 0xFF);
  return g;
}

// Expects two segmentations to be identical: grid, size, every label and
// every centre (floats compared exactly).
inline void expect_same_segmentation(const Segmentation& a, const Segmentation& b) {
  EXPECT_EQ(a.grid, b.grid);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.labels, b.labels);
  ASSERT_EQ(a.centres.size(), b.centres.size());
  for (std::size_t k = 0; k < a.centres.size(); ++k) {
    EXPECT_EQ(a.centres[k].x, b.centres[k].x) << k;
    EXPECT_EQ(a.centres[k].y, b.centres[k].y) << k;
    EXPECT_EQ(a.centres[k].intensity, b.centres[k].intensity) << k;
    EXPECT_EQ(a.centres[k].pixels, b.centres[k].pixels) << k;
  }
}

// Two-level checkerboard: 7 columns x 5 rows of tiles, alternately 0 and 255.
inline GrayImage two_level_image(int width, int height) {
  GrayImage img;
  img.width = width;
  img.height = height;
  img.pixels.resize(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      img.pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>(((x * 7 / width + y * 5 / height) % 2) * 255);
    }
  }
  return img;
}

// Segmentations of two_level_image(w, h) where, in the last iteration, some
// pixels lie outside every centre's window and join the nearest centre (found
// by instrumenting the segmenter; the tests check they still occur).
struct UnreachedPixelCase {
  int w, h, sp, iterations;
  double intensity_scale;
};
inline constexpr UnreachedPixelCase kUnreachedPixelCases[] = {
    {31, 25, 4, 8, 20.0}, {34, 27, 5, 7, 20.0}, {32, 37, 5, 8, 0.001},
    {11, 37, 5, 9, 2.3},  {36, 8, 2, 8, 20.0},  {26, 15, 4, 8, 20.0}};

// Exact descriptor of one row of cells, each cell given as (bin, count) pairs
// (a bin may repeat: counts add up).
inline Descriptor make_descriptor(const std::vector<std::vector<std::pair<int, Count>>>& cells) {
  Descriptor d;
  d.grid = {1, static_cast<int>(cells.size())};
  d.hist.assign(cells.size() * kBins, 0);
  d.pixels.assign(cells.size(), 0);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    for (const auto& [bin, count] : cells[k]) {
      d.hist[k * kBins + bin] = static_cast<Bin>(d.hist[k * kBins + bin] + count);
      d.pixels[k] += count;
    }
  }
  return d;
}

// Gray image whose pixels all equal `value`.
inline GrayImage uniform_image(int width, int height, std::uint8_t value) {
  GrayImage g;
  g.width = width;
  g.height = height;
  g.pixels.assign(static_cast<std::size_t>(width) * height, value);
  return g;
}

// Runs `f` and returns the what() of the exception of type E it throws,
// "<other exception>" if it throws anything else, "<no exception>" if it
// returns normally.
template <class E, class F>
std::string message_of(F&& f) {
  try {
    std::forward<F>(f)();
  } catch (const E& e) {
    return e.what();
  } catch (...) {
    return "<other exception>";
  }
  return "<no exception>";
}

// Expects `call` to throw E with a message containing every one of `parts`.
template <typename E, typename F>
void expect_error(F call, const std::vector<std::string>& parts) {
  try {
    call();
    ADD_FAILURE() << "no exception thrown";
  } catch (const E& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "message '" << e.what() << "' lacks '" << part << "'";
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

}  // namespace lsgd::test
