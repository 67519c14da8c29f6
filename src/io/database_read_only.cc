// A database on a read-only file system or in a folder this user cannot
// write (a map shipped on read-only media, a container's read-only volume).
// SQLite reads a WAL database through its shared index, FILE-shm, which it
// creates beside the file; where that cannot be created, the file is read
// as immutable (SQLite's `immutable=1`: no locks, no -shm), which is exact
// as long as nothing is in the log and nobody writes.
#include <errno.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <string>

#include "io/database_internal.h"

namespace lsgd::io {

bool companions_cannot_be_created(const std::string& path) {
  struct statvfs fs {};
  if (::statvfs(path.c_str(), &fs) == 0 && (fs.f_flag & ST_RDONLY) != 0) return true;
  const std::size_t slash = path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  return ::access(folder.c_str(), W_OK) != 0 && errno != ENOENT;
}

std::string immutable_uri(const std::string& path) {
  std::string absolute = path;
  if (path.empty() || path[0] != '/') {
    if (char* cwd = ::getcwd(nullptr, 0)) {
      absolute = std::string(cwd) + "/" + path;
      std::free(cwd);
    }
  }
  // file:///a/b for /a/b (an empty authority, so that //a/b stays a path);
  // a relative path (no working folder) as file:a/b. Every byte but the
  // unreserved ones and '/' is percent-encoded ('?', '#' and '%' must be).
  std::string uri = absolute[0] == '/' ? "file://" : "file:";
  static const char kHex[] = "0123456789ABCDEF";
  for (const unsigned char c : absolute) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '-' || c == '_' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += '%';
      uri += kHex[c >> 4];
      uri += kHex[c & 15];
    }
  }
  return uri + "?immutable=1";
}

}  // namespace lsgd::io
