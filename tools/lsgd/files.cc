#include "files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <utility>

#include "internal/check.h"
#include "internal/file_mode.h"
#include "lsgd/error.h"
#include "lsgd/io/files.h"

namespace lsgd::cli {
namespace {

namespace fs = std::filesystem;
using internal::concat;

using FileId = std::pair<dev_t, ino_t>;

bool identify(const std::string& path, FileId& id, struct stat& st) {
  if (::stat(path.c_str(), &st) != 0) return false;
  id = {st.st_dev, st.st_ino};
  return true;
}

// Where writing `path` lands: a symbolic link, also one whose target does
// not exist yet, is followed to that target (at most 40 links, as the kernel).
std::string target_of(const std::string& path) {
  fs::path p = path;
  for (int links = 0; links < 40; ++links) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) break;
    const fs::path to = fs::read_symlink(p, ec);
    if (ec) break;
    p = to.is_absolute() ? to : p.parent_path() / to;
  }
  return p.string();
}

// The absolute, normalised spelling of a path that may not exist yet, after
// its links.
std::string spelling(const std::string& path) {
  std::error_code ec;
  const std::string target = target_of(path);
  const fs::path p = fs::weakly_canonical(fs::absolute(target, ec), ec);
  return ec ? fs::absolute(target).lexically_normal().string() : p.string();
}

std::string folder_of(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

[[noreturn]] void unwritable(const std::string& flag, const std::string& path,
                             const std::string& why) {
  throw IoError(concat("cannot write ", flag, " '", path, "': ", why, " (nothing was run)"));
}

// The folder an output goes to must exist and be writable.
void check_folder(const std::string& flag, const std::string& path, const std::string& folder) {
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0) {
    unwritable(flag, path, concat("folder '", folder, "' does not exist"));
  }
  if (!S_ISDIR(st.st_mode)) unwritable(flag, path, concat("'", folder, "' is not a folder"));
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    unwritable(flag, path, concat("folder '", folder, "' is not writable (", std::strerror(errno), ")"));
  }
  if (!internal::mode_allows_writing(st.st_mode)) {
    unwritable(flag, path, concat("folder '", folder, "' is read-only (no write permission at all)"));
  }
}

// An output folder that exists (`where`: `path`, or the folder it lands in)
// holds only what the command writes there itself (the names `own`,
// `marker` among them).
void check_existing_output_folder(const std::string& flag, const std::string& path,
                                  const std::string& where, const struct stat& st,
                                  const std::vector<std::string>& own, const std::string& marker) {
  if (!S_ISDIR(st.st_mode)) unwritable(flag, path, "it exists and is not a folder");
  std::error_code ec;
  bool empty = true, marked = false;
  for (const auto& entry : fs::directory_iterator(where, ec)) {
    const std::string name = entry.path().filename().string();
    empty = false;
    marked = marked || name == marker;
    if (std::find(own.begin(), own.end(), name) == own.end()) {
      throw InvalidArgument(concat("refusing to write into ", flag, " '", path,
                                   "': it holds '", name, "', which this command did not "
                                   "write; give a new or empty folder (nothing was run)"));
    }
  }
  if (!empty && !marked) {
    throw InvalidArgument(concat("refusing to write into ", flag, " '", path, "': it is not "
                                 "empty and has no ", marker, ", so this command "
                                 "did not write it; give a new or empty folder (nothing was "
                                 "run)"));
  }
  if (::access(where.c_str(), W_OK | X_OK) != 0) {
    unwritable(flag, path, concat("the folder is not writable (", std::strerror(errno), ")"));
  }
  if (!internal::mode_allows_writing(st.st_mode)) unwritable(flag, path, "the folder is read-only (no write permission at all)");
}

