// Candidate search over stored frames: the detector's extension point for
// finding the earlier frames most like the query. A search mode is a class
// implementing CandidateSearch, registered by name in src/search.cc (the one
// table of built-in modes) or by register_search_mode(); SearchOptions::mode
// selects it. The built-in modes:
// - "exhaustive" (lsgd/search/exhaustive.h): every frame outside the
//   temporal window is scored;
// - "nodes" (lsgd/search/dynamic_nodes.h): the paper's dynamic nodes
//   (Sec. III-D/E, Algorithm 1) with the reference implementation's
//   thresholds relative to the similarity between the query and its
//   previous frame;
// - "index" (lsgd/search/index.h): an HNSW graph over the stored frames,
//   its shortlist re-scored exactly; the query reads a few thousand frames
//   whatever the map's size.
// docs/design.md, "Add a search mode", is the recipe.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "lsgd/state.h"

namespace lsgd {

// Names of the built-in modes.
inline constexpr const char* kExhaustiveSearch = "exhaustive";
inline constexpr const char* kNodesSearch = "nodes";
inline constexpr const char* kIndexSearch = "index";

struct DynamicNodeOptions {
  // base = threshold_0 * sim(query, previous frame); in (0, 10]. Reference: 0.9.
  double threshold_0 = 0.9;
  // A node is examined when sim(query, its first frame) > alpha * base; in [0, 10].
  // Reference threshold_1 = 0.8.
  double alpha = 0.8;
  // The query joins the node when the mean similarity to its frames > beta * base;
  // in [0, 10]. Reference threshold_2 = 1.0; the paper's Table II sweeps 0.9 / 1.0 / 1.1.
  double beta = 1.0;
  void check() const;
  static const OptionTable<DynamicNodeOptions>& fields();  // lsgd/options.h
};

struct IndexOptions {
  // Graph links per frame (HNSW's M; 2 M on the bottom layer), [4, 64].
  int m = 16;
  // Candidates examined when a frame is inserted, [8, 2000].
  int ef_construction = 100;
  // Candidates examined per query (at least rescore), [1, 10000].
  int ef_search = 64;
  // Frames the graph returns, re-scored exactly (at least the shortlist),
  // [1, 10000]: the graph ranks by a coarse key, so the best single frames
  // may rank below the shortlist there.
  int rescore = 64;
  // Of them, the best by exact similarity the temporal stage realigns (at
  // least top_n), [1, 1000].
  int shortlist = 10;
  // Places beyond top_n followed to the next query along their diagonals,
  // [0, 1000]: their sequence is extended by one frame (no realignment
  // window), so a place whose sequence builds up over many queries stays in
  // view (a query that revisits nothing: its best place is the highest of
  // the map's sequences of noise, no single frame of which stands out).
  int follow = 22;
  // A query with at most this many candidates (frames outside the temporal
  // window) scores every frame, as exhaustive search, and gets exhaustive
  // search's candidates, statistics and loops; the graph answers beyond (it
  // takes the frames all along), [0, 1e9], 0: the graph from the start. The
  // default is kExactStatisticsCandidates (evidence.h), where exhaustive
  // search's statistics start to be sampled as the index's are: on a map up
  // to that size a sample of 512 diagonals among a few thousand weighs a
  // revisit's own diagonal differently, and declares other loops.
  std::int64_t exhaustive_up_to = 8192;
  void check() const;
  static const OptionTable<IndexOptions>& fields();  // lsgd/options.h
};

struct SearchOptions {
  // A registered search mode (search_modes()): "exhaustive", "nodes" or "index".
  std::string mode = kExhaustiveSearch;
  // Temporal window w in frames, [0, 1e9]: frame j is a candidate for query i
  // only if j < i - w. Reference disc_num: 50.
  std::int64_t min_gap = 50;
  // How many best candidates to return, [1, 1000].
  int top_n = 10;
  DynamicNodeOptions nodes;  // used in nodes mode
  IndexOptions index;        // used in index mode
  // The options registered modes declare (SearchMode::options), keys
  // "<mode>.<name>" (search.<mode>.<name> in DetectorOptions), set through
  // the option table like any other. A mode reads its own in its make
  // function with own_integer("name") and the like: the value set, or the
  // declared default (InvalidArgument for an option `mode` does not declare
  // with that kind).
  OwnOptionValues own;
  std::int64_t own_integer(const std::string& name) const;
  double own_real(const std::string& name) const;
  std::string own_choice(const std::string& name) const;
  void check() const;
  // Built again after register_search_mode() (a new mode's options).
  static const OptionTable<SearchOptions>& fields();  // lsgd/options.h
};

struct Candidate {
  std::int64_t frame = -1;
  double score = 0.0;
};

// Orders candidates best first; equal scores by lower (older) frame id, so
// results are deterministic.
bool better(const Candidate& a, const Candidate& b);

// One search mode. The detector owns one, made by make_search() from its
// options, and calls search() once per frame, before storing the frame. Its
// per-frame state (the group a frame joined) is saved and restored through
// Stateful (state.h) under its name.
class CandidateSearch : public Stateful {
 public:
  // Frame `id` (== store.size(): it is searched before it is stored), its
  // descriptor as stored, and the similarity metric.
  struct Query {
    const FrameStore& store;
    DescriptorView descriptor;
    std::int64_t id;
    SimilarityMetric metric;
  };
  struct Outcome {
    // The group the query joined or created (a dynamic node); -1 for a mode
    // without groups. The store keeps a group's frames together.
    std::int64_t group = -1;
    bool created = false;  // true when the query started a new group
    // Frames this search added to the mode's own index (index mode: those
    // that left the temporal window) and the milliseconds that took.
    std::int64_t inserted = 0;
    double insert_ms = 0;
  };

