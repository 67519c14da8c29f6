// The images and stores lsgd_stages_bench measures on (stages_bench_data.h).
#include "stages_bench_data.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/segmentation.h"

namespace stages_bench {

// ---------------------------------------------------------------- images

// A smooth textured BGR image: sinusoids + soft blobs + hard-edged rectangles
// (facades with windows, so ORB finds corners) + Gaussian noise (sigma 4).
// `shift` moves the camera horizontally over the same scene (seed), so two
// shifts of one seed overlap like consecutive frames.
cv::Mat make_bgr(int width, int height, std::uint32_t seed, int shift) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int scene_w = width + 256;  // scene wider than the view, for shifts
  cv::Mat scene(height, scene_w, CV_32FC1);
  // Low-frequency sinusoids.
  struct Wave {
    double fx, fy, phase, amp;
  };
  std::vector<Wave> waves(6);
  for (Wave& w : waves) {
    w = {(0.5 + 4.0 * u(rng)) * 2 * M_PI / scene_w, (0.5 + 3.0 * u(rng)) * 2 * M_PI / height,
         2 * M_PI * u(rng), 10 + 20 * u(rng)};
  }
  // Soft blobs.
  struct Blob {
    double x, y, r, amp;
  };
  std::vector<Blob> blobs(12);
  for (Blob& b : blobs) {
    b = {scene_w * u(rng), height * u(rng), 15 + 60 * u(rng), -50 + 100 * u(rng)};
  }
  for (int y = 0; y < height; ++y) {
    float* row = scene.ptr<float>(y);
    for (int x = 0; x < scene_w; ++x) {
      double v = 128;
      for (const Wave& w : waves) v += w.amp * std::sin(w.fx * x + w.fy * y + w.phase);
      for (const Blob& b : blobs) {
        const double dx = x - b.x, dy = y - b.y;
        v += b.amp * std::exp(-(dx * dx + dy * dy) / (2 * b.r * b.r));
      }
      row[x] = static_cast<float>(v);
    }
  }
  // Hard-edged facades with window grids.
  const int facades = 10 + static_cast<int>(u(rng) * 8);
  for (int f = 0; f < facades; ++f) {
    const int w = 30 + static_cast<int>(u(rng) * 120),
              h = 40 + static_cast<int>(u(rng) * (height / 2));
    const int x0 = static_cast<int>(u(rng) * (scene_w - w)),
              y0 = static_cast<int>(u(rng) * (height - h));
    const float base = static_cast<float>(40 + 180 * u(rng));
    const cv::Rect r(x0, y0, w, h);
    scene(r).setTo(base);
    const float window = static_cast<float>(std::fmod(base + 60 + 80 * u(rng), 255.0));
    for (int wy = y0 + 6; wy + 8 < y0 + h; wy += 16) {
      for (int wx = x0 + 5; wx + 7 < x0 + w; wx += 14) scene(cv::Rect(wx, wy, 7, 8)).setTo(window);
    }
  }
  cv::GaussianBlur(scene, scene, cv::Size(3, 3), 0.8);
  cv::Mat view = scene(cv::Rect(std::clamp(shift, 0, scene_w - width), 0, width, height));
  cv::Mat noise(height, width, CV_32FC1);
  cv::RNG cv_rng(seed * 2654435761u + 1);
  cv::Mat bgr(height, width, CV_8UC3);
  for (int c = 0; c < 3; ++c) {
    cv_rng.fill(noise, cv::RNG::NORMAL, 0.0, 4.0);
    cv::Mat channel = view * (0.85 + 0.1 * c) + noise + 10.0 * c;
    cv::Mat channel8;
    channel.convertTo(channel8, CV_8U);
    cv::insertChannel(channel8, bgr, c);
  }
  return bgr;
}

lsgd::Descriptor describe_image(const cv::Mat& bgr) {
  lsgd::Segmenter segmenter;
  const lsgd::GrayImage gray = lsgd::to_gray(bgr);
  const lsgd::Segmentation seg = segmenter.segment(gray);
  return lsgd::describe(gray, seg);
}

// ---------------------------------------------------------------- stores

constexpr int kPlaces = 12;          // real descriptors per size
constexpr int kFramesPerPlace = 25;  // route: 25 frames from one place to the next

