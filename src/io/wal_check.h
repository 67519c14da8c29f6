// Checks an SQLite write-ahead log before SQLite opens it (internal to lsgd_io).
//
// SQLite replays a WAL's frames up to the first one whose checksum fails and
// silently ignores the rest: a damaged log loses committed transactions and
// nothing says so. check_wal reads the log itself (format: sqlite.org,
// "Database File Format", section "The Write-Ahead Log") and reports the
// damage that would lose a commit.
#pragma once

#include <cstdint>
#include <string>

namespace lsgd::io::wal {

struct WalCheck {
  std::int64_t bytes = 0;            // size of the log file (0: absent or empty)
  std::int64_t valid_frames = 0;     // frames SQLite will replay ...
  std::int64_t committed_frames = 0; // ... of which up to the last commit count
  // Non-empty when a commit would be lost: what is wrong, for the error message.
  std::string damage;
};

// Reads `wal_path` (absent: an empty result). A log whose valid frames end in
// an incomplete transaction (a writer killed mid-commit) is not damaged: that
// transaction was never committed. A log whose header is invalid while it
// holds frames, or in which a complete frame of the current log generation
// marking a commit follows the first invalid frame, is damaged. Throws
// nothing; an unreadable log is reported in `damage`.
WalCheck check_wal(const std::string& wal_path);

}  // namespace lsgd::io::wal
