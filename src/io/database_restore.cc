#include "lsgd/io/database.h"

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

void Database::restore(Detector& detector, IndexUse index) const {
  Impl& m = *impl_;
  if (detector.size() != 0) {
    internal::throw_invalid("database ", m.path, ": restore needs a new detector, this one holds ",
                            detector.size(), " frames");
  }
  check_compatible(detector.options());
  if (m.frames == 0) return;
  const DetectorOptions& o = detector.options();
  const bool nodes_mode = detector.search().has_groups();  // dynamic nodes
  const auto cells = static_cast<std::size_t>(m.grid.cells());

  // Compact storage keeps cells * kCompactBins bytes per frame and no pixel
  // counts (an empty pixels blob); exact storage 16-bit bins and counts.
  const bool compact = o.descriptor.storage == HistogramStorage::kCompact;
  const std::size_t hist_bytes =
      compact ? cells * kCompactBins * sizeof(CompactBin) : cells * kBins * sizeof(Bin);
  const std::size_t pixel_bytes = compact ? 0 : cells * sizeof(Count);
  Descriptor descriptor;
  descriptor.grid = m.grid;
  descriptor.storage = o.descriptor.storage;
  if (compact) {
    descriptor.cell_pixels = static_cast<double>(m.width) * m.height / static_cast<double>(cells);
  }
  // The descriptor's memory is committed when the first row shows a blob of
  // its size, so the meta's frame size alone never makes an allocation.
  const auto allocate = [&] {
    if (compact) {
      descriptor.compact.resize(cells * kCompactBins);
    } else {
      descriptor.hist.resize(cells * kBins);
      descriptor.pixels.resize(cells);
    }
  };
  std::vector<std::uint8_t> state;
  std::int64_t nodes = 0;  // dynamic nodes so far (the node column)

  // One read transaction: the rows and their count are one snapshot, even
  // while another process appends (a reader beside the writer).
  exec_write(m.db, m.path, "BEGIN");
  struct EndRead {
    sqlite3* db;
    ~EndRead() { sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr); }
  } end_read{m.db};
  Statement stmt(m.db, m.path, select_frames(m.format).c_str());
  std::int64_t id = 0;
  std::int64_t last_frame = -1;
  for (; step_read(m.db, stmt.get(), m.path); ++id) {
    sqlite3_stmt* s = stmt.get();
    const auto bad = [&](const auto&... parts) {
      format_error(m.path, "frame ", id, ": ", parts...);
    };
    const auto type = [&](int column) { return sqlite3_column_type(s, column); };
    if (type(0) != SQLITE_INTEGER || sqlite3_column_int64(s, 0) != id) bad("id is not ", id);
    if (type(1) != SQLITE_INTEGER || sqlite3_column_int64(s, 1) < 0)
      bad("session is not an integer >= 0");
    if (type(2) != SQLITE_TEXT) bad("name is not text");
    if (type(3) != SQLITE_BLOB || type(4) != SQLITE_BLOB) bad("histogram or pixels is not a blob");
    if (type(8) != SQLITE_INTEGER) bad("crc32 is not an integer");
    RowBytes row;
    row.id = id;
    row.session = sqlite3_column_int64(s, 1);
    row.hist = sqlite3_column_blob(s, 3);
    row.hist_size = sqlite3_column_bytes(s, 3);
    row.pixels = sqlite3_column_blob(s, 4);
    row.pixels_size = sqlite3_column_bytes(s, 4);
    if (row.hist_size != static_cast<std::int64_t>(hist_bytes)) {
      bad("histogram blob has ", row.hist_size, " bytes, expected ", hist_bytes, " (", m.grid.rows,
          "x", m.grid.cols, " cells of ",
          compact ? "128 8-bit bins, descriptor.storage compact"
                  : "256 16-bit bins, descriptor.storage exact",
          ")");
    }
    if (row.pixels_size != static_cast<std::int64_t>(pixel_bytes)) {
      bad("pixels blob has ", row.pixels_size, " bytes, expected ", pixel_bytes);
    }
    if (id == 0) allocate();
    // The node column: the dynamic node of the frame, kept beside its state
    // for db info and inspection.
    if (nodes_mode) {
      if (type(5) != SQLITE_INTEGER) bad("node is not an integer (search mode nodes)");
      row.node = sqlite3_column_int64(s, 5);
      if (row.node < 0 || row.node > nodes) {
        bad("node ", row.node, " does not exist yet (", nodes, " nodes before this frame)");
      }
      if (row.node == nodes) ++nodes;
    } else if (type(5) != SQLITE_NULL) {
      bad("has a node but the search mode is ", o.search.mode);
    }
    if (type(6) == SQLITE_INTEGER) {
      row.place = sqlite3_column_int64(s, 6);
    } else if (type(6) != SQLITE_NULL) {
      bad("place is not an integer");
    }
    if (type(7) == SQLITE_BLOB) {
      row.features = sqlite3_column_blob(s, 7);
      row.features_size = sqlite3_column_bytes(s, 7);
    } else if (type(7) != SQLITE_NULL) {
      bad("features is not a blob");
    }
    if (type(10) == SQLITE_FLOAT || type(10) == SQLITE_INTEGER) {
      if (type(9) != SQLITE_INTEGER) bad("loop is not an integer");
      row.loop = sqlite3_column_int64(s, 9);
      row.has_loop_inliers = true;
      row.loop_inliers = sqlite3_column_double(s, 10);
    } else if (type(10) != SQLITE_NULL || type(9) != SQLITE_NULL) {
      bad("loop_inliers is not a number");
    }
    if (type(11) == SQLITE_INTEGER) {
      row.frame = sqlite3_column_int64(s, 11);
      if (row.frame <= last_frame || row.frame > kMaxFrameId) {
        bad("frame id ", row.frame, " is not above the previous frame's ", last_frame,
            " and at most ", kMaxFrameId);
      }
    } else if (type(11) != SQLITE_NULL) {
      bad("frame is not an integer");
    } else if (id <= last_frame) {
      bad("has no frame id, and its row id ", id, " is not above the previous frame's ",
          last_frame);
    }
    if (type(12) == SQLITE_BLOB) {
      if (row.place != kNull || row.features_size >= 0 || row.has_loop_inliers) {
        bad("has both a state and the place, features or loop columns of older formats");
      }
      row.state = sqlite3_column_blob(s, 12);
      row.state_size = sqlite3_column_bytes(s, 12);
    } else if (type(12) != SQLITE_NULL) {
      bad("state is not a blob");
    }
    last_frame = row.frame == kNull ? id : row.frame;
    const std::string name = column_text(s, 2);  // after the blobs: text conversion is not needed
    row.name = name.data();
    row.name_size = static_cast<std::int64_t>(name.size());
    const std::uint32_t crc = row_checksum(row);
    if (static_cast<std::int64_t>(crc) != sqlite3_column_int64(s, 8)) {
      bad("checksum ", sqlite3_column_int64(s, 8), " does not match the row (", crc,
          "): the file was modified or damaged");
    }

    if (compact) {
      std::memcpy(descriptor.compact.data(), row.hist, hist_bytes);
    } else {
      decode_le(static_cast<const std::uint8_t*>(row.hist), cells * kBins, descriptor.hist.data());
      decode_le(static_cast<const std::uint8_t*>(row.pixels), cells, descriptor.pixels.data());
    }
    if (row.state_size >= 0) {
      const auto* bytes = static_cast<const std::uint8_t*>(row.state);
      state.assign(bytes, bytes + row.state_size);
    } else {
      // A row of format 1 to 3: its columns as the components' records.
      std::vector<StateRecord> records;
      const auto i64 = [](std::int64_t v) {
        StateWriter w;
        w.put_i64(v);
        return w.bytes();
      };
      if (nodes_mode) legacy_record(records, detector.search().name(), i64(row.node));
      if (row.place != kNull) legacy_record(records, kTemporalStage, i64(row.place));
      if (row.features_size >= 0) {
        const auto* bytes = static_cast<const std::uint8_t*>(row.features);
        legacy_record(records, kGeometricStage, {bytes, bytes + row.features_size});
      }
      if (row.has_loop_inliers) {
        StateWriter w;
        w.put_i64(row.loop);
        w.put_f64(row.loop_inliers);
        legacy_record(records, "decision", w.bytes());
      }
      state = encode_records(records);
    }
    try {
      detector.restore_frame(m.width, m.height, descriptor, state, last_frame);
    } catch (const InvalidArgument& e) {
      bad(e.what());
    }
    if (nodes_mode && detector.search().group_of(id) != row.node) {
      bad("node column ", row.node, " differs from the node in its state, ",
          detector.search().group_of(id));
    }
  }
  if (id != m.frames) {
    if (m.writable) {  // we hold the writer's lock: nothing else appends
      format_error(m.path, "read ", id, " frames but the database held ", m.frames, " at open");
    }
    m.frames = id;  // a writer appended since open: this snapshot holds more
    m.last_frame = last_frame;
  }
  if (index == IndexUse::kSaved) {
    std::vector<std::uint8_t> bytes;
    if (m.read_index(detector.search().name(), id, bytes) > 0) {
      try {
        detector.restore_index(bytes.data(), bytes.size());
      } catch (const InvalidArgument& e) {
        format_error(m.path, "the saved index of search mode ", detector.search().name(), ": ",
                     e.what(), " (restore with IndexUse::kRebuild, lsgd run --rebuild-index, to "
                     "ignore it)");
      }
    }
  }
}