// Real descriptors of kPlaces distinct places, computed once per size.
const std::vector<lsgd::Descriptor>& places(Size size) {
  static std::map<int, std::vector<lsgd::Descriptor>> cache;
  auto& out = cache[size.width * 100000 + size.height];
  if (out.empty()) {
    for (int p = 0; p < kPlaces; ++p) {
      out.push_back(describe_image(make_bgr(size.width, size.height, 1000 + p)));
    }
  }
  return out;
}

// Frame j of a looping route through the places: linear interpolation of the
// two nearest places' histograms, then a per-frame perturbation (small runs of
// counts moved to nearby bins, as lighting and viewpoint jitter would).
void route_frame(const std::vector<lsgd::Descriptor>& base, std::int64_t j, std::mt19937& rng,
                 lsgd::Descriptor& out) {
  const std::int64_t step = j / kFramesPerPlace;
  const double t = static_cast<double>(j % kFramesPerPlace) / kFramesPerPlace;
  const lsgd::Descriptor& a = base[static_cast<std::size_t>(step % kPlaces)];
  const lsgd::Descriptor& b = base[static_cast<std::size_t>((step + 1) % kPlaces)];
  const int cells = a.grid.cells();
  out.grid = a.grid;
  out.hist.resize(a.hist.size());
  out.pixels.assign(static_cast<std::size_t>(cells), 0);
  for (std::size_t i = 0; i < a.hist.size(); ++i) {
    out.hist[i] = static_cast<lsgd::Bin>(std::lround((1 - t) * a.hist[i] + t * b.hist[i]));
  }
  std::uniform_int_distribution<int> bin(0, lsgd::kBins - 1), delta(-3, 3);
  for (int c = 0; c < cells; ++c) {
    lsgd::Bin* h = out.hist.data() + static_cast<std::size_t>(c) * lsgd::kBins;
    for (int m = 0; m < 24; ++m) {
      const int from = bin(rng);
      if (h[from] == 0) continue;
      const int to = std::clamp(from + delta(rng), 0, lsgd::kBins - 1);
      const lsgd::Bin moved = static_cast<lsgd::Bin>(1 + rng() % (h[from] / 4 + 1));
      const lsgd::Bin n = std::min(moved, h[from]);
      h[from] = static_cast<lsgd::Bin>(h[from] - n);
      h[to] = static_cast<lsgd::Bin>(h[to] + n);
    }
    lsgd::Count sum = 0;
    for (int k = 0; k < lsgd::kBins; ++k) sum += h[k];
    out.pixels[static_cast<std::size_t>(c)] = sum;
  }
}

// A store holding the first `frames` route frames of one size and storage
// (built once, grown on demand and shared by every benchmark of that size and
// storage; compact frames are the exact ones encoded).
const lsgd::FrameStore& route_store(Size size, std::int64_t frames, lsgd::HistogramStorage storage) {
  struct Entry {
    lsgd::FrameStore store;
    std::mt19937 rng{7};
  };
  static std::map<std::pair<int, lsgd::HistogramStorage>, std::unique_ptr<Entry>> cache;
  auto& entry = cache[{size.width * 100000 + size.height, storage}];
  if (!entry) entry = std::make_unique<Entry>();
  if (entry->store.size() < frames) {
    const auto& base = places(size);
    lsgd::Descriptor d, c;
    for (std::int64_t j = entry->store.size(); j < frames; ++j) {
      route_frame(base, j, entry->rng, d);
      if (storage == lsgd::HistogramStorage::kCompact) {
        lsgd::compact(d, c);
        // Interpolated route frames do not all hold exactly the image's pixels;
        // a store has one cell size.
        if (!entry->store.empty()) c.cell_pixels = entry->store.view(0).cell_pixels;
        entry->store.add(c);
      } else {
        entry->store.add(d);
      }
      if (j == 0) entry->store.reserve(frames);
    }
  }
  return entry->store;
}

// A query that revisits the route: frame `j` of the route under another seed.
lsgd::Descriptor route_query(Size size, std::int64_t j, lsgd::HistogramStorage storage) {
  std::mt19937 rng(99);
  lsgd::Descriptor d;
  route_frame(places(size), j, rng, d);
  if (storage == lsgd::HistogramStorage::kExact) return d;
  lsgd::Descriptor c;
  lsgd::compact(d, c);
  c.cell_pixels = route_store(size, 1, storage).view(0).cell_pixels;  // as in route_store
  return c;
}

std::string size_label(Size size) {
  return "cells" + std::to_string(lsgd::grid_size(size.width, size.height, 40).cells()) + "_" +
         std::to_string(size.width) + "x" + std::to_string(size.height);
}

}  // namespace stages_bench
