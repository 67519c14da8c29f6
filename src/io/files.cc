#include "lsgd/io/files.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <ios>
#include <vector>

#include "internal/check.h"
#include "internal/file_mode.h"
#include "internal/hash.h"
#include "lsgd/error.h"
#include "lsgd/limits.h"

namespace lsgd::io {

using internal::concat;

namespace {

// read_line's loop; the stream library's exceptions pass through.
bool read_line_from(std::istream& in, std::streambuf& buffer, std::string& line,
                    const std::string& file, std::int64_t number) {
  for (;;) {
    const int c = buffer.sbumpc();
    if (c == std::char_traits<char>::eof()) {
      in.setstate(std::ios::eofbit);
      if (line.empty()) in.setstate(std::ios::failbit);
      return !line.empty();
    }
    if (c == '\n') return true;
    if (c == '\r') {  // "\r\n", or a lone '\r' (classic Mac line endings)
      if (buffer.sgetc() == '\n') buffer.sbumpc();
      return true;
    }
    if (static_cast<std::int64_t>(line.size()) >= kMaxLineBytes) {
      throw FormatError(concat("line ", number, " of '", file, "' is longer than ", kMaxLineBytes,
                               " bytes: not a text file of this kind"));
    }
    line.push_back(static_cast<char>(c));
  }
}

}  // namespace

bool read_line(std::istream& in, std::string& line, const std::string& file, std::int64_t number) {
  line.clear();
  std::istream::sentry sentry(in, true);  // no whitespace skipped
  if (!sentry) return false;
  errno = 0;
  try {
    return read_line_from(in, *in.rdbuf(), line, file, number);
  } catch (const std::ios_base::failure&) {  // libstdc++'s filebuf on a failed read()
    const int error = errno;
    in.setstate(std::ios::badbit);
    throw IoError(concat("error while reading '", file, "' at line ", number, ": ",
                         error != 0 ? std::strerror(error) : "a read error"));
  }
}

std::vector<unsigned char> read_file(const std::string& path, const std::string& what,
                                     std::int64_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    if (error == EMFILE || error == ENFILE || error == ENOMEM) {
      throw ResourceError(concat("cannot read ", what, " '", path, "': ", std::strerror(error),
                                 " (the system's limit, not the file's fault)"));
    }
    throw IoError(concat("cannot read ", what, " '", path, "': ", std::strerror(error)));
  }
  struct Close {
    int fd;
    ~Close() { ::close(fd); }
  } close{fd};
  std::vector<unsigned char> bytes;
  struct stat st {};
  if (::fstat(fd, &st) == 0 && st.st_size > 0 && st.st_size <= max_bytes) {
    bytes.reserve(static_cast<std::size_t>(st.st_size));
  }
  unsigned char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof(chunk));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      throw IoError(concat("error while reading ", what, " '", path, "' (after ", bytes.size(),
                           " bytes): ", std::strerror(error)));
    }
    if (n == 0) return bytes;
    if (static_cast<std::int64_t>(bytes.size()) + n > max_bytes) {
      throw FormatError(concat(what, " '", path, "' has more than the ", max_bytes,
                               " bytes this lsgd reads"));
    }
    bytes.insert(bytes.end(), chunk, chunk + n);
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

namespace {

// The temporary file write_output_file() is writing, for the signal handler
// of remove_temporary_files_on_signal() (async-signal-safe: a fixed buffer,
// unlink()).
char g_temporary[4096];
volatile std::sig_atomic_t g_writing = 0;

extern "C" void remove_temporary_and_die(int signal) {
  if (g_writing) ::unlink(g_temporary);
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

struct Writing {
  explicit Writing(const std::string& temp) {
    if (temp.size() < sizeof(g_temporary)) {
      std::memcpy(g_temporary, temp.c_str(), temp.size() + 1);
      g_writing = 1;
    }
  }
  ~Writing() { g_writing = 0; }
};

}  // namespace

void remove_temporary_files_on_signal() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGXFSZ}) {
    struct sigaction action {};
    if (::sigaction(signal, nullptr, &action) != 0 || action.sa_handler == SIG_IGN) continue;
    // A file size limit (ulimit -f): the write that passes it fails with
    // EFBIG instead of killing the process, so the error names the file, as
    // a full disk's does, and the temporary file is removed on that path.
    action.sa_handler = signal == SIGXFSZ && action.sa_handler == SIG_DFL ? SIG_IGN : remove_temporary_and_die;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;
    ::sigaction(signal, &action, nullptr);
  }
}

