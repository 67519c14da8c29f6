// Tests of reading another system's detections (eval/detections.h) and
// scoring them with the strict protocol, metrics computed by hand.
#include "lsgd/eval/detections.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/eval/results_csv.h"
#include "test_util.h"

namespace lsgd::eval {
namespace {

namespace fs = std::filesystem;

// The record of `frame`: read_detections lists only the queries with a row,
// and any other frame reports nothing (evaluate() counts it as such a query).
FrameRecord at(const std::vector<FrameRecord>& records, std::int64_t frame) {
  for (const FrameRecord& r : records) {
    if (r.frame == frame) return r;
  }
  FrameRecord none;
  none.frame = frame;
  return none;
}

class DetectionsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(LSGD_TEST_TMP) /
           (std::string("detections_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& content) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p.string();
  }
  // Expects FormatError whose message has file:line and `part`.
  void expect_line_error(const std::string& content, int line, const std::string& part) {
    const std::string path = write("bad.csv", content);
    const std::string message = test::message_of<FormatError>([&] { read_detections(path, 10); });
    EXPECT_NE(message.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << message;
    EXPECT_NE(message.find(part), std::string::npos) << message;
  }
  fs::path dir_;
};

TEST_F(DetectionsTest, ReadsQueryMatchScoreWithoutHeader) {
  const std::string path =
      write("d.csv", "# from another system\n5,0,0.9\n6,-1,\n\n7,2,0.85,extra\n");
  const auto records = read_detections(path, 8);
  ASSERT_EQ(records.size(), 3u);  // the queries with a row, in frame order
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(records[k].frame, static_cast<std::int64_t>(5 + k));
  EXPECT_EQ(at(records, 5).reported.frame, 0);
  EXPECT_DOUBLE_EQ(at(records, 5).reported.score, 0.9);
  ASSERT_EQ(at(records, 5).candidates.size(), 1u);
  EXPECT_EQ(at(records, 6).reported.frame, -1);  // match -1: no loop
  EXPECT_TRUE(at(records, 6).candidates.empty());
  EXPECT_EQ(at(records, 7).reported.frame, 2);
  EXPECT_EQ(at(records, 0).reported.frame, -1);  // no row: no loop
  // Another system's reported matches are its declared loops.
  EXPECT_TRUE(at(records, 5).loop);
  EXPECT_FALSE(at(records, 6).loop);
  EXPECT_FALSE(at(records, 0).loop);
}

TEST_F(DetectionsTest, HeaderNamesColumnsInAnyOrder) {
  const std::string path = write("d.csv", "score,match,query\n0.5,1,4\n");
  const auto records = read_detections(path);
  ASSERT_EQ(records.size(), 1u);  // frames -1: largest query + 1 bounds the ids
  EXPECT_EQ(at(records, 4).reported.frame, 1);
  EXPECT_DOUBLE_EQ(at(records, 4).reported.score, 0.5);
}

TEST_F(DetectionsTest, AByteOrderMarkBeforeTheHeaderIsSkipped) {
  const std::string path = write("bom.csv", "\xEF\xBB\xBF" "query,match,score\n4,1,0.5\n");
  const auto records = read_detections(path);
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(at(records, 4).reported.frame, 1);
}

// A file saved with Windows or classic Mac line endings reads as the lines it shows.
TEST_F(DetectionsTest, EveryLineEndingReadsTheSameRows) {
  const std::string rows = "query,match,score|# a comment||5,0,0.9|6,-1,|7,2,0.85";
  for (const std::string ending : {"\n", "\r\n", "\r"}) {
    SCOPED_TRACE(ending == "\r" ? "CR" : ending == "\n" ? "LF" : "CRLF");
    std::string text;
    for (const char c : rows) text += c == '|' ? ending : std::string(1, c);
    const auto records = read_detections(write("d.csv", text + ending));
    ASSERT_EQ(records.size(), 3u);
    EXPECT_EQ(at(records, 5).reported.frame, 0);
    EXPECT_DOUBLE_EQ(at(records, 5).reported.score, 0.9);
    EXPECT_EQ(at(records, 6).reported.frame, -1);
    EXPECT_EQ(at(records, 7).reported.frame, 2);
    EXPECT_DOUBLE_EQ(at(records, 7).reported.score, 0.85);
  }
}

// A read error (EIO) names the file, the line and the reason.
TEST_F(DetectionsTest, AReadErrorNamesTheFile) {
  const std::string eio = "/proc/self/mem";  // read() fails with EIO at offset 0
  std::error_code ec;
  if (!fs::is_regular_file(eio, ec)) GTEST_SKIP() << eio << " is not here";
  const std::string m = test::message_of<IoError>([&] { read_detections(eio, 10); });
  EXPECT_NE(m.find(eio), std::string::npos) << m;
  EXPECT_NE(m.find("Input/output error"), std::string::npos) << m;
}

TEST_F(DetectionsTest, WhiteSpaceSeparatedRowsAreAccepted) {
  const std::string path = write("d.txt", "3 0 0.25\r\n4\t-1\t0\n");
  const auto records = read_detections(path, 5);
  EXPECT_EQ(at(records, 3).reported.frame, 0);
  EXPECT_DOUBLE_EQ(at(records, 3).reported.score, 0.25);
  EXPECT_EQ(at(records, 4).reported.frame, -1);
}

TEST_F(DetectionsTest, ReadsLsgdRunCsvUsingTheCandidateFrame) {
  const std::string path =
      write("run.csv",
            "frame,image,loop_frame,candidate_frame,score,ms\n"
            "0,a.png,-1,-1,0,1.5\n"
            "1,\"b,\"\"quoted\"\"\nname.png\",-1,0,0.4,2.5\n"  // a quoted field over two lines
            "2,c.png,0,0,0.95,3\n");
  const auto records = read_detections(path, 3);
  EXPECT_EQ(at(records, 0).reported.frame, -1);
  EXPECT_DOUBLE_EQ(at(records, 0).timings.total_ms, 1.5);
  EXPECT_EQ(at(records, 1).reported.frame, 0);  // below the decision threshold, still reported
  EXPECT_DOUBLE_EQ(at(records, 1).reported.score, 0.4);
  EXPECT_DOUBLE_EQ(at(records, 1).timings.total_ms, 2.5);
  EXPECT_EQ(at(records, 2).reported.frame, 0);
  EXPECT_DOUBLE_EQ(at(records, 2).reported.score, 0.95);
  // loop_frame says what lsgd declared: frame 2 only.
  EXPECT_FALSE(at(records, 1).loop);
  EXPECT_TRUE(at(records, 2).loop);
}

// Image names with a newline or a lone CR (both legal in a Linux file name)
// in lsgd run's own CSV: written quoted, read back as one row each, and a
// resumed run's trim() keeps the rows the database holds (it took the
// newline for a row's end and cut every row after it; a lone CR was written
// unquoted and ended the row for the readers).
TEST_F(DetectionsTest, NamesWithNewlinesOrCarriageReturnsStayInTheirRow) {
  const std::string path = (dir_ / "run.csv").string();
  const std::vector<std::string> names = {"a\nb.png", "c\rd.png", "e.png", "f\r\ng,\".png"};
  {
    CsvWriter csv(path);
    for (std::size_t i = 0; i < names.size(); ++i) {
      Result r;
      r.frame = static_cast<std::int64_t>(i);
      r.best = {i > 0 ? 0 : -1, 0.5};
      csv.write(r, names[i]);
    }
  }
  EXPECT_EQ(read_detections(path, 4).size(), 4u);
  EXPECT_EQ(at(read_detections(path, 4), 3).reported.frame, 0);
  const CsvWriter::Trim trim = CsvWriter::trim(path, 2);
  EXPECT_EQ(trim.last_row, 2);
  EXPECT_EQ(trim.dropped, 1);
  EXPECT_FALSE(trim.partial);
  const auto kept = read_detections(path, 4);
  EXPECT_EQ(kept.size(), 3u);
  EXPECT_EQ(at(kept, 3).reported.frame, -1);  // cut
  EXPECT_EQ(at(kept, 2).reported.frame, 0);
  // Lines that are no row, added after the rows, are cut and counted apart
  // (a resumed run said the database had lost frames for them).
  std::ofstream(path, std::ios::app) << "garbage\nmore\n";
  const CsvWriter::Trim other = CsvWriter::trim(path, 2);
  EXPECT_EQ(other.dropped, 0);
  EXPECT_EQ(other.other, 2);
  EXPECT_EQ(read_detections(path, 4).size(), 3u);
}

// trim() shows the rows at the cut (the last kept, the first cut; images
// unquoted) before it cuts, and cuts nothing when the check throws: a
// resumed run refuses another run's CSV this way (lsgd run's continue_csv).
TEST_F(DetectionsTest, TrimShowsTheRowsAtTheCutAndCutsNothingWhenRefused) {
  const std::string path = (dir_ / "run.csv").string();
  {
    CsvWriter csv(path);
    for (int i = 0; i < 5; ++i) {
      Result r;
      r.frame = i;
      csv.write(r, i == 3 ? "img,\"3\".png" : "img" + std::to_string(i) + ".png");
    }
  }
  const auto slurp = [](const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::string before = slurp(path);
  std::vector<std::pair<std::int64_t, std::string>> seen;
  const auto refuse = [&](std::int64_t frame, const std::string& image) {
    seen.emplace_back(frame, image);
    if (frame == 3) throw InvalidArgument("another run's CSV");
  };
  EXPECT_THROW(CsvWriter::trim(path, 2, refuse), InvalidArgument);
  const std::vector<std::pair<std::int64_t, std::string>> expected = {{2, "img2.png"},
                                                                       {3, "img,\"3\".png"}};
  EXPECT_EQ(seen, expected);
  EXPECT_EQ(slurp(path), before);  // nothing cut
  seen.clear();
  const CsvWriter::Trim trim =
      CsvWriter::trim(path, 3, [&](std::int64_t f, const std::string& i) { seen.emplace_back(f, i); });
  EXPECT_EQ(trim.dropped, 1);
  const std::vector<std::pair<std::int64_t, std::string>> cut = {{3, "img,\"3\".png"}, {4, "img4.png"}};
  EXPECT_EQ(seen, cut);
  EXPECT_EQ(read_detections(path, 5).size(), 4u);
}

// csv_fields() is the inverse of csv_field() for any text (the one reader
// of quoted fields: a resumed run's row check and detections files both use
// it; the row check had its own copy). Spaces are kept; the detections
// reader trims them around numbers.
TEST_F(DetectionsTest, CsvFieldsReadBackWhatCsvFieldWrote) {
  const std::vector<std::string> texts = {"", "a.png", " lead.png", "trail.png ", "a,b", "\"q\"",
                                          "x\ny", "c\rd", "\"\"", ",", "e,\"f\"\n,g"};
  for (const std::string& t : texts) {
    const std::vector<std::string> fields = csv_fields("7," + csv_field(t) + ",-1");
    ASSERT_EQ(fields.size(), 3u) << t;
    EXPECT_EQ(fields[1], t);
    EXPECT_EQ(fields[2], "-1");
  }
  EXPECT_EQ(csv_fields(" 1 , 2 ").front(), " 1 ");
  const std::string path = write("spaces.csv", "query,match,score\n 3 , 1 , 5 \n");
  EXPECT_EQ(at(read_detections(path, 5), 3).reported.frame, 1);
}

// A CSV written row by row has one writer: a second CsvWriter (another
// lsgd run or eval given the same --output) is refused before it truncates
// anything; two runs interleaved their rows, both exiting 0 (issue 35,
// seventh pass). trim() waits for no one either.
TEST_F(DetectionsTest, ASecondWriterOfTheSameCsvIsRefusedAndChangesNothing) {
  const std::string path = (dir_ / "run.csv").string();
  const auto slurp = [](const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  {
    CsvWriter first(path);
    Result r;
    r.frame = 0;
    first.write(r, "a.png");
    const std::string before = slurp(path);
    const std::string m = test::message_of<IoError>([&] { CsvWriter second(path); });
    EXPECT_NE(m.find("another process is writing it"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_THROW(CsvWriter(path, CsvWriter::kAppend), IoError);
    EXPECT_THROW(CsvWriter::trim(path, 0), IoError);
    EXPECT_EQ(slurp(path), before);
    r.frame = 1;
    first.write(r, "b.png");
  }
  EXPECT_EQ(read_detections(path, 2).size(), 2u);
  CsvWriter again(path);  // the first one is gone: its lock with it
  // Devices are not locked: two writers may share /dev/null.
  CsvWriter null1("/dev/null");
  CsvWriter null2("/dev/null");
}

// Frame ids are bounded before the records are allocated.
TEST_F(DetectionsTest, HugeFrameIdsAreFormatErrors) {
  expect_line_error("10000000000,0,0.5\n", 1, "implausibly large");
  expect_line_error("5,99999999,0.5\n", 1, "99999999");
  EXPECT_THROW(read_detections(write("ok.csv", "1,0,0.5\n"), lsgd::kMaxFrames + 1),
               lsgd::InvalidArgument);
}

TEST_F(DetectionsTest, LsgdRunLoopFrameMustBeTheCandidateOrNone) {
  expect_line_error(
      "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers\n0,a.png,3,1,7.5,1,4,30\n",
      2, "loop_frame '3'");
  const std::string path = write(
      "new.csv",
      "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers\n0,a.png,-1,-1,0,1,0,-1\n"
      "1,b.png,0,0,7.5,1,4.0,30\n");
  const auto records = read_detections(path, 2);
  EXPECT_TRUE(at(records, 1).loop);
  EXPECT_EQ(at(records, 1).reported.frame, 0);
}

// lsgd run's ranking columns give each record its ranking; bad values name
// the column, file and line.
TEST_F(DetectionsTest, LsgdRunRankingColumnsAreReadAndChecked) {
  const std::string header =
      "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,"
      "ranked_score,ranked_confirmed\n";
  const auto records = read_detections(
      write("ranked.csv", header + "0,a.png,-1,-1,0,1,0,-1,-1,0,0\n1,b.png,-1,0,5,1,5,12,0,2.5,1\n"), 2);
  ASSERT_TRUE(at(records, 1).ranking.has_value());
  EXPECT_EQ(at(records, 1).ranking->best.frame, 0);
  EXPECT_DOUBLE_EQ(at(records, 1).ranking->best.score, 2.5);
  EXPECT_TRUE(at(records, 1).ranking->confirmed);
  EXPECT_EQ(at(records, 0).ranking->best.frame, -1);
  expect_line_error(header + "1,b.png,-1,0,5,1,5,12,x,2.5,1\n", 2, "ranked_frame 'x'");
  expect_line_error(header + "1,b.png,-1,0,5,1,5,12,0,inf,1\n", 2, "ranked_score 'inf'");
  expect_line_error(header + "1,b.png,-1,0,5,1,5,12,0,1e300,1\n", 2, "ranked_score 1e300 is beyond");
  expect_line_error(header + "1,b.png,-1,0,5,1,5,12,0,2.5,yes\n", 2, "ranked_confirmed 'yes'");
  expect_line_error(header + "1,b.png,-1,0,5,1,5,12,10,2.5,1\n", 2, "ranked_frame 10 is outside");
}

TEST_F(DetectionsTest, ScoresLikeHandComputation) {
  // 10 frames, window 2: loops 5~0, 6~1, 7~2 (three positives).
  GroundTruth gt(10);
  gt.add(5, 0);
  gt.add(6, 1);
  gt.add(7, 2);
  const std::string path = write("d.csv",
                                 "query,match,score\n"
                                 "5,0,0.9\n"  // true
                                 "6,3,0.8\n"  // false
                                 "7,2,0.7\n"  // true
                                 "9,4,0.6\n"  // false, on a loop-free query
                                 "8,-1,0\n");
  const Metrics m = evaluate(read_detections(path, gt.frames()), gt, 2);
  EXPECT_EQ(m.frames, 10);
  EXPECT_EQ(m.positives, 3);
  // Sweep: 0.9 (1/1, 1/3), 0.8 (1/2, 1/3), 0.7 (2/3, 2/3), 0.6 (2/4, 2/3).
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.average_precision, (1.0 / 3.0) * 1.0 + (1.0 / 3.0) * (2.0 / 3.0));
  EXPECT_DOUBLE_EQ(m.recall_at_1, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.recall_at_10, 2.0 / 3.0);  // one candidate per query from a file
}

// A ground truth naming frame 9,999,999 and a one-row file: the records are
// the row (memory follows the file, not the ids: dense records were 2.3 GB),
// and the frames without a row still count, as queries that reported nothing.
TEST_F(DetectionsTest, FarFrameIdsCostTheRowsAndEveryFrameIsAQuery) {
  GroundTruth gt(10'000'000);
  gt.add(9'999'999, 0);
  gt.add(5'000'000, 1);  // a revisit without a row: missed
  const std::string path = write("far.csv", "query,match,score\n9999999,0,0.9\n");
  const auto records = read_detections(path, gt.frames());
  ASSERT_EQ(records.size(), 1u);
  const Metrics m = evaluate(records, gt, 2);
  EXPECT_EQ(m.frames, 10'000'000);
  EXPECT_EQ(m.positives, 2);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_at_decision, 0.5);
  EXPECT_EQ(m.declared_true, 1);
  // The same rows given as one record per frame score the same.
  GroundTruth small(10);
  small.add(5, 0);
  small.add(7, 2);
  const auto sparse = read_detections(write("s.csv", "5,0,0.9\n8,3,0.95\n"), 10);
  std::vector<FrameRecord> dense(10);
  for (std::int64_t f = 0; f < 10; ++f) dense[static_cast<std::size_t>(f)] = at(sparse, f);
  const Metrics a = evaluate(sparse, small, 2), b = evaluate(dense, small, 2);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.positives, b.positives);
  EXPECT_EQ(a.declared_loops, b.declared_loops);
  EXPECT_DOUBLE_EQ(a.recall_at_100_precision, b.recall_at_100_precision);
  EXPECT_DOUBLE_EQ(a.average_precision, b.average_precision);
  EXPECT_DOUBLE_EQ(a.recall_at_1, b.recall_at_1);
  EXPECT_EQ(a.positives, 2);
  EXPECT_DOUBLE_EQ(a.average_precision, 0.5 * 0.5);  // 0.95 false, then 0.9 true: (1/2, 1/2)
}

TEST_F(DetectionsTest, MalformedRowsNameFileAndLine) {
  expect_line_error("1,0,0.5\n2,x,0.5\n", 2, "match 'x'");
  expect_line_error("# c\n\n1,0\n", 3, "at least 3 fields");
  expect_line_error("query,match,score\n1,0,abc\n", 2, "score 'abc'");
  expect_line_error("1,0,nan\n", 1, "score 'nan'");
  // Finite, but spanning more than a double holds: the report's charts
  // were '-nan' (and a histogram bin was cast from NaN).
  expect_line_error("1,0,1e308\n2,0,-1e308\n", 1, "score 1e308 is beyond the +-1e+15 lsgd reads");
  expect_line_error("1,0,0.5\n2,0,-1e16\n", 2, "score -1e16 is beyond");
  expect_line_error("-2,0,0.5\n", 1, "query '-2'");
  expect_line_error("1,-5,0.5\n", 1, "match '-5'");
  expect_line_error("1,0,0.5\n12,0,0.5\n", 2, "query 12 is outside the 10 frames");
  expect_line_error("1,10,0.5\n", 1, "match 10 is outside");
  expect_line_error("1,0,0.5\n3,0,0.5\n1,2,0.4\n", 3, "already has a row on line 1");
  expect_line_error("1,\"0,0.5\n", 1, "never closed");
  expect_line_error("frame,image,loop_frame,candidate_frame,ms\n", 1, "score");
}

TEST_F(DetectionsTest, EmptyOrMissingFilesAreErrors) {
  const std::string empty = write("empty.csv", "# nothing\n\n");
  EXPECT_NE(test::message_of<FormatError>([&] { read_detections(empty, 5); }).find("no row"),
            std::string::npos);
  const std::string header_only = write("header.csv", "query,match,score\n");
  EXPECT_THROW(read_detections(header_only, 5), FormatError);
  const std::string missing = (dir_ / "missing.csv").string();
  EXPECT_NE(test::message_of<IoError>([&] { read_detections(missing, 5); }).find(missing),
            std::string::npos);
}

// A top-k file (lsgd match): a query's rows are its candidates by rank, rank
// 1 the reported match, in any row order; a repeated rank or a query without
// rank 1 is refused by file and line.
TEST_F(DetectionsTest, TopKRowsAreTheCandidatesByRank) {
  const std::string path = write("topk.csv",
                                 "query,match,score,similarity,rank\n"
                                 "5,2,1.5,0.9,2\n"
                                 "5,1,2.5,0.95,1\n"
                                 "5,0,0.5,0.8,3\n"
                                 "6,-1,,0,1\n");
  const std::vector<FrameRecord> r = read_detections(path, 7);
  EXPECT_EQ(at(r, 5).reported.frame, 1);
  EXPECT_EQ(at(r, 5).reported.score, 2.5);
  ASSERT_EQ(at(r, 5).candidates.size(), 3u);
  EXPECT_EQ(at(r, 5).candidates[1].frame, 2);
  EXPECT_EQ(at(r, 5).candidates[2].frame, 0);
  EXPECT_EQ(at(r, 6).reported.frame, -1);
  EXPECT_TRUE(at(r, 6).candidates.empty());
  const std::string twice = write("twice.csv", "query,match,score,rank\n5,1,1,1\n5,2,1,1\n");
  EXPECT_NE(test::message_of<FormatError>([&] { read_detections(twice, 7); })
                .find(twice + ":3: query 5 already has rank 1 on line 2"),
            std::string::npos);
  const std::string no_first = write("nofirst.csv", "query,match,score,rank\n5,1,1,2\n");
  EXPECT_NE(test::message_of<FormatError>([&] { read_detections(no_first, 7); })
                .find("query 5 has ranks from 2 but no rank 1"),
            std::string::npos);
  const std::string bad = write("badrank.csv", "query,match,score,rank\n5,1,1,0\n");
  EXPECT_NE(test::message_of<FormatError>([&] { read_detections(bad, 7); }).find("rank '0' is not a rank"),
            std::string::npos);
  // Without a rank column a repeated query stays an error.
  const std::string plain = write("plain.csv", "query,match,score\n5,1,1\n5,2,1\n");
  EXPECT_NE(test::message_of<FormatError>([&] { read_detections(plain, 7); }).find("already has a row on line 2"),
            std::string::npos);
}

}  // namespace
}  // namespace lsgd::eval
