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

namespace {

// The descriptor restore() decodes each frame row into, and the sizes of the
// rows' blobs. Compact storage keeps cells * kCompactBins bytes per frame and
// no pixel counts (an empty pixels blob); exact storage 16-bit bins and counts.
struct RowDescriptor {
  bool compact;
  std::size_t cells;
  std::size_t hist_bytes;
  std::size_t pixel_bytes;
  Descriptor descriptor;

  RowDescriptor(GridSize grid, int width, int height, HistogramStorage storage)
      : compact(storage == HistogramStorage::kCompact),
        cells(static_cast<std::size_t>(grid.cells())),
        hist_bytes(compact ? cells * kCompactBins * sizeof(CompactBin) : cells * kBins * sizeof(Bin)),
        pixel_bytes(compact ? 0 : cells * sizeof(Count)) {
    descriptor.grid = grid;
    descriptor.storage = storage;
    if (compact) {
      descriptor.cell_pixels = static_cast<double>(width) * height / static_cast<double>(cells);
    }
  }

  // The descriptor's memory is committed when the first row shows a blob of
  // its size, so the meta's frame size alone never makes an allocation.
  void allocate() {
    if (compact) {
      descriptor.compact.resize(cells * kCompactBins);
    } else {
      descriptor.hist.resize(cells * kBins);
      descriptor.pixels.resize(cells);
    }
  }

  // The row's blobs (their sizes checked) into the descriptor.
  void decode(const RowBytes& row) {
    if (compact) {
      std::memcpy(descriptor.compact.data(), row.hist, hist_bytes);
    } else {
      decode_le(static_cast<const std::uint8_t*>(row.hist), cells * kBins, descriptor.hist.data());
      decode_le(static_cast<const std::uint8_t*>(row.pixels), cells, descriptor.pixels.data());
    }
  }
};

// Reads the frame rows of one select_frames() statement, checking every
// column in the order restore() always has; keeps what the next row is
// checked against (its id, the previous frame id, the nodes so far).
class RowReader {
 public:
  RowReader(sqlite3_stmt* s, const std::string& path, const std::string& search_mode, bool nodes_mode)
      : s_(s), path_(path), search_mode_(search_mode), nodes_mode_(nodes_mode) {}

  // Row `id`'s keys, the types of its required columns and its blobs' sizes.
  RowBytes read_blobs(std::int64_t id, const RowDescriptor& layout) {
    id_ = id;
    if (type(0) != SQLITE_INTEGER || sqlite3_column_int64(s_, 0) != id) bad("id is not ", id);
    if (type(1) != SQLITE_INTEGER || sqlite3_column_int64(s_, 1) < 0)
      bad("session is not an integer >= 0");
    if (type(2) != SQLITE_TEXT) bad("name is not text");
    if (type(3) != SQLITE_BLOB || type(4) != SQLITE_BLOB) bad("histogram or pixels is not a blob");
    if (type(8) != SQLITE_INTEGER) bad("crc32 is not an integer");
    RowBytes row;
    row.id = id;
    row.session = sqlite3_column_int64(s_, 1);
    row.hist = sqlite3_column_blob(s_, 3);
    row.hist_size = sqlite3_column_bytes(s_, 3);
    row.pixels = sqlite3_column_blob(s_, 4);
    row.pixels_size = sqlite3_column_bytes(s_, 4);
    if (row.hist_size != static_cast<std::int64_t>(layout.hist_bytes)) {
      const GridSize& grid = layout.descriptor.grid;
      bad("histogram blob has ", row.hist_size, " bytes, expected ", layout.hist_bytes, " (",
          grid.rows, "x", grid.cols, " cells of ",
          layout.compact ? "128 8-bit bins, descriptor.storage compact"
                         : "256 16-bit bins, descriptor.storage exact",
          ")");
    }
    if (row.pixels_size != static_cast<std::int64_t>(layout.pixel_bytes)) {
      bad("pixels blob has ", row.pixels_size, " bytes, expected ", layout.pixel_bytes);
    }
    return row;
  }