// The saved index of `mode` as one blob (its parts in order, each checked
// against its checksum); returns the frames it covers, 0 when there is none.
std::int64_t Database::Impl::read_index(const std::string& mode, std::int64_t stored,
                                        std::vector<std::uint8_t>& out) const {
  out.clear();
  if (format < 5) return 0;
  {
    // One allocation for the whole blob (a graph of 10^6 frames is ~1.4 GB).
    Statement size(db, path, "SELECT sum(length(data)) FROM indexes WHERE mode = ?1");
    sqlite3_bind_text(size.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
    if (step_read(db, size.get(), path) && sqlite3_column_type(size.get(), 0) == SQLITE_INTEGER) {
      out.reserve(static_cast<std::size_t>(std::max<sqlite3_int64>(0, sqlite3_column_int64(size.get(), 0))));
    }
  }
  Statement stmt(db, path, "SELECT part, frames, data, crc32 FROM indexes WHERE mode = ?1 ORDER BY part");
  sqlite3_bind_text(stmt.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
  std::int64_t covered = -1, part = 0;
  while (step_read(db, stmt.get(), path)) {
    sqlite3_stmt* s = stmt.get();
    const auto bad = [&](const auto&... parts) {
      format_error(path, "the saved index of search mode ", mode, ", part ", part, ": ", parts...,
                   " (restore with IndexUse::kRebuild, lsgd run --rebuild-index, to ignore it)");
    };
    if (sqlite3_column_type(s, 0) != SQLITE_INTEGER || sqlite3_column_int64(s, 0) != part) {
      bad("parts are not numbered 0, 1, 2, ...");
    }
    if (sqlite3_column_type(s, 1) != SQLITE_INTEGER) bad("frames is not an integer");
    const std::int64_t f = sqlite3_column_int64(s, 1);
    if (f < 1 || f > stored || (covered >= 0 && f != covered)) {
      bad("covers ", f, " frames (", stored, " stored", covered >= 0 ? concat(", part 0 says ", covered) : "",
          ")");
    }
    covered = f;
    if (sqlite3_column_type(s, 2) != SQLITE_BLOB || sqlite3_column_type(s, 3) != SQLITE_INTEGER) {
      bad("data is not a blob or crc32 not an integer");
    }
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s, 2));
    const auto size = static_cast<std::size_t>(sqlite3_column_bytes(s, 2));
    const std::uint32_t crc = crc_of(data, size);
    if (static_cast<std::int64_t>(crc) != sqlite3_column_int64(s, 3)) {
      bad("checksum ", sqlite3_column_int64(s, 3), " does not match its data (", crc,
          "): the file was modified or damaged");
    }
    out.insert(out.end(), data, data + size);
    ++part;
  }
  return covered < 0 ? 0 : covered;
}


}  // namespace lsgd::io
