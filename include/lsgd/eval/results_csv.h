// The per-frame CSV of `lsgd run` (and `lsgd eval --output`, the demo, Python's
// lsgd.write_csv): one row per processed frame. Its reader is
// read_detections() (lsgd/eval/detections.h).
#pragma once

#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/io/files.h"
#include "lsgd/similarity.h"

namespace lsgd::eval {

// `text` as one CSV field: quoted (quotes doubled) when it holds a comma, a
// quote or a line break, else as it is.
std::string csv_field(const std::string& text);
// The fields of one CSV record, the inverse of csv_field(): split at the
// commas outside quotes, quoted text unquoted (a doubled quote is one), every
// byte kept as it is (readers that allow spaces around numbers trim them).
// The one reader of quoted fields: lsgd run's rows (a resumed run's check
// of their images) and detections files (eval::read_detections).
std::vector<std::string> csv_fields(const std::string& record);

// The CSV of `lsgd match` and Python's lsgd.match(output=): a header, then
// query,match,score,similarity,rank per match, in the order given.
std::string match_csv(const std::vector<TopMatch>& matches);

// Writes `lsgd run` rows:
// frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,
// ranked_frame,ranked_score,ranked_confirmed (the ranking, Result::ranking).
// Each row is flushed, so an error later in the run loses nothing written.
// Errors name the file.
class CsvWriter {
 public:
  // The CSV's newest version: frame, image, loop_frame, candidate_frame,
  // score, ms, appearance, inliers (0), ranked_frame, ranked_score,
  // ranked_confirmed (1), status (2, to_string(LoopStatus)), stamp (3:
  // Result::stamp in its shortest exact text, empty when the frame has none).
  static constexpr int kCsvNewest = 3;
  enum Mode { kCreate, kAppend };
  // Empty path: stdout. kCreate writes the newest header (replacing the
  // file); kAppend adds rows after the existing ones (a file trim()
  // accepted) in the columns of the CSV's `version` (Trim::version): a run
  // written before the ranking's or the status column resumes without them.
  explicit CsvWriter(const std::string& path, Mode mode = kCreate, int version = kCsvNewest);
  void write(const Result& result, const std::string& image);
  std::int64_t loops() const { return loops_; }  // rows written with a loop

  struct Trim {
    std::int64_t dropped = 0;    // complete rows cut
    std::int64_t other = 0;      // complete lines cut that are no row (no frame id first)
    bool partial = false;        // an incomplete last line was cut
    std::int64_t last_row = -1;  // frame of the last row kept; -1: none
    int version = kCsvNewest;    // of the header: 0 none of the columns below, 1 ranked_*, 2 status, 3 stamp
  };
  // What trim() shows its caller before it cuts anything: the frame and the
  // image of a row (unquoted), the last row kept and then the first complete
  // row cut, each when there is one. Whatever it throws leaves the file as it
  // was: a resumed run refuses another run's CSV (rows naming other images
  // at those frame ids) this way.
  using RowCheck = std::function<void(std::int64_t frame, const std::string& image)>;
  // Cuts the rows of frames after `last_frame` (and an incomplete last line)
  // from an existing CSV this writer wrote, in place, once `check` (when
  // given) accepted the rows at the cut. Throws FormatError when the file is
  // not one (its header differs).
  static Trim trim(const std::string& path, std::int64_t last_frame, const RowCheck& check = {});

 private:
  std::string path_;
  int version_ = kCsvNewest;
  std::int64_t loops_ = 0;
  io::OutputLock lock_;  // no second writer of the file while this one lives
  std::unique_ptr<std::ofstream> file_;
  std::ostream* out_;
};

}  // namespace lsgd::eval
