#include "lsgd/io/session.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <unordered_set>

#include <opencv2/core.hpp>

#include "lsgd/error.h"
#include "lsgd/io/sequence.h"
#include "lsgd/limits.h"

namespace lsgd::io {

namespace fs = std::filesystem;

namespace {
const char* kNewSessionHint = "; choose a new session id (lsgd run --session N) to store them as a new session";
}  // namespace

std::string stored_image_name(const std::string& image) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(image, ec);
  return ec ? image : absolute.lexically_normal().string();
}

bool same_image(const std::string& image, const std::string& stored) {
  return stored == image || stored == stored_image_name(image);
}

double descriptor_difference(const DescriptorView& a, const DescriptorView& b) {
  if (a.cells != b.cells || a.storage() != b.storage()) return 1.0;
  double diff = 0, mass = 0;
  const std::size_t n = static_cast<std::size_t>(a.cells) *
                        (a.storage() == HistogramStorage::kCompact ? kCompactBins : kBins);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = a.storage() == HistogramStorage::kCompact ? a.compact[i] : a.hist[i];
    const double y = b.storage() == HistogramStorage::kCompact ? b.compact[i] : b.hist[i];
    diff += std::abs(x - y);
    mass += x + y;
  }
  return mass > 0 ? diff / mass : 0.0;
}

namespace {

// A new session `session`, its first id one past the database's last: `count`
// more images must stay within kMaxFrameId.
SessionPlan new_session(const Database& db, std::int64_t session, std::int64_t count) {
  SessionPlan plan;
  plan.session = session;
  plan.first_id = db.last_frame() + 1;
  if (plan.first_id > kMaxFrameId - count) {
    throw InvalidArgument("database " + db.path() + ": the frame ids of " +
                          std::to_string(count) + " more images would exceed " +
                          std::to_string(kMaxFrameId));
  }
  return plan;
}

// The first of the session's `stored` frames that is not the sequence's
// image at its id (first_id + index), said in words; empty when they all are.
std::string first_mismatch(const SessionFrames& stored, const std::vector<std::string>& images) {
  const auto count = static_cast<std::int64_t>(images.size());
  for (const StoredFrame& f : stored.frames) {
    const std::int64_t index = f.frame - stored.first_id;
    if (index < 0 || index >= count) {
      return "frame " + std::to_string(f.frame) + " (" + f.name + ") would be image " +
             std::to_string(index) + ", beyond the " + std::to_string(count) +
             " images of the sequence";
    }
    if (!same_image(images[static_cast<std::size_t>(index)], f.name)) {
      return "frame " + std::to_string(f.frame) + " is " + f.name + ", but image " +
             std::to_string(index) + " of the sequence is " +
             images[static_cast<std::size_t>(index)];
    }
  }
  return "";
}

// The session's images have the stored names: the plan continuing it after
// its last stored frame, if that image has the same content too. (A camera
// folder reused for a new recording keeps its file names.) The last stored
// frame is described again and compared with what was stored.
SessionPlan continue_session(const Database& db, const Detector& detector,
                             const std::vector<std::string>& images, const SessionFrames& stored) {
  const std::string session = std::to_string(stored.session);
  const StoredFrame& tail = stored.frames.back();
  const std::int64_t index = tail.frame - stored.first_id;
  double difference = 1.0;
  std::string why;
  try {
    Detector probe(detector.options());
    probe.process(read_image(images[static_cast<std::size_t>(index)]));
    difference = descriptor_difference(probe.store().view(0),
                                       detector.store().view(detector.size() - 1));
    why = "its histograms differ in " + std::to_string(std::lround(100 * difference)) +
          " % of their mass";
  } catch (const Error& e) {
    why = e.what();
  }
  if (difference > 0.01) {
    throw InvalidArgument("database " + db.path() + ": the sequence has the image names of "
                          "session " + session + ", but image " + std::to_string(index) + " (" +
                          images[static_cast<std::size_t>(index)] +
                          ") is not the one stored as frame " + std::to_string(tail.frame) +
                          " (" + why + ")" + kNewSessionHint);
  }
  SessionPlan plan;
  plan.session = stored.session;
  plan.first_id = stored.first_id;
  plan.first = index + 1;
  plan.resume = true;
  plan.last_stored = tail.frame;
  return plan;
}

// Refuses a sequence holding an image the session stores at another id
// (another --first or --every, an edited list) rather than storing it twice.
void refuse_stored_images(const Database& db, const std::vector<std::string>& images,
                          const SessionFrames& stored, const std::string& mismatch) {
  const std::string session = std::to_string(stored.session);
  std::unordered_set<std::string> names;
  for (const StoredFrame& f : stored.frames) names.insert(f.name);
  const auto count = static_cast<std::int64_t>(images.size());
  for (std::int64_t i = 0; i < count; ++i) {
    const std::string& image = images[static_cast<std::size_t>(i)];
    if (names.count(image) || names.count(stored_image_name(image))) {
      throw InvalidArgument(
          "database " + db.path() + ": image " + std::to_string(i) + " of the sequence (" + image +
          ") is already stored in session " + session + ", whose frames are not the sequence's "
          "images at their ids (" + mismatch + "). To continue session " + session +
          ", re-run with the sequence and --first/--last/--every it was started with" +
          kNewSessionHint);
    }
  }
}

}  // namespace

