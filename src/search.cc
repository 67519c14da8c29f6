#include "lsgd/search.h"

#include <mutex>

#include "internal/check.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"

namespace lsgd {

namespace {

std::mutex registry_mutex;

// The registered search modes: a built-in mode is one line here (and its
// file pair in src/search/, include/lsgd/search/); others come from
// register_search_mode().
std::vector<SearchMode>& registry() {
  static std::vector<SearchMode> modes = {
      {kExhaustiveSearch, "every frame outside the temporal window is scored",
       make_exhaustive_search},
      {kNodesSearch, "the paper's dynamic nodes (Algorithm 1)", make_nodes_search},
  };
  return modes;
}

}  // namespace

std::vector<SearchMode> search_modes() {
  const std::lock_guard<std::mutex> lock(registry_mutex);
  return registry();
}

void register_search_mode(const SearchMode& mode) {
  if (mode.name == nullptr || *mode.name == '\0' || mode.summary == nullptr || mode.make == nullptr) {
    internal::throw_invalid("register_search_mode: a mode needs a name, a summary and a make function");
  }
  const std::lock_guard<std::mutex> lock(registry_mutex);
  for (const SearchMode& m : registry()) {
    if (std::string(m.name) == mode.name) {
      internal::throw_invalid("register_search_mode: search mode '", mode.name,
                              "' is already registered");
    }
  }
  registry().push_back(mode);
}

std::string search_mode_names() {
  std::string names;
  for (const SearchMode& m : search_modes()) names += (names.empty() ? "" : ", ") + std::string(m.name);
  return names;
}

void check_search_mode(const std::string& name) {
  for (const SearchMode& m : search_modes()) {
    if (name == m.name) return;
  }
  internal::throw_invalid("search mode '", name, "' is unknown: expected one of ",
                          search_mode_names());
}

std::unique_ptr<CandidateSearch> make_search(const SearchOptions& options) {
  options.check();
  for (const SearchMode& m : search_modes()) {
    if (options.mode != m.name) continue;
    std::unique_ptr<CandidateSearch> search = m.make(options);
    if (!search || options.mode != search->name()) {
      internal::throw_invalid("search mode '", options.mode, "' made ",
                              search ? internal::concat("a search named '", search->name(), "'")
                                     : std::string("no search"));
    }
    return search;
  }
  internal::throw_invalid("search mode '", options.mode, "' is unknown");  // check() said so
}

void DynamicNodeOptions::check() const {
  internal::check_range_open_low("search.nodes.threshold_0", threshold_0, 0.0, 10.0);
  internal::check_range("search.nodes.alpha", alpha, 0.0, 10.0);
  internal::check_range("search.nodes.beta", beta, 0.0, 10.0);
}

void SearchOptions::check() const {
  try {
    check_search_mode(mode);
  } catch (const InvalidArgument& e) {
    internal::throw_invalid("search.mode: ", e.what());
  }
  internal::check_range<std::int64_t>("search.min_gap", min_gap, 0, 1000000000, "frames");
  internal::check_range("search.top_n", top_n, 1, 1000);
  nodes.check();
}

bool better(const Candidate& a, const Candidate& b) {
  if (a.score != b.score) return a.score > b.score;
  return a.frame < b.frame;
}

const std::vector<std::int64_t>& CandidateSearch::members(std::int64_t group) const {
  internal::throw_invalid("search mode ", name(), " has no groups (group ", group, " asked for)");
}

void CandidateSearch::restore_groups(std::vector<std::vector<std::int64_t>> /*groups*/,
                                     std::int64_t /*frames*/) {
  internal::throw_invalid("restore_nodes: the search mode is ", name(), ", which has no groups");
}

}  // namespace lsgd
