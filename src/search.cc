#include "lsgd/search.h"

#include "internal/check.h"
#include "internal/option_tables.h"
#include "internal/registry.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/search/index.h"
#include "lsgd/limits.h"

namespace lsgd {

namespace {

// The registered search modes: a built-in mode is one line here (and its
// file pair in src/search/, include/lsgd/search/); others come from
// register_search_mode().
internal::Registry<SearchMode>& registry() {
  static internal::Registry<SearchMode> modes(
      "search mode",
      {
          {kExhaustiveSearch, "every frame outside the temporal window is scored",
           make_exhaustive_search, exhaustive_bytes_per_frame},
          {kNodesSearch, "the paper's dynamic nodes (Algorithm 1)", make_nodes_search},
          {kIndexSearch, "an HNSW graph (hnswlib), its shortlist re-scored exactly",
           make_index_search, index_bytes_per_frame},
      });
  return modes;
}

}  // namespace

std::vector<SearchMode> search_modes() { return registry().entries(); }

void register_search_mode(const SearchMode& mode) {
  registry().add(internal::with_checked_options<SearchOptions>(mode, "register_search_mode", "mode", "search"),
                 "register_search_mode");
  internal::count_registration();
}

std::string search_mode_names() { return registry().names(); }

void check_search_mode(const std::string& name) { registry().find(name); }

SearchMode find_search_mode(const std::string& name) { return registry().find(name); }

std::unique_ptr<CandidateSearch> make_search(const SearchOptions& options) {
  options.check();
  std::unique_ptr<CandidateSearch> search = registry().find(options.mode).make(options);
  if (!search || options.mode != search->name()) {
    internal::throw_invalid("search mode '", options.mode, "' made ",
                            search ? internal::concat("a search named '", search->name(), "'")
                                   : std::string("no search"));
  }
  return search;
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

const OptionTable<IndexOptions>& IndexOptions::fields() {
  using S = IndexOptions;
  static const OptionTable<S> table = {
      integer_option("m", &S::m, 4, 64, "", "graph links per frame (HNSW's M)"),
      integer_option("ef_construction", &S::ef_construction, 8, 2000, "frames",
                     "candidates examined when a frame is inserted"),
      integer_option("ef_search", &S::ef_search, 1, 10000, "frames",
                     "candidates examined per query (at least rescore)"),
      integer_option("rescore", &S::rescore, 1, 10000, "frames",
                     "frames the graph returns, re-scored exactly (at least the shortlist)"),
      integer_option("shortlist", &S::shortlist, 1, 1000, "frames",
                     "of them, the best by exact similarity the temporal stage realigns (at least top_n)"),
      integer_option("follow", &S::follow, 0, 1000, "places",
                     "places beyond top_n followed to the next query along their diagonals"),
      integer_option<S, std::int64_t>(
          "exhaustive_up_to", &S::exhaustive_up_to, 0, 1000000000, "frames",
          "a query with at most this many candidates scores every frame (exhaustive search's "
          "results and statistics); the graph beyond (0: always the graph)"),
  };
  return table;
}

void IndexOptions::check() const { check_options(fields(), *this, "search.index"); }

namespace {

OptionTable<SearchOptions> search_table() {
  using S = SearchOptions;
  OptionTable<S> t = {
      internal::registry_choice<S, SearchMode>(
          "mode", "how earlier frames are searched: a registered search mode (search.h)", search_modes,
          find_search_mode, &S::mode),
      integer_option<S, std::int64_t>("min_gap", &S::min_gap, 0, kMaxWindowFrames, "frames",
                                      "temporal window w: frame j is a candidate for query i "
                                      "only if j < i - w"),
      integer_option("top_n", &S::top_n, 1, 1000, "", "best candidates returned"),
  };
  nest<S, DynamicNodeOptions>(t, "nodes", &S::nodes, DynamicNodeOptions::fields(),
                              [](const S& s) { return s.mode == kNodesSearch; },
                              "in nodes mode");
  nest<S, IndexOptions>(t, "index", &S::index, IndexOptions::fields(),
                        [](const S& s) { return s.mode == kIndexSearch; }, "in index mode");
  for (const SearchMode& m : search_modes()) {
    const std::string name = m.name;
    add_own_options<S>(t, name, m.options, &S::own, [name](const S& s) { return s.mode == name; },
                       "in " + name + " mode");
  }
  return t;
}

}  // namespace

const OptionTable<SearchOptions>& SearchOptions::fields() {
  return internal::current_table(search_table);
}

std::int64_t SearchOptions::own_integer(const std::string& name) const {
  return lsgd::own_integer(own, find_search_mode(mode).options, mode, name);
}

double SearchOptions::own_real(const std::string& name) const {
  return lsgd::own_real(own, find_search_mode(mode).options, mode, name);
}

std::string SearchOptions::own_choice(const std::string& name) const {
  return lsgd::own_choice(own, find_search_mode(mode).options, mode, name);
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

CandidateSearch::Outcome CandidateSearch::query(const Query& query, std::vector<Candidate>&,
                                                std::vector<double>&) {
  internal::throw_invalid("search mode ", name(), " cannot answer query ", query.id,
                          " without storing it (it does not implement CandidateSearch::query)");
}

const std::vector<std::int64_t>& CandidateSearch::followed() const {
  static const std::vector<std::int64_t> none;
  return none;
}

void CandidateSearch::restore_index(const FrameStore&, SimilarityMetric, const std::uint8_t*,
                                    std::size_t size) {
  internal::throw_invalid("search mode ", name(), " keeps no index to restore (", size,
                          " bytes given)");
}


}  // namespace lsgd
