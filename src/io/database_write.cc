#include "lsgd/io/database.h"

#include "internal/numbers.h"
#include "io/database_internal.h"


#include <errno.h>
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <type_traits>

#include "internal/check.h"
#include "lsgd/error.h"
#include "io/wal_check.h"
#include "lsgd/io/config.h"
#include "lsgd/limits.h"
#include "lsgd/version.h"


namespace lsgd::io {

void Database::Impl::insert_frame(const Detector& detector, std::int64_t frame,
                                  std::int64_t session, const std::string& name,
                                  std::int64_t caller_id) {
  const DescriptorView view = detector.store().view(frame);
  const auto cells = static_cast<std::size_t>(view.cells);
  hist_bytes.clear();
  pixel_bytes.clear();
  if (view.storage() == HistogramStorage::kCompact) {
    hist_bytes.assign(view.compact, view.compact + cells * kCompactBins);
  } else {
    encode_le(view.hist, cells * kBins, hist_bytes);
    encode_le(view.pixels, cells, pixel_bytes);
  }
  const std::vector<std::uint8_t> state = detector.frame_state(frame);
  RowBytes row;
  row.id = frame;
  row.session = session;
  if (detector.search().has_groups()) row.node = detector.search().group_of(frame);
  row.frame = caller_id;
  row.name = name.data();
  row.name_size = static_cast<std::int64_t>(name.size());
  row.hist = hist_bytes.data();
  row.hist_size = static_cast<std::int64_t>(hist_bytes.size());
  row.pixels = pixel_bytes.data();
  row.pixels_size = static_cast<std::int64_t>(pixel_bytes.size());
  row.state = state.data();
  row.state_size = static_cast<std::int64_t>(state.size());
  sqlite3_stmt* s = insert.get();
  sqlite3_reset(s);
  sqlite3_clear_bindings(s);
  sqlite3_bind_int64(s, 1, frame);
  sqlite3_bind_int64(s, 2, session);
  sqlite3_bind_text(s, 3, name.c_str(), static_cast<int>(name.size()), SQLITE_STATIC);
  sqlite3_bind_blob(s, 4, hist_bytes.data(), static_cast<int>(hist_bytes.size()), SQLITE_STATIC);
  if (pixel_bytes.empty()) {  // compact storage: an empty blob, not NULL
    sqlite3_bind_zeroblob(s, 5, 0);
  } else {
    sqlite3_bind_blob(s, 5, pixel_bytes.data(), static_cast<int>(pixel_bytes.size()),
                      SQLITE_STATIC);
  }
  if (row.node != kNull) sqlite3_bind_int64(s, 6, row.node);
  sqlite3_bind_int64(s, 7, row_checksum(row));
  sqlite3_bind_int64(s, 8, caller_id);
  sqlite3_bind_blob(s, 9, state.data(), static_cast<int>(state.size()), SQLITE_STATIC);
  const int rc = sqlite3_step(s);
  sqlite3_reset(s);
  if (rc != SQLITE_DONE)
    io_error(path, "cannot write frame ", frame, " (", sqlite_message(db), ")");
}


void Database::Impl::check_session(std::int64_t session) const {
  if (session < 0 || session > kMaxSession) {
    internal::throw_invalid("database ", path, ": session ", session, " is outside [0, ",
                            kMaxSession, "]");
  }
  if (session != last_session && sessions.count(session) != 0) {
    internal::throw_invalid("database ", path, ": session ", session,
                            " has frames before session ", last_session,
                            "'s: a session's frames stay together, so only the last session "
                            "can be continued; choose a new session id");
  }
}

// What append() takes: a frame name a path can be, the detector's next frame
// with the Result process() returned for it, and an id above the last
// stored one. Returns the frame's id.
std::int64_t Database::Impl::check_append(const Detector& detector, const Result& result,
                                          const std::string& name, std::int64_t frame) const {
  // The image's name (a path, as lsgd run stores it): no NUL, which no path
  // holds, and not longer than a line of a list file.
  if (name.find('\0') != std::string::npos) {
    internal::throw_invalid("database ", path, ": the frame's name '", name.substr(0, name.find('\0')),
                            "\\0...' has a NUL character inside: no image has such a name");
  }
  if (static_cast<std::int64_t>(name.size()) > kMaxLineBytes) {
    internal::throw_invalid("database ", path, ": the frame's name is ", name.size(),
                            " bytes, more than ", kMaxLineBytes, " ('", name.substr(0, 40), "...')");
  }
  if (detector.size() == frames) {
    internal::throw_invalid("database ", path, ": every frame of the detector (", frames,
                            ") is stored already: append each frame once, right after process()");
  }
  if (detector.size() != frames + 1) {
    internal::throw_invalid("database ", path, ": append from a detector holding ",
                            detector.size(), " frames, but the database holds ", frames,
                            " (append each frame right after process())");
  }
  // The frame's id is the detector's (Detector::process(frame, id)): a
  // different one would be refused when the frame is restored.
  const std::int64_t own = detector.id_of(detector.size() - 1);
  // The Result must be the one process() returned for that frame: its id
  // (Result::frame may be a run's number, eval::run_detector) is the
  // detector's last; another detector's or a query's names another frame.
  if (result.id != own) {
    internal::throw_invalid("database ", path, ": the Result is of frame id ", result.id,
                            ", not of the detector's last frame (id ", own,
                            "): append the Result this detector's process() just returned");
  }
  if (frame < -1) {
    internal::throw_invalid("database ", path, ": frame id ", frame, " is negative (-1: the "
                            "detector's id of its last frame)");
  }
  if (frame >= 0 && frame != own) {
    internal::throw_invalid("database ", path, ": frame id ", frame, " is not the detector's id ", own,
                            " of its last frame (give the id to Detector::process)");
  }
  frame = own;
  if (frame <= last_frame || frame > kMaxFrameId) {
    internal::throw_invalid("database ", path, ": frame id ", frame, " must be above the last ",
                            "stored id ", last_frame, " and at most ", kMaxFrameId);
  }
  return frame;
}

void Database::append(const Detector& detector, const Result& result, std::int64_t session,
                      const std::string& name, std::int64_t frame) {
  Impl& m = *impl_;
  m.check_open();
  m.check_writable();
  m.check_session(session);
  frame = m.check_append(detector, result, name, frame);
  const std::string yaml = to_yaml(detector.options());
  if (yaml != m.checked_yaml) {
    check_compatible(detector.options());
    m.checked_yaml = yaml;
  }
  const std::int64_t dense = m.frames;  // the detector's id of its last frame
  m.transaction([&] {
    std::map<std::string, std::string> saved = m.meta;
    if (m.frames == 0) {
      m.meta["width"] = std::to_string(detector.width());
      m.meta["height"] = std::to_string(detector.height());
      m.meta["grid_rows"] = std::to_string(detector.store().grid().rows);
      m.meta["grid_cols"] = std::to_string(detector.store().grid().cols);
      try {
        m.write_meta();
      } catch (...) {
        m.meta = saved;
        throw;
      }
    }
    try {
      m.insert_frame(detector, dense, session, name, frame);
    } catch (...) {
      m.meta = saved;
      throw;
    }
  });
  if (m.frames == 0) {
    m.width = detector.width();
    m.height = detector.height();
    m.grid = detector.store().grid();
  }
  ++m.frames;
  m.last_session = session;
  m.last_frame = frame;
  m.sessions.insert(session);
  if (++m.since_checkpoint >= kCheckpointFrames) {
    m.checkpoint("open");
    m.check_same_file();  // every 32 frames: a file replaced under the writer is said
  }
}

void Database::append_all(const Detector& detector, std::int64_t session) {
  Impl& m = *impl_;
  m.check_open();
  m.check_writable();
  m.check_session(session);
  if (detector.size() < m.frames) {
    internal::throw_invalid("database ", m.path, ": the detector holds ", detector.size(),
                            " frames, fewer than the ", m.frames, " stored");
  }
  if (detector.size() == m.frames) return;
  check_compatible(detector.options());
  const std::int64_t first = m.frames;
  if (detector.id_of(first) <= m.last_frame) {
    internal::throw_invalid("database ", m.path, ": the detector's frame ", first, " has id ",
                            detector.id_of(first), ", not above the last stored id ", m.last_frame);
  }
  m.transaction([&] {
    const std::map<std::string, std::string> saved = m.meta;
    try {
      if (first == 0) {
        m.meta["width"] = std::to_string(detector.width());
        m.meta["height"] = std::to_string(detector.height());
        m.meta["grid_rows"] = std::to_string(detector.store().grid().rows);
        m.meta["grid_cols"] = std::to_string(detector.store().grid().cols);
        m.write_meta();
      }
      for (std::int64_t f = first; f < detector.size(); ++f) {
        m.insert_frame(detector, f, session, "", detector.id_of(f));
      }
    } catch (...) {
      m.meta = saved;
      throw;
    }
  });
  if (first == 0) {
    m.width = detector.width();
    m.height = detector.height();
    m.grid = detector.store().grid();
  }
  m.last_frame = detector.id_of(detector.size() - 1);
  m.frames = detector.size();
  m.last_session = session;
  m.sessions.insert(session);
  m.checkpoint("open");
  m.check_same_file();
}

namespace {

// The meta session_first_ids that forget() keeps, as a map and as its text.
struct FirstIds {
  std::map<std::int64_t, std::int64_t> ids;
  std::string text;  // "session=first_id" pairs separated by spaces
};

// Of the first ids lsgd run gave the sessions (`first_ids`), those of the
// kept `sessions` that the frames before them no longer give.
FirstIds kept_first_ids(const std::map<std::int64_t, std::int64_t>& first_ids,
                        const std::vector<FrameKeys>& rows, const std::set<std::int64_t>& sessions) {
  FirstIds kept;
  for (const auto& [session, id] : first_ids) {
    if (sessions.count(session) == 0) continue;
    const std::int64_t s = session;  // (C++17 lambdas cannot capture a structured binding)
    const auto at = std::find_if(rows.begin(), rows.end(), [s](const FrameKeys& r) { return r.session == s; });
    const std::int64_t before = at == rows.begin() ? 0 : std::prev(at)->id + 1;
    if (before == id) continue;
    kept.ids[session] = id;
    kept.text += concat(kept.text.empty() ? "" : " ", session, "=", id);
  }
  return kept;
}

}  // namespace

std::int64_t Database::forget(std::int64_t first_id, std::int64_t last_id) {
  Impl& m = *impl_;
  m.check_open();
  m.check_writable();
  if (first_id > last_id) {
    internal::throw_invalid("database ", m.path, ": forget: the first id ", first_id,
                            " is above the last ", last_id);
  }
  if (first_id < 0 || last_id > kMaxFrameId) {  // as lsgd db forget --frames refuses them
    internal::throw_invalid("database ", m.path, ": forget: ids ", first_id, " .. ", last_id,
                            " are outside the frame ids 0 .. ", kMaxFrameId);
  }
  m.check_same_file();  // before rewriting: the file at the path is the one to change
  std::vector<FrameKeys> rows = m.read_keys();
  const auto from = std::find_if(rows.begin(), rows.end(), [&](const FrameKeys& r) { return r.id >= first_id; });
  const auto to = std::find_if(from, rows.end(), [&](const FrameKeys& r) { return r.id > last_id; });
  const std::int64_t forgotten = to - from;
  if (forgotten == 0) return 0;
  const auto dense = static_cast<std::int64_t>(from - rows.begin());  // the first forgotten frame
  // The first id of every session as lsgd run numbered it, before any of
  // its earlier frames are gone.
  std::map<std::int64_t, std::int64_t> first_ids;
  for (const std::int64_t s : m.sessions) first_ids[s] = session_frames(s).first_id;
  // The kept frames' state: what the detector keeps when it forgets them.
  Detector detector(m.options);
  restore(detector, IndexUse::kRebuild);
  if (detector.forget(first_id, last_id) != forgotten) {
    format_error(m.path, "the rows' ids do not match their frames' state");
  }
  rows.erase(from, to);
  std::set<std::int64_t> sessions;
  for (const FrameKeys& r : rows) sessions.insert(r.session);
  FirstIds kept = kept_first_ids(first_ids, rows, sessions);
  m.rewrite_from(dense, detector, rows, kept.text);
  m.frames = detector.size();
  m.sessions = sessions;
  m.last_session = rows.empty() ? -1 : rows.back().session;
  m.last_frame = rows.empty() ? -1 : rows.back().id;
  m.session_first = std::move(kept.ids);
  if (rows.empty()) m.width = m.height = 0, m.grid = GridSize{0, 0};
  m.checkpoint("open");
  // The freed pages go back to the file system.
  exec_write(m.db, m.path, "VACUUM");
  m.checkpoint("open");
  return forgotten;
}

std::vector<FrameKeys> Database::Impl::read_keys() const {
  std::vector<FrameKeys> rows;
  Statement stmt(db, path,
                 concat("SELECT session, name, ", frame_column(format), " FROM frames ORDER BY id")
                     .c_str());
  while (step_read(db, stmt.get(), path)) {
    rows.push_back({sqlite3_column_int64(stmt.get(), 0), column_text(stmt.get(), 1),
                    sqlite3_column_int64(stmt.get(), 2)});
  }
  return rows;
}

void Database::Impl::rewrite_from(std::int64_t dense, const Detector& detector,
                                  const std::vector<FrameKeys>& rows, const std::string& first_ids) {
  transaction([&] {
    const std::map<std::string, std::string> saved = meta;
    try {
      Statement drop(db, path, "DELETE FROM frames WHERE id >= ?1");
      sqlite3_bind_int64(drop.get(), 1, dense);
      if (sqlite3_step(drop.get()) != SQLITE_DONE) io_error(path, "cannot write (", sqlite_message(db), ")");
      // The saved graph numbers the forgotten frames: the next resume builds it again.
      exec_write(db, path, "DELETE FROM indexes");
      for (std::int64_t f = dense; f < detector.size(); ++f) {
        const FrameKeys& r = rows[static_cast<std::size_t>(f)];
        insert_frame(detector, f, r.session, r.name, r.id);
      }
      if (first_ids.empty()) {
        meta.erase("session_first_ids");
        exec_write(db, path, "DELETE FROM meta WHERE key = 'session_first_ids'");
      } else {
        meta["session_first_ids"] = first_ids;
      }
      if (rows.empty()) {  // the next frame sets the size again
        for (const char* key : {"width", "height", "grid_rows", "grid_cols"}) meta[key] = "0";
      }
      write_meta();
    } catch (...) {
      meta = saved;
      throw;
    }
  });
}

std::int64_t Database::forget_session(std::int64_t session) {
  Impl& m = *impl_;
  m.check_open();
  m.check_writable();
  if (m.sessions.count(session) == 0) {
    std::string known;
    for (const std::int64_t s : m.sessions) known += concat(known.empty() ? "" : ", ", s);
    internal::throw_invalid("database ", m.path, ": session ", session, " has no frames (sessions: ",
                            known.empty() ? "none" : known, ")");
  }
  const SessionFrames frames = session_frames(session);
  // A session's frames are consecutive: the range of its ids holds no other.
  return forget(frames.frames.front().frame, frames.frames.back().frame);
}

std::int64_t Database::save_index(const Detector& detector) {
  Impl& m = *impl_;
  m.check_open();
  m.check_writable();
  if (detector.size() != m.frames) {
    internal::throw_invalid("database ", m.path, ": save_index needs the detector of the stored ",
                            m.frames, " frames; this one holds ", detector.size());
  }
  check_compatible(detector.options());
  m.check_same_file();
  std::vector<std::uint8_t> bytes;
  const std::int64_t covered = detector.save_index(bytes);
  const std::string mode = detector.search().name();
  m.transaction([&] {
    Statement drop(m.db, m.path, "DELETE FROM indexes WHERE mode = ?1");
    sqlite3_bind_text(drop.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
    if (sqlite3_step(drop.get()) != SQLITE_DONE) io_error(m.path, "cannot write (", sqlite_message(m.db), ")");
    Statement insert(m.db, m.path,
                     "INSERT INTO indexes(mode, part, frames, data, crc32) VALUES(?1, ?2, ?3, ?4, ?5)");
    std::int64_t part = 0;
    for (std::size_t at = 0; at < bytes.size(); at += kIndexPartBytes, ++part) {
      const std::size_t n = std::min(kIndexPartBytes, bytes.size() - at);
      sqlite3_stmt* s = insert.get();
      sqlite3_reset(s);
      sqlite3_bind_text(s, 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
      sqlite3_bind_int64(s, 2, part);
      sqlite3_bind_int64(s, 3, covered);
      sqlite3_bind_blob(s, 4, bytes.data() + at, static_cast<int>(n), SQLITE_STATIC);
      sqlite3_bind_int64(s, 5, crc_of(bytes.data() + at, n));
      if (sqlite3_step(s) != SQLITE_DONE) io_error(m.path, "cannot write (", sqlite_message(m.db), ")");
    }
  });
  m.checkpoint("open");
  return covered;
}

void Database::Impl::checkpoint(const char* state) {
  exec_write(db, path, "BEGIN IMMEDIATE");
  try {
    const std::map<std::string, std::string> saved = meta;
    meta["writer"] = state;
    meta["checkpoint_frames"] = std::to_string(frames);
    // Counts the checkpoints that moved something written into the file: a
    // log carries the count it began after, so a log older than the file (a
    // backup copying FILE-wal before FILE) is told apart (check_log_belongs).
    // A run that writes nothing (opened and closed) leaves the count, and the
    // file, as they were.
    if (sqlite3_total_changes64(db) != changes_at_checkpoint) {
      const auto count = meta.find("checkpoints");
      std::int64_t done = 0;
      if (count != meta.end() && !internal::parses_as(count->second, done)) done = 0;
      meta["checkpoints"] = std::to_string(done + 1);
    }
    try {
      write_meta();
    } catch (...) {
      meta = saved;
      throw;
    }
    exec_write(db, path, "COMMIT");
    changes_at_checkpoint = sqlite3_total_changes64(db);
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  // TRUNCATE waits (busy timeout) for readers of the log; if one still holds
  // it, the frames stay in the log until the next checkpoint.
  int log = -1, moved = -1;
  const int rc = sqlite3_wal_checkpoint_v2(db, nullptr, SQLITE_CHECKPOINT_TRUNCATE, &log, &moved);
  if (rc != SQLITE_OK && (rc & 0xFF) != SQLITE_BUSY) {
    io_error(path, "cannot checkpoint its write-ahead log (", sqlite_message(db), ")");
  }
  since_checkpoint = 0;
  log_named = false;  // a new log: its first transaction writes meta
}

}  // namespace lsgd::io
