// Persistence of the detector's state in an SQLite file, so that a run
// survives restarts and later runs (sessions) append to it. One row per
// frame, one transaction per appended frame: a crash loses at most the frame
// being written, and the file stays inspectable with the sqlite3 shell.
//
// Schema (format version 5; docs/reliability.md, "Persistence"):
//
//   meta(key TEXT PRIMARY KEY, value NOT NULL)
//     format_version   5 (integer)
//     library_version  e.g. "0.1.0", the lsgd that created the file
//     options          the DetectorOptions as YAML (io::to_yaml)
//     width, height    frame size (0 until the first frame)
//     grid_rows, grid_cols
//     writer           "open" while a writer has the file, "closed" after it
//                      closed it (absent in older files)
//     checkpoint_frames  frames in the file at the writer's last checkpoint
//     session_first_ids  "session=first_id ..." (absent when none): the id a
//                      session's numbering started from, for sessions whose
//                      earlier frames forget() removed (SessionFrames::first_id)
//     checksum         CRC-32 of every other "key=value\n", keys in order
//   frames(id INTEGER PRIMARY KEY,  -- detector frame id: 0, 1, 2, ... dense
//          session INTEGER NOT NULL, -- 0 .. kMaxSession, chosen by the writer;
//                                    -- a session's rows are consecutive
//          name TEXT NOT NULL,       -- image name or path ('' when unknown)
//          histogram BLOB NOT NULL,  -- cells * 256 uint16, little-endian
//          pixels BLOB NOT NULL,     -- cells uint32, little-endian
//          node INTEGER,             -- dynamic node joined/created (also in its
//                                    -- state; for db info); NULL without groups
//          crc32 INTEGER NOT NULL,   -- CRC-32 of every other column (see database.cc)
//          frame INTEGER,            -- the caller's frame id, increasing with id
//                                    -- (NULL in rows of formats 1, 2: = id)
//          state BLOB,               -- Detector::frame_state(): the versioned
//                                    -- records of the search mode, the
//                                    -- verification stages and the decision
//                                    -- (lsgd/state.h), stored without looking
//                                    -- inside; NULL in rows of older formats
//          place INTEGER, features BLOB, loop INTEGER, loop_inliers REAL)
//                                    -- formats 1 to 3: the temporal place, the
//                                    -- ORB features and the decision's loop in
//                                    -- columns of their own (NULL in format 4
//                                    -- rows); restore() reads them as the
//                                    -- components' version-1 records
//   indexes(mode TEXT, part INTEGER,  -- the search mode's saved index
//           frames INTEGER NOT NULL,   -- (Database::save_index), its bytes
//           data BLOB NOT NULL,        -- in parts 0, 1, ... of <= 64 MiB,
//           crc32 INTEGER NOT NULL,    -- each with its CRC-32; the frames
//           PRIMARY KEY(mode, part))   -- 0 .. frames - 1 it covers
//
// A component with new state (a new verification stage) needs no schema
// change: its records travel in `state`. Appending a frame is one row.
//
// Durability: the write-ahead log is checked before SQLite replays it (a
// damaged log that would silently lose a commit is a FormatError), and the
// writer moves the log into the file every 32 frames and when it closes, so
// a writer that ends (normally or by an error) leaves every frame in the file
// itself. At those checkpoints, before save_index() and forget() write, and
// in close(), the writer checks that its path still names the file it
// writes: a file replaced (mv other.db FILE) or deleted under it is an
// IoError naming it, not frames silently written to a file no name reaches.
//
// Errors: a missing or unwritable file is IoError; a file that is not SQLite,
// is truncated, damaged (SQLite's quick_check, the checksums, blob sizes, ids,
// node order, the write-ahead log) or of a newer format is FormatError naming
// the file; options that do not match the stored ones are InvalidArgument
// naming the key.
//
// Thread safety: a Database is used by one thread at a time (it owns one
// sqlite3 connection and its prepared statements). One writer at a time: a
// Database opened for writing holds an exclusive lock on the file (flock)
// until destroyed, and a second writer, in this process or another, gets an
// IoError saying so. Readers may open it meanwhile.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/detector.h"

