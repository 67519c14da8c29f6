// Names close to a misspelt one, for "did you mean" in messages (the CLI's
// subcommands and flags, the library's option keys). Header-only.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace lsgd::internal {

// Edit distance (insertions, deletions, substitutions, adjacent swaps).
inline std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

// The name closest to `word` when it is close enough to be a slip ("" otherwise).
inline std::string nearest(const std::string& word, const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const std::string& n : names) {
    const std::size_t d = distance(word, n);
    if (d < best_d || (d == best_d && !best.empty() && n < best)) best = n, best_d = d;
  }
  return best;
}

}  // namespace lsgd::internal
