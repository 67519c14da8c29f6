// Reading text and writing results, the same way everywhere: lines are
// bounded (a file without newlines is not read into memory), and a result is
// either written whole or not at all.
#pragma once

#include <cstdint>
#include <istream>
#include <string>

namespace lsgd::io {

// Reads the next line of `in` into `line`, without its ending: "\n",
// "\r\n" or a lone "\r" (files saved with classic Mac line endings read as
// the lines they show); false at the end. A line longer than kMaxLineBytes
// (lsgd/limits.h) is a FormatError naming `file` and the line number
// `number`, thrown before more than that is held in memory.
bool read_line(std::istream& in, std::string& line, const std::string& file, std::int64_t number);

// Writes `content` to `path` (`what` names it in errors: "JSON file",
// "report"). A regular file or a new path is written to a temporary file
// beside it and renamed over it, so a failure (a full disk) never leaves a
// half-written result where a good one was. A path that exists and is not
// a regular file (a terminal, /dev/null, a pipe: a stream the user chose) is
// written directly and never replaced. IoError naming the file and the
// system's reason.
void write_output_file(const std::string& path, const std::string& content,
                       const std::string& what);

}  // namespace lsgd::io
