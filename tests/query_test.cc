// Tests of Detector::query() (include/lsgd/detector.h): the answer
// process() would give, with nothing stored and nothing changed. Every
// search mode, with and without the verification stages: a query of any
// frame, at any point of a sequence with revisits, leaves every later answer
// and the whole state (descriptors, nodes, every component's per-frame
// records, index mode's graph) as in a detector that was never queried; a
// detector restored from a database read-only answers as the writer would.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "detector_util.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/stage.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::expect_same;
using test::expect_same_state;
using test::frame;
using test::message_of;
using test::Remembering;
using test::world;

using QueryCase = test::ModeCase;
using test::index_of;
using test::options;

class Query : public ::testing::TestWithParam<QueryCase> {};

// Before frame i is processed, the detector is queried with frame i itself
// (the answer must be process()'s), with a frame far ahead (a revisit of
// something else) and with an earlier one: none of it may show in any later
// answer or in the state.
TEST_P(Query, AnswersAsProcessAndChangesNothing) {
  const QueryCase c = GetParam();
  const DetectorOptions o = options(c);
  Detector reference(o), queried(o);
  const std::int64_t n = world().frames();
  std::int64_t loops = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    const Result expected = reference.process(frame(i));
    const Result ahead = queried.query(frame((i + 150) % n));
    const Result before = queried.query(frame(i / 2));
    EXPECT_EQ(ahead.frame, i);
    EXPECT_EQ(before.frame, i);
    const Result answer = queried.query(frame(i));
    ASSERT_EQ(queried.size(), i);
    expect_same(answer, expected);
    expect_same(queried.process(frame(i)), expected);
    loops += expected.loop ? 1 : 0;
    if (i % 80 == 79) expect_same_state(queried, reference);
    if (::testing::Test::HasFatalFailure()) return;
  }
  if (std::string(c.stages).find("geometric") != std::string::npos) {
    EXPECT_GT(loops, 10) << "the street's revisits";
  }
  expect_same_state(queried, reference);
  EXPECT_EQ(index_of(queried), index_of(reference));
}

INSTANTIATE_TEST_SUITE_P(
    Modes, Query,
    ::testing::Values(QueryCase{kExhaustiveSearch, "temporal,geometric"},
                      QueryCase{kExhaustiveSearch, "none"},
                      QueryCase{kNodesSearch, "temporal,geometric"},
                      QueryCase{kIndexSearch, "temporal,geometric", 0},
                      QueryCase{kIndexSearch, "temporal"}));

TEST(Query, ARefusedFrameLeavesTheDetectorAsItWas) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal,geometric"});
  Detector reference(o), queried(o);
  for (std::int64_t i = 0; i < 40; ++i) {
    reference.process(frame(i));
    queried.process(frame(i));
  }
  const cv::Mat other(60, 80, CV_8UC1, cv::Scalar(9));
  EXPECT_NE(message_of<InvalidArgument>([&] { queried.query(other); }).find("every frame must have the same size"),
            std::string::npos);
  EXPECT_THROW(queried.query(cv::Mat()), InvalidArgument);
  for (std::int64_t i = 40; i < 60; ++i) expect_same(queried.process(frame(i)), reference.process(frame(i)));
  expect_same_state(queried, reference);
}

TEST(Query, AnEmptyDetectorAnswersNoLoop) {
  Detector d(options({kExhaustiveSearch, "temporal,geometric"}));
  const Result r = d.query(frame(0));
  EXPECT_EQ(r.frame, 0);
  EXPECT_FALSE(r.loop);
  EXPECT_EQ(r.best.frame, -1);
  EXPECT_EQ(d.size(), 0);
  EXPECT_EQ(d.width(), 0);  // the first frame's size is not taken from a query
  const Result p = d.process(frame(1));
  EXPECT_EQ(p.frame, 0);
}

// A search mode of one's own that does not implement query(): refused by
// name before anything changes.
class StoringOnly final : public CandidateSearch {
 public:
  explicit StoringOnly(const SearchOptions& o) : options_(o) {}
  const char* name() const override { return "test-storing-only"; }
  bool scores_every_frame() const override { return true; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    search_exhaustive(q.store, q.descriptor, q.id, options_, q.metric, scratch_, out, &row);
    return {};
  }

 private:
  SearchOptions options_;
  std::vector<Candidate> scratch_;
};