namespace lsgd::io {

// The format this lsgd writes and the newest it reads. Version 2 keeps the
// loop decision's state per frame, version 3 the caller's frame id, version 4
// every component's state as versioned records (the state column), version 5
// the search mode's saved index (the indexes table). Older
// files are read as they are and, opened for writing, upgraded in place
// (columns added, old rows kept as written; from version 1 its decision
// options reset to this version's defaults: version 1 thresholds were raw
// similarities, version 2's are in sigma).
constexpr int kDatabaseFormatVersion = 5;

// Whether restore() reads the saved index of the search mode (index mode's
// graph) or lets the detector rebuild it from the stored frames.
enum class IndexUse { kSaved, kRebuild };

// The frames of one session, as the caller numbered and named them.
struct StoredFrame {
  std::int64_t frame = 0;  // the caller's id (in files of format 1 and 2: the row id)
  std::string name;
};
struct SessionFrames {
  std::int64_t session = -1;
  // One past the id of the frame stored just before the session (0 for the
  // first), or, when frames before it were forgotten (Database::forget),
  // the id it was then: lsgd run numbers a session's frames first_id + image
  // index.
  std::int64_t first_id = 0;
  std::vector<StoredFrame> frames;  // in order; empty for an unknown session
};

struct SessionInfo {
  std::int64_t session = 0;
  std::int64_t frames = 0;
  std::int64_t first_frame = 0;  // smallest and largest caller id
  std::int64_t last_frame = 0;
};

struct DatabaseInfo {
  std::string path;
  int format_version = 0;
  std::string library_version;
  std::string options_yaml;
  int width = 0;  // 0 until the first frame
  int height = 0;
  GridSize grid;
  std::int64_t frames = 0;
  std::vector<SessionInfo> sessions;  // in the order they were stored
  std::int64_t nodes = 0;  // dynamic nodes (0 in exhaustive mode)
  std::int64_t index_frames = 0;  // frames the saved index covers (0: none saved)
  std::int64_t index_bytes = 0;   // ... and its size
  std::int64_t bytes = 0;  // size of the file plus its write-ahead log
  std::string note;        // Database::note()
};

class Database {
 public:
  enum class Mode { kReadOnly, kReadWrite };

  // Creates a new, empty database for detectors with `options` (validated).
  // Atomic: written to a temporary file beside `path` and linked into place,
  // so `path` either does not exist or is complete. Throws IoError when
  // `path` already exists or cannot be written.
  static Database create(const std::string& path, const DetectorOptions& options);

  // Opens an existing database and validates its header: SQLite quick_check,
  // tables, format version, meta checksum, options, dense frame ids. Throws
  // IoError when the file cannot be opened and FormatError when it is damaged,
  // not an lsgd database, or of a newer format.
  static Database open(const std::string& path, Mode mode = Mode::kReadWrite);

  ~Database();
  // Closes the file now, as the destructor does, but with what the
  // destructor can only swallow thrown: a writer's last checkpoint failing,
  // or IoError when its path no longer names the file it wrote (replaced,
  // moved or deleted meanwhile: the frames are not there). Closed in every
  // case; afterwards path(), options(), frames(), last_session(),
  // last_frame() and note() still answer, and every other call is an
  // InvalidArgument saying it is closed. Again: nothing.
  void close();
  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  const std::string& path() const;
  // The options stored at creation.
  const DetectorOptions& options() const;
  std::int64_t frames() const;
  // Session of the last frame; -1 when there is none.
  std::int64_t last_session() const;
  // The caller's id of the last frame; -1 when there is none.
  std::int64_t last_frame() const;
  // What open() found about the writer before this one: empty when it closed
  // the file, else that it was stopped (killed) and what was recovered.
  const std::string& note() const;
  // Reads in one snapshot: counts, sessions, nodes, size. Cheap: rows are
  // not checked (verify() does).
  DatabaseInfo info() const;
  // Checks every row as restore() would (types, sizes, checksums, node order,
  // places, ids), into a scratch detector; throws FormatError naming the file
  // and the first damaged frame.
  void verify() const;
  // The caller's id of every stored frame, in storage order (increasing).
  std::vector<std::int64_t> frame_ids() const;
  // The frames of `session` (empty when it has none).
  SessionFrames session_frames(std::int64_t session) const;