  // The row's other columns, then its checksum over them all.
  void read_columns(RowBytes& row) {
    read_node(row);
    read_older_columns(row);
    read_frame_id(row);
    read_state(row);
    last_frame_ = row.frame == kNull ? id_ : row.frame;
    check_checksum(row);
  }

  // The caller's id of the last row read (-1 before the first).
  std::int64_t last_frame() const { return last_frame_; }

  template <typename... Parts>
  [[noreturn]] void bad(const Parts&... parts) const {
    format_error(path_, "frame ", id_, ": ", parts...);
  }

 private:
  int type(int column) const { return sqlite3_column_type(s_, column); }

  // The node column: the dynamic node of the frame, kept beside its state
  // for db info and inspection.
  void read_node(RowBytes& row) {
    if (nodes_mode_) {
      if (type(5) != SQLITE_INTEGER) bad("node is not an integer (search mode nodes)");
      row.node = sqlite3_column_int64(s_, 5);
      if (row.node < 0 || row.node > nodes_) {
        bad("node ", row.node, " does not exist yet (", nodes_, " nodes before this frame)");
      }
      if (row.node == nodes_) ++nodes_;
    } else if (type(5) != SQLITE_NULL) {
      bad("has a node but the search mode is ", search_mode_);
    }
  }

  // The place, features and loop columns of formats 1 to 3 (NULL in later rows).
  void read_older_columns(RowBytes& row) {
    if (type(6) == SQLITE_INTEGER) {
      row.place = sqlite3_column_int64(s_, 6);
    } else if (type(6) != SQLITE_NULL) {
      bad("place is not an integer");
    }
    if (type(7) == SQLITE_BLOB) {
      row.features = sqlite3_column_blob(s_, 7);
      row.features_size = sqlite3_column_bytes(s_, 7);
    } else if (type(7) != SQLITE_NULL) {
      bad("features is not a blob");
    }
    if (type(10) == SQLITE_FLOAT || type(10) == SQLITE_INTEGER) {
      if (type(9) != SQLITE_INTEGER) bad("loop is not an integer");
      row.loop = sqlite3_column_int64(s_, 9);
      row.has_loop_inliers = true;
      row.loop_inliers = sqlite3_column_double(s_, 10);
    } else if (type(10) != SQLITE_NULL || type(9) != SQLITE_NULL) {
      bad("loop_inliers is not a number");
    }
  }

  void read_frame_id(RowBytes& row) const {
    if (type(11) == SQLITE_INTEGER) {
      row.frame = sqlite3_column_int64(s_, 11);
      if (row.frame <= last_frame_ || row.frame > kMaxFrameId) {
        bad("frame id ", row.frame, " is not above the previous frame's ", last_frame_,
            " and at most ", kMaxFrameId);
      }
    } else if (type(11) != SQLITE_NULL) {
      bad("frame is not an integer");
    } else if (id_ <= last_frame_) {
      bad("has no frame id, and its row id ", id_, " is not above the previous frame's ",
          last_frame_);
    }
  }

  void read_state(RowBytes& row) const {
    if (type(12) == SQLITE_BLOB) {
      if (row.place != kNull || row.features_size >= 0 || row.has_loop_inliers) {
        bad("has both a state and the place, features or loop columns of older formats");
      }
      row.state = sqlite3_column_blob(s_, 12);
      row.state_size = sqlite3_column_bytes(s_, 12);
    } else if (type(12) != SQLITE_NULL) {
      bad("state is not a blob");
    }
  }

  void check_checksum(RowBytes& row) const {
    const std::string name = column_text(s_, 2);  // after the blobs: text conversion is not needed
    row.name = name.data();
    row.name_size = static_cast<std::int64_t>(name.size());
    const std::uint32_t crc = row_checksum(row);
    if (static_cast<std::int64_t>(crc) != sqlite3_column_int64(s_, 8)) {
      bad("checksum ", sqlite3_column_int64(s_, 8), " does not match the row (", crc,
          "): the file was modified or damaged");
    }
  }

