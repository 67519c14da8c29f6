// The process's table of open database files, by file identity (device,
// inode): which Database objects have each file open, which one writes it,
// and the descriptors they hold.
//
// POSIX (fcntl) locks belong to a process and an inode, and close() of ANY
// descriptor of the file drops all of them, the SQLite connections' locks
// included. A second Database of a file in the writer's process (a reader,
// or a refused second writer) that closed its own descriptor dropped the
// writer's SQLite lock: another program's connection then took itself for
// the last one, checkpointed and deleted FILE-wal under the running writer,
// and a crash lost committed frames. So a Database's descriptor is closed
// only with the file's last Database in the process; until then it waits
// for the next Database of the file, which takes it instead of opening
// another (SQLite's unix VFS defers the closes of its own connections the
// same way). Each Database keeps a descriptor of its own: flock locks, the
// writer's and the readers', belong to the open file, not to the process.
#include <errno.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

#include "io/database_internal.h"

namespace lsgd::io {

namespace {

struct OpenFile {
  pid_t pid = 0;               // the process whose entry this is (fork() copies the table)
  int users = 0;               // its Database objects open now
  bool writer = false;         // one of them writes it
  std::vector<int> spare;      // descriptors of its Databases closed meanwhile
};

std::mutex& files_mutex() {
  static std::mutex m;
  return m;
}

std::map<std::pair<dev_t, ino_t>, OpenFile>& files() {
  static auto* open = new std::map<std::pair<dev_t, ino_t>, OpenFile>();  // never destroyed: used at exit
  return *open;
}

// The entry of `key` for this process; one inherited through fork() is the
// parent's, whose descriptors are left alone (the child's are its own).
OpenFile& entry(const std::pair<dev_t, ino_t>& key) {
  OpenFile& file = files()[key];
  if (file.pid != ::getpid()) file = OpenFile{::getpid(), 0, false, {}};
  return file;
}

}  // namespace

void Database::Impl::open_file() {
  const std::lock_guard<std::mutex> guard(files_mutex());
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    const auto at = files().find({st.st_dev, st.st_ino});
    if (at != files().end() && at->second.pid == ::getpid() && !at->second.spare.empty()) {
      lock_fd = at->second.spare.back();
      at->second.spare.pop_back();
      file_key = at->first;
      owner = ::getpid();
      ++at->second.users;
      return;
    }
  }
  lock_fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (lock_fd < 0) io_error(path, "cannot be opened (", std::strerror(errno), ")");
  if (::fstat(lock_fd, &st) != 0) {
    io_error(path, "cannot be examined once opened (", std::strerror(errno), ")");
  }
  file_key = {st.st_dev, st.st_ino};
  ++entry(file_key).users;
  owner = ::getpid();
}

// A writer in this very process holds the lock already: say so, rather
// than the "another process" of the flock in lock().
void Database::Impl::register_writer() {
  const std::lock_guard<std::mutex> guard(files_mutex());
  OpenFile& file = entry(file_key);
  if (file.writer) {
    io_error(path, "is already open for writing in this process (close that Database first: "
                   "C++ destroys it, Python's db.close() or a `with` block closes it)");
  }
  file.writer = true;
  registered_writer = true;
}

void Database::Impl::release_file() noexcept {
  if (lock_fd < 0) return;
  const int fd = std::exchange(lock_fd, -1);
  const std::lock_guard<std::mutex> guard(files_mutex());
  const auto at = files().find(file_key);
  const bool here = at != files().end() && at->second.pid == ::getpid();
  if (owner != ::getpid()) {
    // A Database copied by fork(): its descriptor shares the parent's open
    // file (and flock). Closed unless a Database of the file is open here.
    if (!here || at->second.users == 0) ::close(fd);
    return;
  }
  OpenFile& file = at->second;  // there: registered by open_file()
  if (registered_writer) file.writer = false;
  ::flock(fd, LOCK_UN);  // the writer's lock, or a reader's left by an error
  file.spare.push_back(fd);
  if (--file.users > 0) return;
  for (const int spare : file.spare) ::close(spare);
  files().erase(at);
}

void Database::Impl::check_same_file() const {
  struct stat own {}, now {};
  if (lock_fd < 0 || ::fstat(lock_fd, &own) != 0) return;
  if (::stat(path.c_str(), &now) == 0) {
    if (now.st_dev == own.st_dev && now.st_ino == own.st_ino) return;
    io_error(path, "was replaced while this writer had it open (the path names another file "
             "now): the ", frames, " frames it holds are not in the file at that path but in the "
             "replaced one, which no name reaches any more. Nothing was written to the file now "
             "at the path; run again to store the frames (into another database path if that "
             "file is to stay)");
  }
  if (errno != ENOENT && errno != ENOTDIR) return;  // (a folder made unreadable: no verdict)
  io_error(path, "was deleted or moved away while this writer had it open: the ", frames,
           " frames it holds are not at that path (a moved file has them, without the log "
           "'", path, "-wal' that SQLite keeps by this name). Put the file back, or run again "
           "to store the frames");
}

}  // namespace lsgd::io