  // name(): the registered name (SearchOptions::mode).
  // True when search() scores every frame j < id - min_gap and writes s(id, j)
  // to row[j] (row resized to that count): the appearance statistics then
  // come from every candidate, and the temporal stage ranks every place
  // (evidence.h). False for a shortlist: row is left alone, the statistics
  // come from sampled diagonals and the candidates are realigned.
  virtual bool scores_every_frame() const = 0;
  // A shortlist mode (scores_every_frame() false) that still scores every
  // frame, and writes `row`, for a query with at most this many candidates
  // (frames j < id - min_gap); 0, the default: never. Index mode:
  // search.index.exhaustive_up_to.
  virtual std::int64_t scores_every_frame_up_to() const { return 0; }
  // Whether search() scores every frame and writes `row` for a query with
  // `candidates` candidates (either of the two above).
  bool scores_every_frame_for(std::int64_t candidates) const {
    return scores_every_frame() || (candidates > 0 && candidates <= scores_every_frame_up_to());
  }
  // Writes candidates j < id - min_gap, best first (better()) by raw
  // similarity: top_n, or a longer shortlist that the temporal stage
  // realigns as a whole (the detector keeps top_n); `row` as above.
  virtual Outcome search(const Query& query, std::vector<Candidate>& out,
                         std::vector<double>& row) = 0;
  // The candidates (and row) search() would write for `query`, without adding
  // the query to anything that changes a later answer: a query that is not
  // stored (Detector::query()). The outcome's group is the one the query
  // would join (created: it would start one). A mode may still bring an
  // internal structure up to date with frames already stored, as search()
  // would at the next frame (index mode inserts the frames that left the
  // temporal window into its graph, in the same order): no later answer
  // differs. By default InvalidArgument naming the mode: a mode of one's own
  // implements it to answer queries without storing them.
  virtual Outcome query(const Query& query, std::vector<Candidate>& out,
                        std::vector<double>& row);