TEST(Query, ASearchModeOrStageThatCannotAnswerIsRefusedByName) {
  static const bool registered = [] {
    register_search_mode({"test-storing-only", "exhaustive without query()",
                          [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
                            return std::make_unique<StoringOnly>(o);
                          }});
    register_verification_stage({"test-remembering", "a gate with state",
                                 [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
                                   return std::make_unique<Remembering>();
                                 }});
    return true;
  }();
  (void)registered;
  DetectorOptions o = options({kExhaustiveSearch, "temporal"});
  o.search.mode = "test-storing-only";
  Detector mode(o);
  for (std::int64_t i = 0; i < 30; ++i) mode.process(frame(i));
  const std::string m = message_of<InvalidArgument>([&] { mode.query(frame(30)); });
  EXPECT_NE(m.find("search mode test-storing-only cannot answer query 30 without storing it"),
            std::string::npos) << m;
  EXPECT_EQ(mode.process(frame(30)).frame, 30);

  DetectorOptions s = options({kExhaustiveSearch, "temporal"});
  s.verification.stages.push_back("test-remembering");
  Detector stage(s);
  for (std::int64_t i = 0; i < 30; ++i) stage.process(frame(i));
  const std::string t = message_of<InvalidArgument>([&] { stage.query(frame(30)); });
  EXPECT_NE(t.find("verification stage test-remembering keeps per-frame state"), std::string::npos) << t;
  EXPECT_EQ(stage.process(frame(30)).frame, 30);
  EXPECT_EQ(stage.stage("test-remembering")->name(), std::string("test-remembering"));
}

std::string temp_path(const std::string& name) {
  std::filesystem::create_directories(LSGD_TEST_TMP);
  const std::string path = std::string(LSGD_TEST_TMP) + "/query_" + test::test_file_tag() + "_" + name;
  std::filesystem::remove_all(path);
  for (const char* suffix : {"-wal", "-shm", "-journal"}) std::filesystem::remove(path + suffix);
  return path;
}

// A map opened read-only: query() of the frame after it answers as its
// writer did, and a second session localised against it (processed in
// memory, the file untouched: lsgd run --localize) finds the revisited places.
TEST(Query, AMapOpenedReadOnlyAnswersAsItsWriterAndStaysAsItWas) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal,geometric"});
  const std::string path = temp_path("read_only.lsgd");
  const std::int64_t split = 200, n = world().frames();
  std::vector<Result> expected;
  {
    io::Database db = io::Database::create(path, o);
    Detector writer(o);
    for (std::int64_t i = 0; i < n; ++i) {
      expected.push_back(writer.process(frame(i)));
      if (i < split) db.append(writer, expected.back(), 0, "frame" + std::to_string(i));
    }
  }
  const auto bytes = [&] {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string before = bytes();
  const io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
  Detector map(db.options()), reference(db.options());
  db.restore(map);
  db.restore(reference);
  expect_same(map.query(frame(split)), expected[static_cast<std::size_t>(split)]);
  for (std::int64_t i = split + 1; i < n; i += 40) {
    Detector fresh(db.options());
    db.restore(fresh);
    expect_same(map.query(frame(i)), fresh.process(frame(i)));
  }
  expect_same_state(map, reference);

  std::int64_t ranked = 0, declared = 0, false_loops = 0;
  std::int64_t writer_ranked = 0, writer_declared = 0;
  map.cut();
  for (std::int64_t i = split; i < n; ++i) {
    const Result r = map.process(frame(i));
    const eval::GroundTruth& truth = world().ground_truth();
    if (!truth.has_loop(i, 0)) continue;
    ranked += truth.is_loop(i, r.ranking.best.frame) ? 1 : 0;
    const Result& w = expected[static_cast<std::size_t>(i)];
    writer_ranked += truth.is_loop(i, w.ranking.best.frame) ? 1 : 0;
    writer_declared += w.loop && truth.is_loop(i, w.best.frame) ? 1 : 0;
    declared += r.loop && truth.is_loop(i, r.best.frame) ? 1 : 0;
    false_loops += r.loop && !truth.is_loop(i, r.best.frame) ? 1 : 0;
  }
  // As many as the writer, which processed them right after the map.
  EXPECT_GT(writer_declared, 10);
  EXPECT_GE(ranked, writer_ranked);
  EXPECT_GE(declared, writer_declared);
  EXPECT_EQ(false_loops, 0);
  EXPECT_EQ(bytes(), before);
}

}  // namespace
}  // namespace lsgd
