// The files one lsgd command reads and writes, checked before any work: no
// output may be (same file, by device and inode, not by spelling) one of the
// inputs or another output, and every output must be writable where it is
// going. A command that would destroy what it was given, or lose its results
// at the end of a long run, stops at once with a message naming both files.
#pragma once

#include <string>
#include <vector>

#include "lsgd/io/sequence.h"

namespace lsgd::cli {

class CommandFiles {
 public:
  // An input named by `flag`, e.g. ("x.yaml", "--config"). Missing files are
  // left to the command (it reports them itself).
  void input(const std::string& path, const std::string& flag);
  // Many inputs of one flag, e.g. the images of --sequence ("input image").
  void inputs(const std::vector<std::string>& paths, const std::string& flag,
              const std::string& what);
  // The images of a sequence and the files it was read from (its list file,
  // a dataset folder's sequence.txt, KITTI's times.txt: io::Sequence::files),
  // `what` naming an image ("input image").
  void sequence(const io::Sequence& sequence, const std::string& flag, const std::string& what);
  // A detector database read (and maybe appended to): the file and its
  // SQLite companions (-wal, -shm, -journal), which hold committed frames.
  void database(const std::string& path, const std::string& flag, bool also_output);
  // An output file; an empty path (standard output) is ignored.
  void output(const std::string& path, const std::string& flag);
  // An output file whose absence (an empty path) sends the output to standard
  // output, which must then be open for writing (a closed one is refused:
  // the results would be lost).
  void output_or_stdout(const std::string& path, const std::string& flag);
  // An output folder whose files the command writes; `own` lists the names
  // it writes at its top level (files or folders), `marker` the one it writes
  // last. An existing folder must be empty, or hold only those names and the
  // marker (an earlier run of the command wrote it).
  void output_folder(const std::string& path, const std::string& flag,
                     const std::vector<std::string>& own, const std::string& marker);

  // Throws InvalidArgument when an output is an input or another output, and
  // IoError when an output cannot be written (its folder is missing or not
  // writable, it is a folder, a device or a pipe, or it is read-only).
  void check() const;

 private:
  struct File {
    std::string path;
    std::string flag;
    std::string what;  // e.g. "the database", "input image 5"
  };
  std::vector<File> inputs_;
  std::vector<File> outputs_;
  std::vector<File> folders_;
  std::vector<std::vector<std::string>> folder_names_;
  std::vector<std::string> folder_markers_;
  std::string stdout_flag_;  // the flag whose output goes to standard output ("" none)
};

}  // namespace lsgd::cli
