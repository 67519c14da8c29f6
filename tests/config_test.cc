#include "lsgd/io/config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <set>
#include <sstream>
#include <fstream>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/limits.h"
#include "lsgd/options.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;

const char* kSource = "test.yaml";

void expect_equal(const DetectorOptions& a, const DetectorOptions& b) {
  EXPECT_EQ(a.segmentation.superpixel_size, b.segmentation.superpixel_size);
  EXPECT_EQ(a.segmentation.iterations, b.segmentation.iterations);
  EXPECT_EQ(a.segmentation.intensity_scale, b.segmentation.intensity_scale);
  EXPECT_EQ(a.segmentation.distance_scale, b.segmentation.distance_scale);
  EXPECT_EQ(a.similarity.metric, b.similarity.metric);
  EXPECT_EQ(a.search.mode, b.search.mode);
  EXPECT_EQ(a.search.min_gap, b.search.min_gap);
  EXPECT_EQ(a.search.top_n, b.search.top_n);
  EXPECT_EQ(a.search.nodes.threshold_0, b.search.nodes.threshold_0);
  EXPECT_EQ(a.search.nodes.alpha, b.search.nodes.alpha);
  EXPECT_EQ(a.search.nodes.beta, b.search.nodes.beta);
  EXPECT_EQ(a.verification.stages, b.verification.stages);
  EXPECT_EQ(a.verification.max_candidates, b.verification.max_candidates);
  EXPECT_EQ(a.verification.temporal_options.frames, b.verification.temporal_options.frames);
  EXPECT_EQ(a.verification.temporal_options.tolerance, b.verification.temporal_options.tolerance);
  EXPECT_EQ(a.verification.temporal_options.agree, b.verification.temporal_options.agree);
  EXPECT_EQ(a.verification.temporal_options.long_frames,
            b.verification.temporal_options.long_frames);
  const GeometricOptions& ga = a.verification.geometric_options;
  const GeometricOptions& gb = b.verification.geometric_options;
  EXPECT_EQ(ga.max_features, gb.max_features);
  EXPECT_EQ(ga.min_side, gb.min_side);
  EXPECT_EQ(ga.max_side, gb.max_side);
  EXPECT_EQ(ga.ratio, gb.ratio);
  EXPECT_EQ(ga.ransac_threshold, gb.ransac_threshold);
  EXPECT_EQ(ga.min_inliers, gb.min_inliers);
  EXPECT_EQ(ga.min_inlier_ratio, gb.min_inlier_ratio);
  EXPECT_EQ(a.decision.threshold, b.decision.threshold);
  EXPECT_EQ(a.decision.geometric_bonus, b.decision.geometric_bonus);
  EXPECT_EQ(a.decision.continuity_bonus, b.decision.continuity_bonus);
  EXPECT_EQ(a.decision.continuity_inliers, b.decision.continuity_inliers);
}

// Options that differ from the defaults in every field.
DetectorOptions custom_options() {
  DetectorOptions o;
  o.segmentation.superpixel_size = 17;
  o.segmentation.iterations = 3;
  o.segmentation.intensity_scale = 0.1;       // not exact in binary
  o.segmentation.distance_scale = 1.0 / 3.0;  // needs 17 digits
  o.similarity.metric = SimilarityMetric::kNormalizedL1;
  o.search.mode = kNodesSearch;
  o.search.min_gap = 123456789;
  o.search.top_n = 7;
  o.search.nodes.threshold_0 = 0.123456789012345678;
  o.search.nodes.alpha = 2.0 / 7.0;
  o.search.nodes.beta = 1.1;
  o.verification.stages = {kTemporalStage};
  o.verification.max_candidates = 5;
  o.verification.temporal_options = {11, 4, 2, 30};
  o.verification.geometric_options.max_features = 321;
  o.verification.geometric_options.min_side = 100;
  o.verification.geometric_options.max_side = 480;
  o.verification.geometric_options.ratio = 0.77;
  o.verification.geometric_options.ransac_threshold = 2.5;
  o.verification.geometric_options.min_inliers = 33;
  o.verification.geometric_options.min_inlier_ratio = 0.4;
  o.decision.threshold = 0.7000000000000001;
  o.decision.geometric_bonus = 1.0 / 3.0;
  o.decision.continuity_bonus = 0;
  o.decision.continuity_inliers = 0.55;
  return o;
}