// An output folder: missing (created below a writable folder) or holding only
// what the command writes there itself.
void check_output_folder(const std::string& flag, const std::string& path,
                         const std::vector<std::string>& own, const std::string& marker) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    check_existing_output_folder(flag, path, path, st, own, marker);
    return;
  }
  std::error_code ec;
  if (fs::is_symlink(fs::symlink_status(path, ec))) {
    unwritable(flag, path, concat("it is a symbolic link to '", fs::read_symlink(path, ec).string(),
                                  "', which does not exist"));
  }
  // `new/..` names no folder yet, but the one it lands in once `new` is
  // created (`lsgd demo --output new/..` wrote into a folder holding other
  // files): that folder is the output.
  const fs::path lands = fs::weakly_canonical(path, ec);
  if (!ec && ::stat(lands.c_str(), &st) == 0) {
    check_existing_output_folder(flag, path, lands.string(), st, own, marker);
    return;
  }
  check_folder(flag, path, folder_of(fs::path(path).lexically_normal().string()));
}

// An output already checked: the flag that names it and its path.
struct Written {
  std::string flag;
  std::string path;
};

// The outputs checked so far, by inode (those that exist) and by spelling (all).
struct Outputs {
  std::map<FileId, Written> existing;
  std::map<std::string, Written> spelled;
  std::set<std::string> names;  // the last component of each spelling
};

[[noreturn]] void same_file(const std::string& flag, const std::string& path, const Written& other) {
  throw InvalidArgument(concat("refusing to write ", flag, " '", path, "' and ", other.flag, " '",
                               other.path, "': they are the same file (nothing was run)"));
}

// An output: writable where it goes, a regular file when it exists, and not
// the file of another flag; notes it in `outputs`.
void check_output(const std::string& flag, const std::string& path, Outputs& outputs) {
  // A name the file system cannot hold fails now, not after the run.
  const std::string name = fs::path(path).filename().string();
  if (const std::size_t limit = io::name_limit(path); name.size() > limit) {
    unwritable(flag, path, concat("its name is ", name.size(), " bytes, more than the ", limit,
                                  " its folder takes"));
  }
  FileId id{};
  struct stat st {};
  if (identify(path, id, st)) {
    if (S_ISDIR(st.st_mode)) unwritable(flag, path, "it is a folder");
    // A character device (/dev/null, a terminal) or a pipe is a stream the
    // user chose; a disk or a socket is not a place for a result.
    if (!S_ISREG(st.st_mode) && !S_ISCHR(st.st_mode) && !S_ISFIFO(st.st_mode)) {
      unwritable(flag, path, "it is not a regular file (a block device or a socket)");
    }
    if (!S_ISREG(st.st_mode)) return;  // a stream: writing it destroys nothing
    if (::access(path.c_str(), W_OK) != 0) {
      unwritable(flag, path, concat("it is read-only (", std::strerror(errno), ")"));
    }
    if (!internal::mode_allows_writing(st.st_mode)) unwritable(flag, path, "it is read-only (no write permission at all)");
    const auto [it, fresh] = outputs.existing.emplace(id, Written{flag, path});
    if (!fresh && it->second.flag != flag) same_file(flag, path, it->second);
  } else {
    check_folder(flag, path, folder_of(target_of(path)));
  }
  const std::string spelled = spelling(path);
  outputs.names.insert(fs::path(spelled).filename().string());
  const auto [it, new_spelling] = outputs.spelled.emplace(spelled, Written{flag, path});
  if (!new_spelling && it->second.flag != flag) same_file(flag, path, it->second);
}

// Whether a path that does not exist could spell an output: its spelling
// (links and folders resolved: ~10 system calls) ends in its own last
// component unless the path is a (dangling) link or ends in "." or "..",
// so a missing input whose name no output has is none, for one lstat. A
// list of 200,000 missing images took 6.5 s in spelling() alone.
bool may_spell_an_output(const std::string& path, const Outputs& outputs) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) return true;  // a link to something missing
  const fs::path name = fs::path(path).filename();
  if (name.empty() || name == "." || name == "..") return true;
  return outputs.names.count(name.string()) > 0;
}

// An input is no output of another flag: by inode when the input exists, by
// spelling when it does not (a database's -wal file comes and goes).
void check_not_output(const std::string& flag, const std::string& path, const std::string& what,
                      const Outputs& outputs) {
  FileId id{};
  struct stat st {};
  const Written* out = nullptr;
  if (identify(path, id, st)) {
    const auto it = outputs.existing.find(id);
    if (it != outputs.existing.end()) out = &it->second;
  } else if (may_spell_an_output(path, outputs)) {
    const auto it = outputs.spelled.find(spelling(path));
    if (it != outputs.spelled.end()) out = &it->second;
  }
  if (out == nullptr || out->flag == flag) return;  // a database is its own output
  throw InvalidArgument(concat("refusing to write ", out->flag, " '", out->path, "': it is ",
                               what, " ('", path, "'); choose another file (nothing "
                               "was run)"));
}

}  // namespace

