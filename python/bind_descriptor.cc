// A frame's Descriptor (its histograms as numpy arrays, and back), the
// similarity of two descriptors, and place recognition between two
// traverses (match, as lsgd match).
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "bindings.h"
#include "convert.h"
#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/eval/distractors.h"
#include "lsgd/eval/results_csv.h"
#include "lsgd/io/files.h"
#include "lsgd/image.h"
#include "lsgd/options.h"
#include "lsgd/places.h"
#include "lsgd/similarity.h"

namespace lsgd::python {

namespace {

// The values of `array`, an array of integers each in [0, most], as T:
// counts of another dtype or beyond T were cast silently (-1 became 65535,
// 1e12 and NaN became 0) into a descriptor that compared as if real.
template <typename T>
std::vector<T> counts_of(const py::array& array, const char* name, std::int64_t most) {
  const char kind = array.dtype().kind();
  if (kind != 'u' && kind != 'i') {
    throw lsgd::InvalidArgument(std::string(name) + " has dtype " + py::str(array.dtype()).cast<std::string>() +
                                ": a descriptor's " + name + " are unsigned integer counts (as Descriptor." + name +
                                " gives them)");
  }
  const auto values = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw lsgd::InvalidArgument(std::string(name) + " is not an array of counts");
  std::vector<T> out;
  out.reserve(static_cast<std::size_t>(values.size()));
  for (py::ssize_t i = 0; i < values.size(); ++i) {
    const std::int64_t v = values.data()[i];
    // A uint64 above 2^63 reads as negative here: refused as well.
    if (v < 0 || v > most) {
      throw lsgd::InvalidArgument(std::string(name) + " value " + std::to_string(v) + " at flat index " +
                                  std::to_string(i) + " is outside 0 .. " + std::to_string(most));
    }
    out.push_back(static_cast<T>(v));
  }
  return out;
}

lsgd::Descriptor descriptor_from_arrays(py::array histograms, const py::object& pixels, py::tuple grid,
                                        double cell_pixels) {
  lsgd::Descriptor d;
  if (grid.size() != 2) throw lsgd::InvalidArgument("grid is (rows, cols)");
  long long rows = 0, cols = 0;
  try {
    rows = grid[0].cast<long long>();
    cols = grid[1].cast<long long>();
  } catch (const py::cast_error&) {
    throw lsgd::InvalidArgument("grid " + py::repr(grid).cast<std::string>() + " is not (rows, cols) of integers");
  }
  if (rows <= 0 || cols <= 0 || rows > (1 << 20) || cols > (1 << 20) || rows * cols > (1 << 20)) {
    throw lsgd::InvalidArgument("grid " + std::to_string(rows) + " x " + std::to_string(cols) +
                                " is not a descriptor's grid");
  }
  d.grid = {static_cast<int>(rows), static_cast<int>(cols)};
  if (histograms.dtype().kind() == 'u' && histograms.dtype().itemsize() == 1) {  // compact: uint8
    d.storage = lsgd::HistogramStorage::kCompact;
    d.compact = counts_of<std::uint8_t>(histograms, "histograms", 255);
    d.cell_pixels = cell_pixels;
  } else {
    d.hist = counts_of<std::uint16_t>(histograms, "histograms", 65535);
    if (pixels.is_none()) throw lsgd::InvalidArgument("an exact descriptor needs its pixels per cell");
    const py::array p = py::array::ensure(pixels);
    if (!p) throw lsgd::InvalidArgument("pixels is not an array of counts");
    d.pixels = counts_of<std::uint32_t>(p, "pixels", 4294967295LL);
  }
  d.check_consistent("Descriptor.from_arrays");
  d.check_counts("Descriptor.from_arrays");
  return d;
}

py::dict match_descriptors(const std::vector<lsgd::Descriptor>& reference, const std::vector<lsgd::Descriptor>& query,
                           int top_k, const std::string& metric, std::int64_t query_offset, const py::object& output) {
  // Views carry what each descriptor counts: match_top_k refuses a mix.
  std::vector<lsgd::DescriptorView> refs, queries;
  for (const lsgd::Descriptor& d : reference) refs.push_back(d.view());
  for (const lsgd::Descriptor& d : query) queries.push_back(d.view());
  // The output is checked before the matching: a folder that cannot take it
  // lost the results after the work (lsgd match checks its outputs first).
  const std::string out = output.is_none() ? std::string() : path_of(output, "output");
  if (!out.empty()) lsgd::io::check_output_file(out, "matches CSV");
  std::vector<lsgd::TopMatch> found;
  {
    py::gil_scoped_release release;
    found = lsgd::match_top_k(refs, queries, top_k,
                              lsgd::parse_similarity_metric(metric.c_str()), query_offset);
  }
  if (!output.is_none()) {  // the CSV lsgd match writes, whole or not at all
    lsgd::io::write_output_file(out, lsgd::eval::match_csv(found), "matches CSV");
  }
  const auto n = static_cast<py::ssize_t>(found.size());
  py::array_t<std::int64_t> q(n), j(n), rank(n);
  py::array_t<double> score(n), sim(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const lsgd::TopMatch& t = found[static_cast<std::size_t>(i)];
    q.mutable_at(i) = t.query;
    j.mutable_at(i) = t.match;
    score.mutable_at(i) = t.score;
    sim.mutable_at(i) = t.similarity;
    rank.mutable_at(i) = t.rank;
  }
  py::dict d;
  d["query"] = q;
  d["match"] = j;
  d["score"] = score;
  d["similarity"] = sim;
  d["rank"] = rank;
  return d;
}

void bind_descriptor_class(py::module_& m) {
  py::class_<lsgd::Descriptor>(m, "Descriptor",
      "A frame's descriptor (Detector.describe): one histogram per cell of its grid. "
      "Descriptor.from_arrays builds one back from numpy arrays.")
      .def_property_readonly("grid", [](const lsgd::Descriptor& d) { return py::make_tuple(d.grid.rows, d.grid.cols); })
      .def_property_readonly("storage", [](const lsgd::Descriptor& d) { return std::string(lsgd::to_string(d.storage)); })
      .def_property_readonly("histograms", [](const lsgd::Descriptor& d) -> py::array {
             const auto cells = static_cast<py::ssize_t>(d.grid.cells());
             if (d.storage == lsgd::HistogramStorage::kCompact) {
               py::array_t<std::uint8_t> out({cells, py::ssize_t{lsgd::kCompactBins}});
               std::copy(d.compact.begin(), d.compact.end(), out.mutable_data());
               return out;
             }
             py::array_t<std::uint16_t> out({cells, py::ssize_t{lsgd::kBins}});
             std::copy(d.hist.begin(), d.hist.end(), out.mutable_data());
             return out;
           }, "cells x 256 uint16 counts (exact), or cells x 128 uint8 (compact), cell-major")
      .def_property_readonly("pixels", [](const lsgd::Descriptor& d) {
             py::array_t<std::uint32_t> out(static_cast<py::ssize_t>(d.pixels.size()));
             std::copy(d.pixels.begin(), d.pixels.end(), out.mutable_data());
             return out;
           }, "pixels per cell (exact; empty when compact)")
      .def_readonly("cell_pixels", &lsgd::Descriptor::cell_pixels, "mean pixels per cell (compact)")
      .def_readonly("type", &lsgd::Descriptor::type,
                    "what its bins count: the descriptor type and its own options (\"\" when built from arrays)")
      .def_static("from_arrays", &descriptor_from_arrays,
           py::arg("histograms"), py::arg("pixels") = py::none(), py::arg("grid"), py::arg("cell_pixels") = 0.0,
           "A descriptor from its arrays: uint16 histograms (cells x 256) with uint32 pixels per cell "
           "(exact), or uint8 histograms (cells x 128) with cell_pixels (compact)");
}

}  // namespace

void bind_descriptor(py::module_& m) {
  bind_descriptor_class(m);
  m.def("similarity", [](const lsgd::Descriptor& a, const lsgd::Descriptor& b, const std::string& metric) {
          if (a.grid != b.grid || a.storage != b.storage) {
            throw lsgd::InvalidArgument("the descriptors differ in grid or storage");
          }
          return lsgd::similarity(a.view(), b.view(), lsgd::parse_similarity_metric(metric.c_str()));
        }, py::arg("a"), py::arg("b"), py::arg("metric") = std::string(lsgd::to_string(lsgd::SimilarityOptions{}.metric)),
        "Similarity of two descriptors (the detector's similarity.metric by default).");
  m.def("place_signature", [](py::array image) {
          lsgd::GrayImage gray;
          lsgd::to_gray(image_view(image), gray);
          const std::vector<std::uint8_t> s = lsgd::place_signature(gray);
          return py::bytes(reinterpret_cast<const char*>(s.data()), s.size());
        }, py::arg("image"),
        "The frame's place signature (lsgd/places.h): 4 x 4 cells x 8 gradient orientations of "
        "the frame at 160 x 120, 128 bytes; what verification.temporal.place_cut finds places by.");
  m.def("signature_similarity", [](const py::bytes& a, const py::bytes& b) {
          const std::string x = a, y = b;
          if (x.size() != lsgd::kSignatureBytes || y.size() != lsgd::kSignatureBytes) {
            throw lsgd::InvalidArgument("signature_similarity: signatures of " + std::to_string(x.size()) +
                                        " and " + std::to_string(y.size()) + " bytes, expected " +
                                        std::to_string(lsgd::kSignatureBytes));
          }
          // Each cell's 8 bins sum to about 255 (rounded), or 0 for a cell without
          // gradients: any other bytes are no signature (they scored -3).
          for (const auto& [name, bytes] : {std::pair<const char*, const std::string*>{"a", &x}, {"b", &y}}) {
            for (std::size_t cell = 0; cell < bytes->size() / 8; ++cell) {
              int sum = 0;
              for (std::size_t k = 0; k < 8; ++k) sum += static_cast<unsigned char>((*bytes)[cell * 8 + k]);
              if (sum != 0 && (sum < 255 - 8 || sum > 255 + 8)) {
                throw lsgd::InvalidArgument(std::string("signature_similarity: ") + name + "'s cell " +
                                            std::to_string(cell) + " sums to " + std::to_string(sum) +
                                            ", not about 255 (or 0): not a place signature (lsgd.place_signature)");
              }
            }
          }
          return lsgd::signature_similarity(reinterpret_cast<const std::uint8_t*>(x.data()),
                                            reinterpret_cast<const std::uint8_t*>(y.data()));
        }, py::arg("a"), py::arg("b"),
        "Similarity of two place signatures: 1 - half the mean L1 distance of their cells.");
  m.def("make_distractor", [](const lsgd::Descriptor& base, std::int64_t k, std::int64_t run,
                             const std::string& storage) {
          lsgd::Descriptor exact, out;
          lsgd::eval::make_distractor(base, k, run, lsgd::parse_histogram_storage(storage.c_str()), exact, out);
          return out;
        }, py::arg("base"), py::arg("k"), py::arg("run") = 1, py::arg("storage") = "exact",
        "Distractor k made from `base` (an exact descriptor, Detector.describe()) as lsgd bench "
        "--distractors makes it: cells shuffled and each histogram moved by a random lighting "
        "offset, seeded by k // run (a run of `run` distractors is one stretch of another place); "
        "in `storage` (exact or compact).");
  m.def("match", &match_descriptors,
        py::arg("reference"), py::arg("query"), py::arg("top_k") = 1,
        py::arg("metric") = std::string(lsgd::to_string(lsgd::SimilarityOptions{}.metric)),
        py::arg("query_offset") = 0, py::arg("output") = py::none(),
        "Place recognition between two traverses, as lsgd match: the top_k reference "
        "descriptors of every query descriptor (Detector.describe), as numpy arrays query "
        "(query_offset + index), match (reference index), score (sigma of the query's "
        "similarities to the reference), similarity and rank (1: best); output: also write "
        "lsgd match's CSV there (lsgd.evaluate_detections reads it).");
}

}  // namespace lsgd::python
