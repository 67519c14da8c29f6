// Whether a file's or folder's mode lets anyone write it (internal to lsgd
// and its tool). root passes every access() check, and a rename never asks
// the file it replaces, so an output or a database without any write bit is
// refused by its mode: a read-only file stays read-only for root too.
#pragma once

#include <sys/stat.h>

namespace lsgd::internal {

inline bool mode_allows_writing(mode_t mode) { return (mode & (S_IWUSR | S_IWGRP | S_IWOTH)) != 0; }

}  // namespace lsgd::internal