void CommandFiles::input(const std::string& path, const std::string& flag) {
  if (!path.empty()) inputs_.push_back({path, flag, "the file given by " + flag});
}

void CommandFiles::inputs(const std::vector<std::string>& paths, const std::string& flag,
                          const std::string& what) {
  for (std::size_t i = 0; i < paths.size(); ++i) {
    inputs_.push_back({paths[i], flag, concat(what, " ", i, " of ", flag)});
  }
}

void CommandFiles::sequence(const io::Sequence& sequence, const std::string& flag,
                            const std::string& what) {
  inputs(sequence.images, flag, what);
  for (const std::string& file : sequence.files) {
    inputs_.push_back({file, flag, concat("a file the sequence of ", flag, " was read from")});
  }
}

void CommandFiles::database(const std::string& path, const std::string& flag, bool also_output) {
  if (path.empty()) return;
  inputs_.push_back({path, flag, "the database given by " + flag});
  // SQLite keeps its companions beside the file a link names (its unix VFS
  // resolves links), so they are guarded there and beside the link.
  std::vector<std::string> bases = {path};
  if (const std::string target = target_of(path); target != path) bases.push_back(target);
  for (const std::string& base : bases) {
    for (const char* suffix : {"-wal", "-shm", "-journal"}) {
      inputs_.push_back({base + suffix, flag,
                         concat("the database's SQLite ", suffix + 1, " file (", flag, ")")});
    }
  }
  if (also_output) outputs_.push_back({path, flag, ""});
}

void CommandFiles::output(const std::string& path, const std::string& flag) {
  if (!path.empty()) outputs_.push_back({path, flag, ""});
}

void CommandFiles::output_folder(const std::string& path, const std::string& flag,
                                 const std::vector<std::string>& own, const std::string& marker) {
  if (path.empty()) return;
  folders_.push_back({path, flag, ""});
  folder_names_.push_back(own);
  folder_markers_.push_back(marker);
}

void CommandFiles::output_or_stdout(const std::string& path, const std::string& flag) {
  if (path.empty()) {
    stdout_flag_ = flag;
  } else {
    output(path, flag);
  }
}

void CommandFiles::check() const {
  // lsgd's main() holds a closed descriptor 1 with /dev/null opened for
  // reading, so that nothing else takes it and every write to it fails.
  if (!stdout_flag_.empty()) {
    const int flags = ::fcntl(STDOUT_FILENO, F_GETFL);
    if (flags == -1 || (flags & O_ACCMODE) == O_RDONLY) {
      throw IoError(concat("standard output, where the output goes without ", stdout_flag_,
                           ", is closed: give ", stdout_flag_, " FILE (nothing was run)"));
    }
  }
  // Output folders first, then every output, then that no output is an input.
  for (std::size_t f = 0; f < folders_.size(); ++f) {
    check_output_folder(folders_[f].flag, folders_[f].path, folder_names_[f], folder_markers_[f]);
  }
  Outputs outputs;
  for (const File& out : outputs_) check_output(out.flag, out.path, outputs);
  for (const File& in : inputs_) check_not_output(in.flag, in.path, in.what, outputs);
  // Standard output redirected into a file (`>> list.txt`): not one of the
  // inputs either (`>` empties the file before lsgd starts; `>>` would
  // append the command's output to what it reads).
  struct stat out {};
  if (::fstat(STDOUT_FILENO, &out) != 0 || !S_ISREG(out.st_mode)) return;
  for (const File& in : inputs_) {
    FileId id{};
    struct stat st {};
    if (identify(in.path, id, st) && id == FileId{out.st_dev, out.st_ino}) {
      throw InvalidArgument(concat("refusing to write standard output: it is ", in.what, " ('", in.path,
                                   "'); redirect it to another file (nothing was run)"));
    }
  }
}

}  // namespace lsgd::cli
