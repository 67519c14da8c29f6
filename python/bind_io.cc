// The io layer: the place database (Database, with a `with` block and
// close()), its session plans, the results CSV lsgd run writes, the names a
// database keeps for images, and images and sequences read from files.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "bindings.h"
#include "convert.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/results_csv.h"
#include "lsgd/io/database.h"
#include "lsgd/io/files.h"
#include "lsgd/io/sequence.h"
#include "lsgd/io/session.h"

namespace lsgd::python {

// A Database Python can close before the garbage collector drops it (a
// second writer on the same file in this process is refused while the first
// is open): every call on a closed one is an InvalidArgument naming the file.
struct PyDatabase {
  explicit PyDatabase(lsgd::io::Database d) : db(std::make_unique<lsgd::io::Database>(std::move(d))), path(db->path()) {}
  lsgd::io::Database& get() const {
    if (!db) throw lsgd::InvalidArgument("database " + path + " is closed");
    return *db;
  }
  // Closed whatever happens; what closing finds (a replaced file) is raised.
  void close() {
    if (!db) return;
    const std::unique_ptr<lsgd::io::Database> closing = std::move(db);
    closing->close();
  }
  std::unique_ptr<lsgd::io::Database> db;
  std::string path;
};

namespace {

using DatabaseClass = py::class_<PyDatabase>;

// Creating and opening a database, and what it stores: frames, sessions and
// the search index.
void bind_database_contents(DatabaseClass& database) {
  database
      .def_static("create", [](const py::object& path, const py::object& options, const py::kwargs& kwargs) {
             return PyDatabase(lsgd::io::Database::create(path_of(path), make_options(options, kwargs)));
           }, py::arg("path"), py::arg("options") = py::none(),
           "Creates a new, empty database for detectors with these options.")
      .def_static("open", [](const py::object& path, bool writable) {
             return PyDatabase(lsgd::io::Database::open(
                 path_of(path), writable ? lsgd::io::Database::Mode::kReadWrite : lsgd::io::Database::Mode::kReadOnly));
           }, py::arg("path"), py::arg("writable") = true)
      .def("detector", [](const PyDatabase& db, bool rebuild_index) {
             auto d = std::make_unique<lsgd::Detector>(db.get().options());
             db.get().restore(*d, rebuild_index ? lsgd::io::IndexUse::kRebuild : lsgd::io::IndexUse::kSaved);
             return d;
           }, py::arg("rebuild_index") = false,
           "A detector with the stored options and every stored frame restored (and the saved "
           "search index, unless rebuild_index).")
      .def("restore", [](const PyDatabase& db, lsgd::Detector& d, bool rebuild_index) {
             db.get().restore(d, rebuild_index ? lsgd::io::IndexUse::kRebuild : lsgd::io::IndexUse::kSaved);
           }, py::arg("detector"), py::arg("rebuild_index") = false)
      .def("save_index", [](PyDatabase& db, const lsgd::Detector& d) { return db.get().save_index(d); },
           py::arg("detector"),
           "Saves the detector's search index (index mode's graph) so a resume need not rebuild "
           "it; returns the frames it covers.")
      .def("append", [](PyDatabase& db, const lsgd::Detector& d, const lsgd::Result& r, std::int64_t session,
                        const py::object& name, std::int64_t frame) {
             // The image's name as a path (open_sequence's str, bytes, pathlib.Path): a
             // name that is not UTF-8 is stored as its bytes, as lsgd run stores it.
             // Converted first: its __fspath__ may run any Python code, close
             // the database included, and db.get() checks it is open.
             const std::string path = path_of(name, "append: name");
             db.get().append(d, r, session, path, frame);
           }, py::arg("detector"), py::arg("result"), py::arg("session"), py::arg("name") = "",
           py::arg("frame") = -1, "Stores the detector's last frame (call right after process()).")
      .def("forget", [](PyDatabase& db, std::int64_t first_id, std::int64_t last_id) {
             return db.get().forget(first_id, last_id);
           }, py::arg("first_id"), py::arg("last_id"),
           "Forgets the frames whose ids lie in [first_id, last_id], in one transaction (as "
           "Detector.forget); returns how many.")
      .def("plan_session", [](const PyDatabase& db, lsgd::Detector& d, const py::object& images,
                              std::optional<std::int64_t> session) {
             const std::vector<std::string> paths = paths_of(images, "plan_session: images");
             const lsgd::io::SessionPlan plan = lsgd::io::plan_session(db.get(), d, paths, session);
             lsgd::io::begin_session(d, plan);
             return plan;
           }, py::arg("detector"), py::arg("images"), py::arg("session") = py::none(),
           "Where a run of `images` (paths) continues, as `lsgd run --database` decides: the last "
           "session from its next image when the images are that session's, else a new session "
           "(`session`, or the last + 1). `detector` holds the stored frames (Database.detector()); "
           "for a new session it continues no loop of them (Detector.cut(), as lsgd run does). "
           "Image i is frame plan.first_id + i; store it under lsgd.stored_image_name(path).")
      .def("forget_session", [](PyDatabase& db, std::int64_t session) {
             return db.get().forget_session(session);
           }, py::arg("session"), "Forgets every frame of the session; returns how many.");
}

// The handle: close() and `with`, and what it tells about itself.
void bind_database_handle(DatabaseClass& database) {
  database
      .def("close", &PyDatabase::close,
           "Checkpoints and releases the file (a writer's lock included); an IoError when the "
           "file was replaced or deleted while it was written; again: nothing.")
      .def_property_readonly("closed", [](const PyDatabase& db) { return !db.db; })
      .def("__enter__", [](PyDatabase& db) -> PyDatabase& { return db; }, py::return_value_policy::reference)
      .def("__exit__", [](PyDatabase& db, const py::object& type, const py::object&, const py::object&) {
             // An exception already leaving the block is the one to see.
             try {
               db.close();
             } catch (const lsgd::Error&) {
               if (type.is_none()) throw;
             }
             return false;
           })
      .def_property_readonly("path", [](const PyDatabase& db) { return fs_str(db.path); })
      .def_property_readonly("frames", [](const PyDatabase& db) { return db.get().frames(); })
      .def_property_readonly("last_session", [](const PyDatabase& db) { return db.get().last_session(); })
      .def_property_readonly("options", [](const PyDatabase& db) { return options_dict(db.get().options()); })
      .def("frame_ids", [](const PyDatabase& db) { return db.get().frame_ids(); })
      .def("__repr__", [](const PyDatabase& db) {
        return "Database(" + py::repr(fs_str(db.path)).cast<std::string>() + ", " +
               (db.db ? std::to_string(db.db->frames()) + " frames)" : std::string("closed)"));
      });
}

void bind_database_class(py::module_& m) {
  DatabaseClass database(m, "Database",
      "The place database. close() (or leaving a `with` block) releases the file; a closed "
      "Database refuses every call.");
  bind_database_contents(database);
  bind_database_handle(database);
}

std::int64_t write_results_csv(const std::vector<lsgd::Result>& results, const py::object& images,
                               const py::object& path) {
  const std::vector<std::string> names = paths_of(images, "write_csv: images");
  if (names.size() != results.size()) {
    throw lsgd::InvalidArgument("write_csv: " + std::to_string(names.size()) + " image names for " +
                                std::to_string(results.size()) + " results (one per result)");
  }
  // One detector's results in the order process() returned them: frames and
  // ids increasing (a Result twice, or reversed, paired frames with the
  // wrong images). A subset, or a resumed session's, is fine.
  for (std::size_t i = 1; i < results.size(); ++i) {
    const lsgd::Result& a = results[i - 1];
    const lsgd::Result& b = results[i];
    if (b.frame <= a.frame || b.id <= a.id) {
      throw lsgd::InvalidArgument(
          "write_csv: result " + std::to_string(i) + " is the detector's frame " + std::to_string(b.frame) +
          " (id " + std::to_string(b.id) + ") after frame " + std::to_string(a.frame) + " (id " +
          std::to_string(a.id) + "): give the Results of one detector in the order process() returned "
          "them, each once");
    }
  }
  const std::string out = path_of(path);
  for (const std::string& name : names) {
    std::error_code ec;  // an output never overwrites an input
    if (std::filesystem::equivalent(out, name, ec)) {
      throw lsgd::InvalidArgument("write_csv: the output " + out + " is the input image " + name);
    }
  }
  lsgd::eval::CsvWriter csv(out);
  for (std::size_t i = 0; i < results.size(); ++i) csv.write(results[i], names[i]);
  return csv.loops();
}

void bind_sessions(py::module_& m) {
  py::class_<lsgd::io::SessionPlan>(m, "SessionPlan",
      "Database.plan_session's answer: the session, the id of image 0, the first image to "
      "process, whether the session is continued, and its last stored frame's id.")
      .def_readonly("session", &lsgd::io::SessionPlan::session)
      .def_readonly("first_id", &lsgd::io::SessionPlan::first_id)
      .def_readonly("first", &lsgd::io::SessionPlan::first)
      .def_readonly("resume", &lsgd::io::SessionPlan::resume)
      .def_readonly("last_stored", &lsgd::io::SessionPlan::last_stored)
      .def("__repr__", [](const lsgd::io::SessionPlan& p) {
        return "SessionPlan(session=" + std::to_string(p.session) + ", first_id=" + std::to_string(p.first_id) +
               ", first=" + std::to_string(p.first) + ", resume=" + (p.resume ? "True" : "False") + ")";
      });
  m.def("write_csv", &write_results_csv, py::arg("results"), py::arg("images"), py::arg("path"),
        "Writes the results as `lsgd run`'s CSV (the same code, one row per result, `images` its image "
        "column); returns the loops written. Replaces the file.");
  m.def("stored_image_name", [](const py::object& path) { return fs_str(lsgd::io::stored_image_name(path_of(path))); },
        py::arg("path"), "The name a database keeps for an image (its absolute, normal path), as lsgd run stores it.");
}

void bind_images(py::module_& m) {
  m.def("read_image", [](const py::object& path) { return mat_to_array(lsgd::io::read_image(path_of(path))); },
        py::arg("path"), "Reads an image file as a uint8 array (gray or BGR); lsgd.Error on a bad file.");
  m.def("open_sequence", [](const py::object& path) { return fs_strs(lsgd::io::open_sequence(path_of(path)).images); },
        py::arg("path"), "The image paths of a folder (natural order) or an image list file.");
}

}  // namespace

void bind_io(py::module_& m) {
  bind_database_class(m);
  bind_sessions(m);
  bind_images(m);
}

}  // namespace lsgd::python
