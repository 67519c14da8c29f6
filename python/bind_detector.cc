// The detector's options as dicts (default_options, options) and the
// Detector: frames in as numpy arrays, Results and Descriptors out.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bindings.h"
#include "convert.h"
#include "lsgd/detector.h"
#include "lsgd/options.h"

namespace lsgd::python {

namespace {

void bind_options(py::module_& m) {
  m.def("default_options", [] { return options_dict(lsgd::DetectorOptions{}); },
        "Every detector option and its default, as {'search.min_gap': '50', ...}.");
  m.def("options", [](const py::object& options, const py::kwargs& kwargs) {
          return options_dict(make_options(options, kwargs));
        }, py::arg("options") = py::none(),
        "The options a Detector(options, **kwargs) would use, validated.");
}

using DetectorClass = py::class_<lsgd::Detector>;

py::bytes description_bytes(const lsgd::FrameDescription& d) {
  const std::vector<std::uint8_t> b = lsgd::encode_frame_description(d);
  return py::bytes(reinterpret_cast<const char*>(b.data()), b.size());
}

lsgd::FrameDescription description_of_bytes(const py::bytes& b) {
  const std::string_view text = b;
  return lsgd::decode_frame_description(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

// A frame described apart from the map: Detector.describe_frame() on a
// robot, Detector.process(description) on the map; bytes and pickle to travel.
void bind_frame_description(py::module_& m) {
  py::class_<lsgd::FrameDescription>(m, "FrameDescription",
      "A frame described apart from the map (Detector.describe_frame): its descriptor and each "
      "verification stage's record. Detector.process(description) and .query(description) give "
      "the Results of the image, in any detector made with the same options. to_bytes() / "
      "FrameDescription.from_bytes() and pickle carry it between processes.")
      .def_readonly("width", &lsgd::FrameDescription::width)
      .def_readonly("height", &lsgd::FrameDescription::height)
      .def_readonly("descriptor", &lsgd::FrameDescription::descriptor)
      .def_readonly("stages", &lsgd::FrameDescription::stages)
      .def_readonly("options_key", &lsgd::FrameDescription::options_key)
      .def_property_readonly("record_bytes", [](const lsgd::FrameDescription& d) {
             std::size_t n = 0;
             for (const auto& r : d.records) n += r.size();
             return n;
           }, "bytes of the stages' records (the geometric stage's features)")
      .def_property_readonly("signature", [](const lsgd::FrameDescription& d) {
             return py::bytes(reinterpret_cast<const char*>(d.signature.data()), d.signature.size());
           }, "the frame's place signature (128 bytes with verification.temporal.place_cut, else empty)")
      .def("to_bytes", &description_bytes, "The description as bytes (versioned, little-endian).")
      .def_static("from_bytes", &description_of_bytes, py::arg("data"),
                  "A description back from to_bytes(); lsgd.FormatError for bytes that are not one.")
      .def("__reduce__", [](const lsgd::FrameDescription& d) {
             return py::make_tuple(py::module_::import("lsgd._restore").attr("frame_description"),
                                   py::make_tuple(description_bytes(d)));
           });
  // pickle rebuilds through lsgd._restore, never through __new__ (lsgd_module.cc).
  m.def("_restore_frame_description", &description_of_bytes, py::arg("data"));
}

// Construction from options, and the frames going in: process, query, forget, cut.
void bind_detector_frames(DetectorClass& detector) {
  detector
      .def(py::init([](const py::object& options, const py::kwargs& kwargs) {
             return std::make_unique<lsgd::Detector>(make_options(options, kwargs));
           }),
           py::arg("options") = py::none(),
           "Detector(options=None, **kwargs): options as a dict with the YAML's names "
           "(nested or dotted), a YAML file name, or keyword arguments per section: "
           "Detector(search={'min_gap': 50, 'mode': 'nodes'}, verification={'stages': 'temporal'}).")
      .def("process",
           [](lsgd::Detector& d, const lsgd::FrameDescription& frame, std::int64_t id, double stamp) {
             py::gil_scoped_release release;
             return d.process(frame, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "Processes a frame described apart from the map (Detector.describe_frame, here or in "
           "another process with the same options): the Result of its image.")
      .def("process",
           [](lsgd::Detector& d, py::array image, std::int64_t id, double stamp) {
             // A strided view (a crop with a step, a transposed array) is copied once.
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;  // other Python threads run meanwhile
             return d.process(view, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "Processes the next frame (uint8 numpy array: (H, W) gray, (H, W, 3) BGR or "
           "(H, W, 4) BGRA) and returns its Result. id: the caller's id of the frame (above the "
           "last; -1: the one after it), stamp: its time stamp (NaN: none); Result.id, .stamp and "
           ".loop_id carry them. Zero-copy when each row's pixels are contiguous; the GIL is "
           "released while it runs.")
      .def("query",
           [](lsgd::Detector& d, const lsgd::FrameDescription& frame, std::int64_t id, double stamp) {
             py::gil_scoped_release release;
             return d.query(frame, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "query() of a described frame: the Result query(image) gives.")
      .def("query",
           [](lsgd::Detector& d, py::array image, std::int64_t id, double stamp) {
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;
             return d.query(view, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "The Result process() would give for the frame as the next one, with nothing "
           "stored and nothing changed (relocalisation; a map opened read-only). Result.frame "
           "is the id process() would give it.")
      .def("forget", &lsgd::Detector::forget, py::arg("first_id"), py::arg("last_id"),
           "Forgets the stored frames whose ids lie in [first_id, last_id] and returns how many: "
           "they are never candidates again; the kept frames keep their ids (their frame numbers "
           "close up), and the detector is the one restoring only them would give.")
      .def("cut", &lsgd::Detector::cut,
           "The next frame starts a new sequence (a new session, another place): it "
           "continues no loop declared for the frame before it.");
}

// What the detector holds: its size and options, descriptors, ids and stamps.
void bind_detector_state(DetectorClass& detector) {
  detector
      .def_property_readonly("size", &lsgd::Detector::size)
      .def("__len__", &lsgd::Detector::size)
      .def_property_readonly("nodes", &lsgd::Detector::nodes)
      .def_property_readonly("place_starts", &lsgd::Detector::place_starts,
                             "the first frames of the places found after the first "
                             "(verification.temporal.place_cut), ascending")
      .def_property_readonly("options", [](const lsgd::Detector& d) { return options_dict(d.options()); })
      .def("describe",
           [](lsgd::Detector& d, py::array image) {
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;
             return d.describe(view);
           },
           py::arg("image"), "The image's Descriptor as the detector would store it; nothing stored.")
      .def("describe_frame",
           [](lsgd::Detector& d, py::array image) {
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;
             return d.describe_frame(view);
           },
           py::arg("image"),
           "The frame as process() takes it, nothing stored: a FrameDescription (descriptor and "
           "the stages' records) that process() or query() of this or another detector with the "
           "same options takes in place of the image (a robot describes, the map stores).")
      .def("id_of", &lsgd::Detector::id_of, py::arg("frame"), "The caller's id of stored frame `frame`.")
      .def("stamp_of", &lsgd::Detector::stamp_of, py::arg("frame"), "Its time stamp (NaN: none).")
      .def("frame_of", &lsgd::Detector::frame_of, py::arg("id"),
           "The stored frame of caller id `id` (-1: none).")
      .def("similarity", &lsgd::Detector::similarity, py::arg("a"), py::arg("b"),
           "Similarity of two stored frames with the configured metric.");
}

void bind_detector_class(py::module_& m) {
  DetectorClass detector(m, "Detector");
  bind_detector_frames(detector);
  bind_detector_state(detector);
}

}  // namespace

void bind_detector(py::module_& m) {
  bind_options(m);
  bind_frame_description(m);
  bind_detector_class(m);
}

}  // namespace lsgd::python