// Expects parse_config(text) to throw E with a message containing every part.
template <typename E>
void expect_error(const std::string& text, const std::vector<std::string>& parts) {
  try {
    parse_config(text, kSource);
    ADD_FAILURE() << "no exception for:\n" << text;
  } catch (const E& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "message '" << e.what() << "' lacks '" << part << "' for:\n"
          << text;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type '" << e.what() << "' for:\n" << text;
  }
}

TEST(ParseConfig, EmptyTextGivesTheBase) {
  expect_equal(parse_config("", kSource), DetectorOptions{});
  expect_equal(parse_config("# only a comment\n", kSource), DetectorOptions{});
  expect_equal(parse_config("~\n", kSource), DetectorOptions{});
  const DetectorOptions base = custom_options();
  expect_equal(parse_config("", kSource, base), base);
  expect_equal(parse_config("segmentation:\n", kSource, base), base);  // empty section
}

TEST(ParseConfig, FullConfig) {
  const DetectorOptions o = parse_config(
      "segmentation:\n"
      "  superpixel_size: 20\n"
      "  iterations: 5\n"
      "  intensity_scale: 4.5\n"
      "  distance_scale: 2e-1\n"
      "similarity:\n"
      "  metric: l1\n"
      "search:\n"
      "  mode: nodes\n"
      "  min_gap: 30\n"
      "  top_n: 3\n"
      "  nodes: {threshold_0: 0.5, alpha: 0.7, beta: +1.1}\n"
      "decision:\n"
      "  threshold: 0.6\n",
      kSource);
  EXPECT_EQ(o.segmentation.superpixel_size, 20);
  EXPECT_EQ(o.segmentation.iterations, 5);
  EXPECT_EQ(o.segmentation.intensity_scale, 4.5);
  EXPECT_EQ(o.segmentation.distance_scale, 0.2);
  EXPECT_EQ(o.similarity.metric, SimilarityMetric::kL1);
  EXPECT_EQ(o.search.mode, kNodesSearch);
  EXPECT_EQ(o.search.min_gap, 30);
  EXPECT_EQ(o.search.top_n, 3);
  EXPECT_EQ(o.search.nodes.threshold_0, 0.5);
  EXPECT_EQ(o.search.nodes.alpha, 0.7);
  EXPECT_EQ(o.search.nodes.beta, 1.1);
  EXPECT_EQ(o.decision.threshold, 0.6);
}

