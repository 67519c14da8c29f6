#include "lsgd/search.h"

#include <mutex>

#include "internal/check.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/limits.h"

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

const OptionTable<DynamicNodeOptions>& DynamicNodeOptions::fields() {
  using S = DynamicNodeOptions;
  static const OptionTable<S> table = {
      real_option("threshold_0", &S::threshold_0, 0.0, 10.0, true, "",
                  "base = threshold_0 * sim(query, previous frame); reference 0.9"),
      real_option("alpha", &S::alpha, 0.0, 10.0, false, "",
                  "a node is examined when sim(query, its first frame) > alpha * base"),
      real_option("beta", &S::beta, 0.0, 10.0, false, "",
                  "the query joins a node when its mean similarity to the node > beta * base"),
  };
  return table;
}

void DynamicNodeOptions::check() const { check_options(fields(), *this, "search.nodes"); }

const OptionTable<SearchOptions>& SearchOptions::fields() {
  using S = SearchOptions;
  static const OptionTable<S> table = [] {
    OptionField<S> mode;
    mode.name = "mode";
    mode.kind = OptionKind::kChoice;
    mode.doc = "how earlier frames are searched: a registered search mode (search.h)";
    mode.choices = [] {
      std::vector<std::string> names;
      for (const SearchMode& m : search_modes()) names.emplace_back(m.name);
      return names;
    };
    mode.text = [](const S& s) { return s.mode; };
    mode.set_choice = [](S& s, const std::string& name) {
      check_search_mode(name);
      s.mode = name;
    };
    OptionTable<S> t = {
        mode,
        integer_option<S, std::int64_t>("min_gap", &S::min_gap, 0, kMaxWindowFrames, "frames",
                                        "temporal window w: frame j is a candidate for query i "
                                        "only if j < i - w"),
        integer_option("top_n", &S::top_n, 1, 1000, "", "best candidates returned"),
    };
    nest<S, DynamicNodeOptions>(t, "nodes", &S::nodes, DynamicNodeOptions::fields(),
                                [](const S& s) { return s.mode == kNodesSearch; },
                                "in nodes mode");
    return t;
  }();
  return table;
}

void SearchOptions::check() const {
  try {
    check_search_mode(mode);
  } catch (const InvalidArgument& e) {
    internal::throw_invalid("search.mode: ", e.what());
  }
  check_options(fields(), *this, "search");
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