void check_output_file(const std::string& path, const std::string& what) {
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) {
    throw IoError(concat("cannot write ", what, " '", path, "': it is a folder (give a file name)"));
  }
  if (exists && !S_ISREG(st.st_mode)) return;  // a device or pipe: written in place
  // A read-only file or folder is refused even for root (internal/file_mode.h).
  if (exists && (::access(path.c_str(), W_OK) != 0 || !internal::mode_allows_writing(st.st_mode))) {
    throw IoError(concat("cannot write ", what, " '", path, "': it is read-only (make it writable "
                         "or give another file)"));
  }
  const std::string folder = folder_of(path);
  struct stat in {};
  if (::stat(folder.c_str(), &in) != 0 || !S_ISDIR(in.st_mode)) {
    throw IoError(concat("cannot write ", what, " '", path, "': its folder '", folder, "' does not exist"));
  }
  if (!internal::mode_allows_writing(in.st_mode) || ::access(folder.c_str(), W_OK) != 0) {
    throw IoError(concat("cannot write ", what, " '", path, "': its folder '", folder, "' is read-only"));
  }
}

OutputLock::OutputLock(const std::string& path, const std::string& what) {
  // O_NONBLOCK: a FIFO without a reader is not waited for here (ENXIO).
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_NONBLOCK | O_CLOEXEC, 0666);
  if (fd < 0) return;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd);
    if (error != EWOULDBLOCK) return;  // no locks here (ENOLCK): written as before
    throw IoError(concat("cannot write ", what, " '", path, "': another process is writing it "
                         "(two commands given one output would mix their rows); give another "
                         "file, or wait for that one to end"));
  }
  fd_ = fd;
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);
}

OutputLock::OutputLock(OutputLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

OutputLock& OutputLock::operator=(OutputLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

void write_output_file(const std::string& path, const std::string& content,
                       const std::string& what) {
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  const bool stream = exists && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
  // A folder, a read-only file or one in a read-only or missing folder is
  // refused before anything is written (not even root replaces a read-only
  // file, nor does the rename below).
  if (!stream) check_output_file(path, what);
  if (stream) {  // a device or pipe: written in place, never replaced
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw IoError(concat("cannot write ", what, " '", path, "': ", std::strerror(errno)));
    const bool ok = write_all(fd, content);
    const int error = errno;
    ::close(fd);
    if (!ok) write_failed(what, path, error);
    return;
  }
  const std::string temp = temporary_beside(path);
  const Writing writing(temp);  // an interrupted write leaves no temporary file
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

std::string folder_of(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
}

std::size_t name_length(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path.size() : path.size() - slash - 1;
}

std::size_t name_limit(const std::string& path) {
  errno = 0;
  const long limit = ::pathconf(folder_of(path).c_str(), _PC_NAME_MAX);
  return limit > 0 ? static_cast<std::size_t>(limit) : 255;
}

std::string temporary_beside(const std::string& path, std::size_t reserve) {
  const std::string suffix = concat(".tmp-", ::getpid());
  if (name_length(path) + suffix.size() + reserve <= name_limit(path)) return path + suffix;
  // FNV-1a of the whole path: one name per output.
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(internal::fnv1a(path)));
  return path.substr(0, path.size() - name_length(path)) + ".lsgd-" + hex + suffix;
}

void throw_cannot_write(const std::string& path) {
  const int error = errno;
  std::string why = error != 0 ? std::strerror(error) : "unknown reason";
  char cwd[16];
  if (!path.empty() && path[0] != '/' && ::getcwd(cwd, sizeof(cwd)) == nullptr && errno == ENOENT) {
    why += "; the working folder no longer exists (give an absolute path, or cd into a folder)";
  }
  throw IoError("cannot write output file '" + path + "': " + why);
}

}  // namespace lsgd::io