// The last session continues when its frames are the sequence's images at
// their ids (first_id + index), the last one with the same content; a
// sequence holding some of its images elsewhere is refused (another --first
// or --every, an edited list) rather than stored twice. Else a new session.
SessionPlan plan_session(const Database& db, const Detector& detector,
                         const std::vector<std::string>& images,
                         const std::optional<std::int64_t>& chosen) {
  const auto count = static_cast<std::int64_t>(images.size());
  // What the run would be refused for at its first frame, refused first.
  if (chosen && (*chosen < 0 || *chosen > kMaxSession)) {
    throw InvalidArgument("session " + std::to_string(*chosen) + " for " + db.path() +
                          " is out of range [0, " + std::to_string(kMaxSession) + "]");
  }
  if (detector.size() != db.frames()) {
    throw InvalidArgument("database " + db.path() + " holds " + std::to_string(db.frames()) +
                          " frames, the detector " + std::to_string(detector.size()) +
                          ": plan a session with the detector restored from the database "
                          "(Database::restore, Database.detector() in Python; lsgd run does)");
  }
  db.check_compatible(detector.options());
  if (db.frames() == 0) return new_session(db, chosen.value_or(0), count);
  const std::int64_t last = db.last_session();
  if (chosen && *chosen != last) {
    if (!db.session_frames(*chosen).frames.empty()) {
      throw InvalidArgument("session " +
                            std::to_string(*chosen) + " of " + db.path() +
                            " has frames before the last session (" + std::to_string(last) +
                            "), and a session's frames stay together: continue session " +
                            std::to_string(last) + " or choose a new id");
    }
    return new_session(db, *chosen, count);
  }
  const SessionFrames stored = db.session_frames(last);
  const std::string mismatch = first_mismatch(stored, images);
  if (mismatch.empty()) return continue_session(db, detector, images, stored);
  const std::string session = std::to_string(last);
  if (chosen) {
    throw InvalidArgument("session " + session + " continues session " + session + " of " +
                          db.path() + " only with the images it holds at their ids: " + mismatch +
                          kNewSessionHint);
  }
  refuse_stored_images(db, images, stored, mismatch);
  if (last >= kMaxSession) {
    throw InvalidArgument("database " + db.path() + ": the last session is " + session +
                          ", the largest id; choose an unused session id");
  }
  return new_session(db, last + 1, count);
}

void begin_session(Detector& detector, const SessionPlan& plan) {
  if (!plan.resume && detector.size() > 0) detector.cut();
}

}  // namespace lsgd::io
