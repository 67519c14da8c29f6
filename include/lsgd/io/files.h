// Reading text and writing results, the same way everywhere: lines are
// bounded (a file without newlines is not read into memory), and a result is
// either written whole or not at all.
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <vector>

namespace lsgd::io {

// Reads the next line of `in` into `line`, without its ending: "\n",
// "\r\n" or a lone "\r" (files saved with classic Mac line endings read as
// the lines they show); false at the end. A line longer than kMaxLineBytes
// (lsgd/limits.h) is a FormatError naming `file` and the line number
// `number`, thrown before more than that is held in memory.
// A read error of the system (EIO) is an IoError naming `file`, the line and
// the reason (the stream library's own exception says neither).
bool read_line(std::istream& in, std::string& line, const std::string& file, std::int64_t number);

// The whole of file `path` (`what` names it in errors: "image", "config"):
// at most `max_bytes`, a FormatError beyond, also for a file that grows while
// it is read; IoError naming the file and the system's reason when it cannot
// be opened or a read fails (EIO), never the stream library's bare message.
std::vector<unsigned char> read_file(const std::string& path, const std::string& what,
                                     std::int64_t max_bytes);

// Writes `content` to `path` (`what` names it in errors: "JSON file",
// "report"). A regular file or a new path is written to a temporary file
// beside it and renamed over it, so a failure (a full disk) never leaves a
// half-written result where a good one was. A path that exists and is not
// a regular file (a terminal, /dev/null, a pipe: a stream the user chose) is
// written directly and never replaced. IoError naming the file and the
// system's reason.
// IoError "cannot write output file 'PATH': <errno's reason>" (with a hint
// when a relative PATH's working folder was deleted); call it right after the
// failed open or write, while errno is the failure's.
[[noreturn]] void throw_cannot_write(const std::string& path);

void write_output_file(const std::string& path, const std::string& content,
                       const std::string& what);
// What write_output_file() checks before it writes, for callers that can
// check before their work: IoError naming `what` and the file when `path` is
// a folder, a read-only file, or in a folder that is missing or read-only
// (a device or a pipe passes: it is written in place).
void check_output_file(const std::string& path, const std::string& what);

// A file a command writes row by row as it works (lsgd run's and eval's CSV,
// lsgd sweep's tables), held against a second writer for as long as this
// object lives: an exclusive flock(2) taken before anything is truncated, so
// two commands given one output no longer interleave their rows (each
// truncated the file and wrote at its own offset; both exited 0). Only a
// regular file (or a new path, created here) is locked: a device, a pipe or
// standard output may have many writers. IoError naming `what` and the file
// when another writer (another process, or another OutputLock in this one)
// holds it, nothing changed; a file that cannot be opened here is left to
// the writer's own open, which says why.
class OutputLock {
 public:
  OutputLock() = default;
  OutputLock(const std::string& path, const std::string& what);
  ~OutputLock();
  OutputLock(OutputLock&& other) noexcept;
  OutputLock& operator=(OutputLock&& other) noexcept;
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  int fd_ = -1;
};

// The folder holding `path` ("." for a bare name, "/" for a file in /).
std::string folder_of(const std::string& path);
// The length of the last component of `path` (its file name), in bytes.
std::size_t name_length(const std::string& path);
// The longest file name the folder of `path` takes (pathconf's NAME_MAX;
// 255 when the folder does not say or does not exist yet).
std::size_t name_limit(const std::string& path);
// A temporary file beside `path`, for writing it whole and renaming it over:
// PATH.tmp-PID, or, when that name and `reserve` more bytes (suffixes the
// writer adds, as SQLite's -journal) would not fit the folder's name limit,
// a short name in the same folder (.lsgd-HASH.tmp-PID): a legal 255-byte
// output name still gets its temporary file.
std::string temporary_beside(const std::string& path, std::size_t reserve = 0);

// Installs handlers of SIGINT, SIGTERM and SIGHUP (those not ignored) that
// remove the temporary file write_output_file() is writing, then end the
// process by the signal as before; SIGXFSZ (a file size limit reached), when
// it would end the process, is ignored instead, so that the write fails with
// EFBIG and its error names the file. For programs (lsgd calls it first).
void remove_temporary_files_on_signal();

}  // namespace lsgd::io
