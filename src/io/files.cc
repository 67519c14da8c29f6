#include "lsgd/io/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/limits.h"

namespace lsgd::io {

using internal::concat;

bool read_line(std::istream& in, std::string& line, const std::string& file, std::int64_t number) {
  line.clear();
  std::istream::sentry sentry(in, true);  // no whitespace skipped
  if (!sentry) return false;
  std::streambuf* buffer = in.rdbuf();
  for (;;) {
    const int c = buffer->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      in.setstate(std::ios::eofbit);
      if (line.empty()) in.setstate(std::ios::failbit);
      return !line.empty();
    }
    if (c == '\n') return true;
    if (c == '\r') {  // "\r\n", or a lone '\r' (classic Mac line endings)
      if (buffer->sgetc() == '\n') buffer->sbumpc();
      return true;
    }
    if (static_cast<std::int64_t>(line.size()) >= kMaxLineBytes) {
      throw FormatError(concat("line ", number, " of '", file, "' is longer than ", kMaxLineBytes,
                               " bytes: not a text file of this kind"));
    }
    line.push_back(static_cast<char>(c));
  }
}

namespace {

[[noreturn]] void write_failed(const std::string& what, const std::string& path, int error) {
  throw IoError(concat("error while writing ", what, " '", path, "': ", std::strerror(error),
                       error == ENOSPC ? " (the disk is full)" : ""));
}

// Writes all of `content` to `fd`; false with errno set on failure.
bool write_all(int fd, const std::string& content) {
  const char* p = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

void write_output_file(const std::string& path, const std::string& content,
                       const std::string& what) {
  struct stat st {};
  const bool stream = ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
  if (stream) {  // a device or pipe: written in place, never replaced
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw IoError(concat("cannot write ", what, " '", path, "': ", std::strerror(errno)));
    const bool ok = write_all(fd, content);
    const int error = errno;
    ::close(fd);
    if (!ok) write_failed(what, path, error);
    return;
  }
  const std::string temp = concat(path, ".tmp-", ::getpid());
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(concat("cannot write ", what, " '", path, "': ", std::strerror(errno)));
  bool ok = write_all(fd, content);
  int error = errno;
  if (ok && ::fsync(fd) != 0) ok = false, error = errno;
  if (::close(fd) != 0 && ok) ok = false, error = errno;
  if (!ok) {
    std::remove(temp.c_str());
    write_failed(what, path, error);
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    error = errno;
    std::remove(temp.c_str());
    throw IoError(concat("cannot write ", what, " '", path, "': ", std::strerror(error)));
  }
}

}  // namespace lsgd::io