TEST(ParseConfig, ToYamlRoundTrips) {
  const DetectorOptions custom = custom_options();
  expect_equal(parse_config(to_yaml(custom), kSource), custom);
  expect_equal(parse_config(to_yaml(DetectorOptions{}), kSource, custom), DetectorOptions{});
  const std::string text = to_yaml(DetectorOptions{});
  for (const char* key :
       {"segmentation:", "superpixel_size: 40", "iterations: 3", "intensity_scale: 20",
        "distance_scale: 1.0", "metric: reference", "mode: exhaustive", "min_gap: 50", "top_n: 10",
        "threshold_0: 0.9", "alpha: 0.8", "beta: 1.0", "decision:", "threshold: 7.0", "geometric_bonus: 3.5", "continuity_bonus: 2.5",
        "continuity_inliers: 0.2", "stages: temporal,geometric", "max_side: 240"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << " missing in:\n" << text;
  }
}

TEST(ParseConfig, PartialConfigKeepsTheBase) {
  const DetectorOptions base = custom_options();
  const DetectorOptions o =
      parse_config("search:\n  top_n: 4\n  nodes:\n    beta: 0.9\n", kSource, base);
  DetectorOptions expected = base;
  expected.search.top_n = 4;
  expected.search.nodes.beta = 0.9;
  expect_equal(o, expected);
}

TEST(ParseConfig, UnknownKeysAreFormatErrors) {
  expect_error<FormatError>("segmentaton:\n  iterations: 3\n",
                            {kSource, "unknown key 'segmentaton'; did you mean 'segmentation'?",
                             "segmentation, descriptor, similarity"});
  expect_error<FormatError>("search:\n  min_gapp: 3\n",
                            {kSource, "unknown key 'search.min_gapp'; did you mean 'search.min_gap'?"});
  expect_error<FormatError>("search:\n  foo: 1\n",
                            {kSource, "unknown key 'search.foo'", "mode, min_gap, top_n, nodes"});
  expect_error<FormatError>("search:\n  nodes: {gamma: 1}\n",
                            {kSource, "'search.nodes.gamma'", "threshold_0, alpha, beta"});
  expect_error<FormatError>("decision:\n  threshold: 0.5\n  thresold: 0.5\n",
                            {"'decision.thresold'"});
}

TEST(ParseConfig, DuplicateKeysAreFormatErrors) {
  expect_error<FormatError>("search:\n  top_n: 3\n  top_n: 4\n", {kSource, "'search.top_n'"});
}

TEST(ParseConfig, WrongTypesAreFormatErrors) {
  expect_error<FormatError>(
      "segmentation:\n  superpixel_size: abc\n",
      {kSource, "'segmentation.superpixel_size' must be an integer", "'abc'"});
  expect_error<FormatError>("segmentation:\n  superpixel_size: 40.5\n",
                            {"'segmentation.superpixel_size'", "40.5"});
  expect_error<FormatError>("segmentation:\n  iterations: 40abc\n",
                            {"'segmentation.iterations'", "40abc"});
  expect_error<FormatError>("segmentation:\n  iterations: \"40\"\n",
                            {"'segmentation.iterations'", "quoted"});
  expect_error<FormatError>("segmentation:\n  iterations: true\n",
                            {"'segmentation.iterations'", "true"});
  expect_error<FormatError>("segmentation:\n  iterations:\n",
                            {"'segmentation.iterations'", "null"});
  expect_error<FormatError>("segmentation:\n  iterations: {a: 1}\n",
                            {"'segmentation.iterations'", "a map"});
  expect_error<FormatError>("segmentation:\n  intensity_scale: [1, 2]\n",
                            {"'segmentation.intensity_scale' must be a number", "a sequence"});
  expect_error<FormatError>("segmentation:\n  distance_scale: 1.0.0\n",
                            {"'segmentation.distance_scale'", "1.0.0"});
  expect_error<FormatError>("search:\n  min_gap: 1e3\n", {"'search.min_gap'"});
  expect_error<FormatError>("search:\n  nodes: 3\n", {"'search.nodes' must be a map"});
  expect_error<FormatError>("similarity: l1\n", {"'similarity' must be a map"});
  expect_error<FormatError>("- 1\n- 2\n", {kSource, "map"});
  expect_error<FormatError>("just text\n", {kSource, "map"});
}

TEST(ParseConfig, InvalidEnumsAreFormatErrors) {
  expect_error<FormatError>("similarity:\n  metric: cosine\n",
                            {kSource, "'similarity.metric'", "cosine", "normalized_l1"});
  expect_error<FormatError>("search:\n  mode: fast\n", {kSource, "'search.mode'", "fast"});
  expect_error<FormatError>("search:\n  mode: [nodes]\n", {"'search.mode'"});
  expect_error<FormatError>("descriptor:\n  storage: tiny\n",
                            {kSource, "'descriptor.storage'", "tiny", "compact"});
  // A NUL inside a value is shown as \0 and the message goes on past it
  // (what() ended at the NUL: "search mode 'nodes (line 2)").
  expect_error<FormatError>("search:\n  mode: \"nodes\\0evil\"\n",
                            {"'nodes\\0evil' is unknown: expected one of exhaustive", "(line 2)"});
  EXPECT_STREQ(InvalidArgument(std::string("a\0b", 3)).what(), "a\\0b");
  // Every control character is escaped, so a message stays one line (a
  // newline forged "lsgd:" lines, ESC reached the terminal); and a name value
  // is cut after 64 bytes as a number's is (100 KB was echoed whole).
  EXPECT_STREQ(IoError("x\nlsgd: note: forged\x1b[31m\x7f").what(), "x\\x0alsgd: note: forged\\x1b[31m\\x7f");
  expect_error<FormatError>("search:\n  mode: \"nodes\\nlsgd: note: forged\"\n",
                            {"'nodes\\x0alsgd: note: forged' is unknown"});
  DetectorOptions o;
  for (const std::string& key : {std::string("search.mode"), std::string("descriptor.type"),
                                 std::string("similarity.metric"), std::string("descriptor.storage"),
                                 std::string("verification.stages"), "search." + std::string(100000, 'k')}) {
    const std::string value(100000, 'v');
    const std::string m = test::message_of<InvalidArgument>([&] { set_option(o, key, value); });
    EXPECT_LT(m.size(), 1000u) << key.substr(0, 20) << ": " << m.substr(0, 200);
    EXPECT_NE(m.find(" bytes)"), std::string::npos) << key.substr(0, 20) << ": " << m.substr(0, 200);
  }
}

TEST(LoadConfig, ShippedConfigsLoad) {
  const std::string dir = std::string(LSGD_SOURCE_DIR) + "/configs/";
  const DetectorOptions paper = load_config(dir + "paper.yaml");
  EXPECT_EQ(paper.segmentation.iterations, 10);
  EXPECT_FALSE(paper.verification.has(kTemporalStage));
  const DetectorOptions reference = load_config(dir + "reference-code.yaml");
  EXPECT_EQ(reference.segmentation.superpixel_size, 50);
  const DetectorOptions compact = load_config(dir + "compact.yaml");
  EXPECT_EQ(compact.descriptor.storage, HistogramStorage::kCompact);
  DetectorOptions expected;  // otherwise the defaults
  expected.descriptor.storage = HistogramStorage::kCompact;
  EXPECT_EQ(to_yaml(compact), to_yaml(expected));
}

TEST(ParseConfig, DescriptorStorage) {
  EXPECT_EQ(parse_config("", "t").descriptor.storage, HistogramStorage::kExact);
  const DetectorOptions o = parse_config("descriptor:\n  storage: compact\n", "t");
  EXPECT_EQ(o.descriptor.storage, HistogramStorage::kCompact);
  EXPECT_EQ(parse_config(to_yaml(o), "t").descriptor.storage, HistogramStorage::kCompact);
  expect_error<FormatError>("descriptor:\n  bins: 64\n", {kSource, "unknown key 'descriptor.bins'", "storage"});
}

TEST(ParseConfig, OutOfRangeValuesAreInvalidArguments) {
  for (const char* text :
       {"segmentation: {superpixel_size: 0}", "segmentation: {iterations: 0}",
        "decision: {threshold: 0}", "decision: {threshold: 1001}", "decision: {geometric_bonus: -1}",
        "decision: {continuity_inliers: 0}", "verification: {geometric: {max_side: 100}}",
        "search: {top_n: 0}", "search: {min_gap: -1}",
        "segmentation: {intensity_scale: -1.0}", "decision: {threshold: .nan}",
        "segmentation: {superpixel_size: 99999999999}"}) {
    expect_error<InvalidArgument>(text, {kSource});
  }
}

TEST(ParseConfig, MalformedYamlIsFormatError) {
  expect_error<FormatError>("search:\n  top_n: [1, 2\n", {kSource, "invalid YAML", "line"});
  expect_error<FormatError>("search: {top_n: 3\n", {kSource, "invalid YAML"});
  expect_error<FormatError>("a: b: c\n", {kSource, "invalid YAML"});
  expect_error<FormatError>("search: {}\n---\nsearch: {}\n", {kSource, "one YAML document"});
}

// Found by fuzz/fuzz_config: yaml-cpp 0.7's LoadAll never returns (and grows
// memory without bound) on these; they must be FormatErrors, quickly.
TEST(ParseConfig, StreamsThatHangYamlCppAreFormatErrors) {
  expect_error<FormatError>(",", {kSource, "invalid YAML"});
  expect_error<FormatError>(std::string("{\xc6\xcb},\n1\n"), {kSource, "invalid YAML"});
  expect_error<FormatError>("search: {}\n,\n", {kSource, "invalid YAML"});
}

// YAML's line breaks: LF, CRLF and a lone CR (a classic-Mac config was read
// as one line: "unknown key 'search:  min_gap'").
TEST(ParseConfig, EveryLineBreakReadsTheSameOptions) {
  for (const char* text : {"search:\n  min_gap: 7\ndecision:\n  threshold: 5\n",
                           "search:\r\n  min_gap: 7\r\ndecision:\r\n  threshold: 5\r\n",
                           "search:\r  min_gap: 7\rdecision:\r  threshold: 5\r"}) {
    const DetectorOptions o = parse_config(text, kSource);
    EXPECT_EQ(o.search.min_gap, 7);
    EXPECT_EQ(o.decision.threshold, 5.0);
  }
}

// Streams of many nodes are refused from the parser's events, before
// yaml-cpp builds a node: "[,,,...]" of 1 MB held 550 MB of nodes.
TEST(ParseConfig, MoreNodesThanAConfigCanHaveAreRefusedFirst) {
  expect_error<FormatError>("[" + std::string(20000, ',') + "]", {kSource, "more than 10000 YAML nodes"});
  std::string keys = "{";
  for (int i = 0; i < 6000; ++i) keys += "a" + std::to_string(i) + ",";
  expect_error<FormatError>(keys + "}", {kSource, "more than 10000 YAML nodes"});
  // Every option of the detector, nested, is far below.
  EXPECT_NO_THROW(parse_config(to_yaml(DetectorOptions{}), kSource));
}

// A NUL byte (a binary file, UTF-16 without a byte-order mark) is said to
// be one, on its line: yaml-cpp's message was "unknown escape character:
// \x0a" of a config holding no escape.
TEST(ParseConfig, ANulByteIsSaidToBeOne) {
  expect_error<FormatError>(std::string("search:\n  mode: nodes\0\n", 23),
                            {kSource, "invalid YAML: a NUL byte on line 2", "UTF-8 text"});
  expect_error<FormatError>(std::string("\0\0", 2), {kSource, "a NUL byte on line 1"});
  // UTF-16 with its byte-order mark is YAML, and read.
  const std::string utf16("\xff\xfes\0e\0a\0r\0c\0h\0:\0 \0{\0}\0\n\0", 24);
  EXPECT_NO_THROW(parse_config(utf16, kSource));
}

// Nesting deeper than a config can be is refused from the parser's events
// too: 500 levels got yaml-cpp's "bad file", and with a small stack its
// recursion overflowed first.
TEST(ParseConfig, DeeperNestingThanAConfigCanHaveIsRefusedFirst) {
  for (const int depth : {65, 500, 5000}) {
    expect_error<FormatError>(std::string(static_cast<std::size_t>(depth), '[') +
                                  std::string(static_cast<std::size_t>(depth), ']'),
                              {kSource, "YAML nested more than 64 levels deep (line 1)"});
    std::string maps;
    for (int i = 0; i < depth; ++i) maps += "{a: ";
    expect_error<FormatError>(maps + "1" + std::string(static_cast<std::size_t>(depth), '}'),
                              {kSource, "YAML nested more than 64 levels deep"});
  }
  // 64 levels of sequences are no config, but not refused for their depth.
  try {
    parse_config(std::string(64, '[') + std::string(64, ']'), kSource);
  } catch (const FormatError& e) {
    EXPECT_EQ(std::string(e.what()).find("nested"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------- files

class LoadConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(LSGD_TEST_TMP) /
           (std::string("config_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(LoadConfigTest, ReadsAFile) {
  const std::string path = (dir_ / "lsgd.yaml").string();
  std::ofstream(path) << to_yaml(custom_options());
  expect_equal(load_config(path), custom_options());
  std::ofstream(path) << "search:\n  top_n: 5\n";
  EXPECT_EQ(load_config(path, custom_options()).search.top_n, 5);
  EXPECT_EQ(load_config(path, custom_options()).segmentation.iterations, 3);
}

TEST_F(LoadConfigTest, ErrorsNameTheFile) {
  const std::string path = (dir_ / "bad.yaml").string();
  std::ofstream(path) << "search:\n  top_n: 0\n";
  try {
    load_config(path);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// A config is at most 64 KiB (kMaxConfigBytes), read or not.
TEST_F(LoadConfigTest, AFileBeyondTheConfigLimitIsRefusedUnread) {
  const fs::path big = dir_ / "big.yaml";
  std::ofstream(big) << "# " << std::string(static_cast<std::size_t>(kMaxConfigBytes), 'x') << "\n";
  const std::string m = test::message_of<FormatError>([&] { load_config(big.string()); });
  EXPECT_NE(m.find("more than the 65536 this lsgd reads"), std::string::npos) << m;
}

TEST_F(LoadConfigTest, MissingFileIsIoError) {
  const std::string path = (dir_ / "missing.yaml").string();
  try {
    load_config(path);
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_config(dir_.string()), IoError);  // a folder is not a config file
}

TEST(ParseConfig, VerificationSection) {
  const DetectorOptions o = parse_config(
      "verification:\n  stages: temporal,geometric\n  temporal: {frames: 5}\n"
      "  geometric: {min_inliers: 12}\n",
      kSource);
  EXPECT_EQ(o.verification.stages, (std::vector<std::string>{kTemporalStage, kGeometricStage}));
  EXPECT_EQ(o.verification.temporal_options.frames, 5);
  EXPECT_EQ(o.verification.geometric_options.min_inliers, 12);
  EXPECT_THROW(parse_config("verification:\n  stages: sift\n", kSource), lsgd::FormatError);
  EXPECT_THROW(parse_config("verification:\n  temporal: {window: 3}\n", kSource),
               lsgd::FormatError);
  EXPECT_THROW(parse_config("verification:\n  temporal: {frames: 0}\n", kSource),
               lsgd::InvalidArgument);
  EXPECT_THROW(parse_config("verification:\n  geometric: {ratio: 1.5}\n", kSource),
               lsgd::InvalidArgument);
}

}  // namespace
}  // namespace lsgd::io

namespace lsgd::io {
namespace {

// ---- the option tables (lsgd/options.h): one declaration per option

TEST(OptionTables, DocsOptionsMdIsGeneratedFromThem) {
  std::ifstream in(std::string(LSGD_SOURCE_DIR) + "/docs/options.md");
  ASSERT_TRUE(in) << "docs/options.md is missing";
  std::ostringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), options_reference())
      << "docs/options.md is stale: run build/tools/lsgd/lsgd options --markdown > docs/options.md";
}

TEST(OptionTables, EveryOptionIsDocumentedValidAndReadBackFromItsText) {
  const DetectorOptions defaults;
  std::set<std::string> keys;
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    SCOPED_TRACE(f.name);
    EXPECT_TRUE(keys.insert(f.name).second) << "declared twice";
    EXPECT_FALSE(f.doc.empty());
    EXPECT_TRUE(f.text);
    // The default's text sets the default.
    DetectorOptions o;
    set_option(o, f.name, f.text(defaults));
    EXPECT_EQ(to_yaml(o), to_yaml(defaults));
    if (f.kind == OptionKind::kChoice) {
      for (const std::string& c : f.choices()) {
        DetectorOptions p;
        set_option(p, f.name, c);
        EXPECT_EQ(option_text(p, f.name), c);
        EXPECT_NO_THROW(p.check());
        EXPECT_EQ(option_text(parse_config(to_yaml(p), kSource), f.name), c);
      }
      EXPECT_THROW(set_option(o, f.name, "no-such-value"), InvalidArgument);
      continue;
    }
    // Numbers: the default is in range, the ends are accepted, just outside is
    // refused by check() naming the key, and a value other than the default
    // goes through YAML and back.
    const double v = f.number(defaults);
    EXPECT_TRUE((f.lo_open ? v > f.lo : v >= f.lo) && v <= f.hi);
    const bool integer = f.kind == OptionKind::kInteger;
    const auto text = [integer](double x) {
      return integer ? std::to_string(static_cast<std::int64_t>(x)) : format_real(x);
    };
    const double below = integer ? f.lo - 1 : f.lo_open ? f.lo : f.lo - 0.5;
    for (const double bad : {below, integer ? f.hi + 1 : f.hi + 0.5}) {
      DetectorOptions p;
      set_option(p, f.name, text(bad));
      const std::string message = test::message_of<InvalidArgument>([&] { p.check(); });
      EXPECT_NE(message.find(f.name), std::string::npos) << message;
      EXPECT_NE(message.find("out of range"), std::string::npos) << message;
    }
    DetectorOptions p;
    set_option(p, f.name, text(f.hi));
    if (f.name == "verification.temporal.frames") p.verification.temporal_options.long_frames = 0;
    if (f.name == "verification.geometric.min_side") p.verification.geometric_options.max_side = 0;
    EXPECT_NO_THROW(p.check()) << text(f.hi);
    const DetectorOptions back = parse_config(to_yaml(p), kSource);
    EXPECT_EQ(option_text(back, f.name), text(f.hi));
    EXPECT_EQ(to_yaml(back), to_yaml(p));
    EXPECT_THROW(set_option(p, f.name, "x"), InvalidArgument);
  }
  // Every stage is there.
  for (const char* key : {"segmentation.superpixel_size", "descriptor.storage",
                          "similarity.metric", "search.mode", "search.nodes.beta",
                          "verification.stages", "verification.temporal.long_frames",
                          "verification.geometric.min_inlier_ratio", "decision.threshold"}) {
    EXPECT_EQ(keys.count(key), 1u) << key;
  }
}

TEST(OptionTables, SetOptionNamesUnknownKeysAndWrongValues) {
  DetectorOptions o;
  std::string m = test::message_of<InvalidArgument>([&] { set_option(o, "search.nodes.bta", "1"); });
  EXPECT_NE(m.find("'search.nodes.bta'"), std::string::npos) << m;
  EXPECT_NE(m.find("search.nodes.beta"), std::string::npos) << m;  // the section's keys
  m = test::message_of<InvalidArgument>([&] { set_option(o, "search.min_gap", "12x"); });
  EXPECT_NE(m.find("search.min_gap = '12x' is not an integer"), std::string::npos) << m;
  m = test::message_of<InvalidArgument>([&] { set_option(o, "decision.threshold", "seven"); });
  EXPECT_NE(m.find("decision.threshold = 'seven' is not a number"), std::string::npos) << m;
  // Beyond the option's type (int), or beyond int64: out of range, not "not an integer".
  for (const char* big : {"99999999999", "9223372036854775807", "92233720368547758070"}) {
    m = test::message_of<InvalidArgument>([&] { set_option(o, "search.top_n", big); });
    EXPECT_NE(m.find(std::string("search.top_n = ") + big + " is out of range"), std::string::npos) << m;
  }
  // A real beyond a double (either way) is a number out of range, not "not a number".
  for (const char* big : {"1e309", "-1e400", "1e-400"}) {
    m = test::message_of<InvalidArgument>([&] { set_option(o, "decision.threshold", big); });
    EXPECT_NE(m.find(std::string("decision.threshold = ") + big + " is out of range: beyond what a double holds"),
              std::string::npos)
        << m;
  }
  // A value is shown on one line: a NUL escaped, a long one cut with its length.
  m = test::message_of<InvalidArgument>([&] { set_option(o, "search.min_gap", std::string("1\0x", 3)); });
  EXPECT_NE(m.find("search.min_gap = '1\\0x' is not an integer"), std::string::npos) << m;
  m = test::message_of<InvalidArgument>([&] { set_option(o, "decision.threshold", std::string(900000, '7') + "x"); });
  EXPECT_NE(m.find("... (900001 bytes)"), std::string::npos) << m.substr(0, 200);
  EXPECT_LT(m.size(), 200u);
  set_option(o, "search.mode", "nodes");
  set_option(o, "verification.stages", "geometric,temporal");
  EXPECT_EQ(option_text(o, "verification.stages"), "temporal,geometric");
  EXPECT_EQ(o.search.mode, "nodes");
}

// Which options a resumed database compares: not decision.*, and a stage's
// options only when the stored options use the stage.
TEST(OptionTables, ResumableAndAppliesSayWhatAResumeCompares) {
  DetectorOptions exhaustive;
  exhaustive.verification.stages = {kGeometricStage};
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    SCOPED_TRACE(f.name);
    EXPECT_EQ(f.resumable, f.name.rfind("decision.", 0) == 0);
    const bool applies = !f.applies || f.applies(exhaustive);
    const bool expected = f.name.rfind("search.nodes.", 0) != 0 &&
                          f.name.rfind("search.index.", 0) != 0 &&
                          f.name.rfind("verification.temporal.", 0) != 0 &&
                          f.name.rfind("descriptor.gradient.", 0) != 0;  // intensity by default
    EXPECT_EQ(applies, expected);
    EXPECT_EQ(f.applies == nullptr, f.when.empty());
  }
}

}  // namespace
}  // namespace lsgd::io