  sqlite3_stmt* s_;
  const std::string& path_;
  const std::string& search_mode_;
  bool nodes_mode_;
  std::int64_t id_ = 0;
  std::int64_t last_frame_ = -1;
  std::int64_t nodes_ = 0;  // dynamic nodes so far (the node column)
};

// The migration of a row of format 1 to 3 to format 4's state blob: its
// columns as the components' records (`search`: the nodes mode's name, or
// nullptr in the other search modes).
std::vector<std::uint8_t> legacy_state(const RowBytes& row, const char* search) {
  std::vector<StateRecord> records;
  const auto i64 = [](std::int64_t v) {
    StateWriter w;
    w.put_i64(v);
    return w.bytes();
  };
  if (search) legacy_record(records, search, i64(row.node));
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
  return encode_records(records);
}

}  // namespace

void Database::restore(Detector& detector, IndexUse index) const {
  Impl& m = *impl_;
  m.check_open();
  if (detector.size() != 0) {
    internal::throw_invalid("database ", m.path, ": restore needs a new detector, this one holds ",
                            detector.size(), " frames");
  }
  check_compatible(detector.options());
  if (m.frames == 0) return;

  // One read transaction: the rows and their count are one snapshot, even
  // while another process appends (a reader beside the writer).
  exec_write(m.db, m.path, "BEGIN");
  struct EndRead {
    sqlite3* db;
    ~EndRead() { sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr); }
  } end_read{m.db};
  const auto [id, last_frame] = m.restore_frames(detector);
  if (id != m.frames) {
    if (m.writable) {  // we hold the writer's lock: nothing else appends
      format_error(m.path, "read ", id, " frames but the database held ", m.frames, " at open");
    }
    m.frames = id;  // a writer appended since open: this snapshot holds more
    m.last_frame = last_frame;
  }
  if (index == IndexUse::kSaved) m.restore_index(detector, id);
}

std::pair<std::int64_t, std::int64_t> Database::Impl::restore_frames(Detector& detector) const {
  const DetectorOptions& o = detector.options();
  const bool nodes_mode = detector.search().has_groups();  // dynamic nodes
  const FrameSize work = working_size(width, height, o.segmentation);  // what was described
  RowDescriptor layout(grid, work.width, work.height, o.descriptor.storage);
  std::vector<std::uint8_t> state;
  Statement stmt(db, path, select_frames(format).c_str());
  RowReader rows(stmt.get(), path, o.search.mode, nodes_mode);
  std::int64_t id = 0;
  for (; step_read(db, stmt.get(), path); ++id) {
    RowBytes row = rows.read_blobs(id, layout);
    if (id == 0) layout.allocate();
    rows.read_columns(row);
    layout.decode(row);
    if (row.state_size >= 0) {
      const auto* bytes = static_cast<const std::uint8_t*>(row.state);
      state.assign(bytes, bytes + row.state_size);
    } else {
      state = legacy_state(row, nodes_mode ? detector.search().name() : nullptr);
    }
    try {
      detector.restore_frame(width, height, layout.descriptor, state, rows.last_frame());
    } catch (const InvalidArgument& e) {
      rows.bad(e.what());
    }
    if (nodes_mode && detector.search().group_of(id) != row.node) {
      rows.bad("node column ", row.node, " differs from the node in its state, ",
               detector.search().group_of(id));
    }
  }
  return {id, rows.last_frame()};
}

void Database::Impl::restore_index(Detector& detector, std::int64_t stored) const {
  std::vector<std::uint8_t> bytes;
  if (read_index(detector.search().name(), stored, bytes) > 0) {
    try {
      detector.restore_index(bytes.data(), bytes.size());
    } catch (const InvalidArgument& e) {
      format_error(path, "the saved index of search mode ", detector.search().name(), ": ",
                   e.what(), " (restore with IndexUse::kRebuild, lsgd run --rebuild-index, to "
                   "ignore it)");
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