  // Throws InvalidArgument naming the first key whose value differs from the
  // stored one, with both values. Every option must match except
  // decision.threshold; options of a disabled stage or of the other search
  // mode are not compared.
  void check_compatible(const DetectorOptions& options) const;

  // Loads every stored frame into `detector`, which must be new (size() 0)
  // and have compatible options, in one read transaction. Afterwards the
  // detector processes the next frame exactly as one that had processed every
  // stored frame itself. Throws FormatError naming the file and frame for
  // damaged rows (detector then holds part of the frames: discard it).
  // The search mode's index (index mode's graph) is taken from the file when
  // save_index() stored one and `index` is kSaved, so it is not rebuilt: the
  // frames stored after it are indexed at the next query. A damaged saved
  // index is a FormatError (kRebuild ignores it).
  void restore(Detector& detector, IndexUse index = IndexUse::kSaved) const;

  // Forgets the frames whose caller ids lie in [first_id, last_id], in one
  // transaction (bounded working memory; a session the map no longer needs);
  // returns how many (0: none there, nothing changed). Afterwards restore()
  // gives the detector Detector::forget() leaves (the kept frames' records
  // renumbered: nodes keep their kept frames, places and loops that were
  // forgotten are none), the kept frames keep their ids, names and
  // sessions, the saved index is dropped (the next resume rebuilds it) and
  // the file gives the freed space back (VACUUM). Rows before the first
  // forgotten frame stay as written; every later one is written again.
  // lsgd run still resumes the last session at its next image. Throws
  // InvalidArgument for first_id > last_id or a database opened read-only,
  // FormatError (nothing changed) for a damaged row.
  std::int64_t forget(std::int64_t first_id, std::int64_t last_id);
  // Forgets every frame of `session`; InvalidArgument naming the sessions
  // there are when it has none.
  std::int64_t forget_session(std::int64_t session);

  // Saves the detector's search index (Detector::save_index) in place of the
  // one saved before, in one transaction, in parts of at most 64 MiB; the
  // detector must hold exactly the stored frames. Returns the frames it
  // covers (0: the mode keeps no index, nothing saved). Costs a write of the
  // whole graph (about 1.4 KB per 1241x376 frame), so a writer calls it when
  // it stops or now and then, not per frame; frames appended after it are
  // indexed again at the next resume.
  std::int64_t save_index(const Detector& detector);

  // Appends the detector's last frame, just processed (the detector must
  // hold frames() + 1 frames; `result` is what process() returned for it,
  // checked by its id against the detector's last: everything stored is
  // read from the detector, Detector::frame_state()), in one transaction. `session`: 0 .. kMaxSession, either the last
  // session or one without frames (a session's frames stay together).
  // `name` is free text (the image path). The frame's id is the detector's
  // (Detector::process(frame, id), id_of()), above every stored one; `frame`,
  // when given (>= 0), must be that id. Throws InvalidArgument for misuse,
  // IoError when the file cannot be written.
  void append(const Detector& detector, const Result& result, std::int64_t session,
              const std::string& name = "", std::int64_t frame = -1);

  // Appends every frame of `detector` not stored yet (ids frames() ..
  // detector.size() - 1) in one transaction, with empty names and the
  // detector's ids (above last_frame()). Node
  // membership comes from the detector; temporal places are known only for
  // its last max(agree, 1) frames (earlier rows get NULL, which restore()
  // never reads).
  void append_all(const Detector& detector, std::int64_t session);

 private:
  struct Impl;
  explicit Database(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace lsgd::io