  // How far past +-tolerance of a candidate the temporal stage looks for the
  // places exhaustive search would report, when it realigns a shortlist
  // (AppearanceEvidence::realign). 0: none, the best of +-tolerance (nodes
  // mode, as the paper's groups were measured).
  virtual std::int64_t realign_reach() const { return 0; }

  // Places beyond top_n the temporal stage ranks and passes to end() (the
  // mode follows them along their diagonals), and the frames it followed to
  // this query: their sequences are scored at that frame only, and one that
  // ranks among the top_n is realigned as a candidate (AppearanceEvidence::realign).
  virtual int follow() const { return 0; }
  virtual const std::vector<std::int64_t>& followed() const;

  // Called once per frame after the detector ranked its candidates (the
  // places its sequences point to, best first, top_n of them, then up to
  // follow() more places and followed frames): a shortlist mode may follow
  // them along their diagonals at the next query.
  virtual void end(std::int64_t frame, const std::vector<Candidate>& candidates) {
    (void)frame, (void)candidates;
  }

  // Groups: how many, and the frames of group k (first frame first);
  // InvalidArgument for a group that does not exist. None by default.
  virtual bool has_groups() const { return false; }
  virtual std::int64_t groups() const { return 0; }
  virtual const std::vector<std::int64_t>& members(std::int64_t group) const;
  // The group of stored frame `frame` (-1 for a mode without groups).
  virtual std::int64_t group_of(std::int64_t frame) const { (void)frame; return -1; }

  // An index the mode can save whole (index mode's graph), so that a detector
  // restored from storage need not rebuild it. save_index() writes it as it
  // is now and returns the frames it covers (0 .. covered - 1; 0 and nothing
  // written for a mode without one). restore_index() takes what save_index()
  // wrote, for a mode with the same options and similarity `metric`, before
  // the mode's first query after its frames were restored to `store`; frames after the covered ones
  // are indexed at the next query as usual. Throws InvalidArgument naming
  // what is wrong when the bytes are damaged or do not fit `store`, and then
  // holds no index (the next query rebuilds it).
  virtual std::int64_t save_index(std::vector<std::uint8_t>& out) const {
    out.clear();
    return 0;
  }
  virtual void restore_index(const FrameStore& store, SimilarityMetric metric,
                             const std::uint8_t* data, std::size_t size);
};

struct DetectorOptions;  // lsgd/detector.h

// A registered search mode.
struct SearchMode {
  const char* name;
  const char* summary;  // one line, for help texts
  std::unique_ptr<CandidateSearch> (*make)(const SearchOptions& options);
  // Its memory model: the bytes a detector with `options` keeps per stored
  // frame of `cells` cells beyond the frame's descriptor (estimated_map_bytes(),
  // docs/performance.md); nullptr: none.
  std::int64_t (*bytes_per_frame)(const DetectorOptions& options, int cells) = nullptr;
  // Its own options (lsgd/options.h): search.<name>.<option>, in this mode
  // only; make() reads them with SearchOptions::own_integer() and the like.
  std::vector<OwnOption> options = {};
};

// Every registered mode, in registration order: the built-in ones first.
std::vector<SearchMode> search_modes();
// Registers another mode (e.g. an application's own index), usable by name
// in SearchOptions::mode from then on; call it before the detectors that use
// it are made. InvalidArgument for a missing name, summary or make function,
// a name already registered, or an own option that is not complete (a name,
// a line of documentation, a range or choices its default is in; a mode with
// options may not be named as a search option: "top_n"). Thread-safe.
void register_search_mode(const SearchMode& mode);
// "exhaustive, nodes": the names, for messages and help texts.
std::string search_mode_names();
// Throws InvalidArgument naming `name` and the registered modes unless `name` is one.
void check_search_mode(const std::string& name);
// The registered mode named `name` (InvalidArgument naming it and the
// registered ones when there is none).
SearchMode find_search_mode(const std::string& name);
// The mode options.mode names, made with `options` (checked first).
std::unique_ptr<CandidateSearch> make_search(const SearchOptions& options);

}  // namespace lsgd
