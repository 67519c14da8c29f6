// Tests of frames described apart from the map (FrameDescription,
// include/lsgd/detector.h; issue 34): a robot's detector describes a frame,
// another detector (the map) processes or queries the description, and gets
// the Results and the state processing the image gives, in every search
// mode, through the description's bytes too. A description that does not
// fit the map (other options, another size, damaged bytes, a stage that
// cannot describe) is refused with nothing changed.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "detector_util.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/stage.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::expect_same;
using test::expect_same_state;
using test::frame;
using test::message_of;
using test::world;

using DescribedCase = test::ModeCase;
using test::index_of;
using test::options;

FrameDescription travelled(const FrameDescription& d) {
  const std::vector<std::uint8_t> bytes = encode_frame_description(d);
  return decode_frame_description(bytes.data(), bytes.size());
}

class Described : public ::testing::TestWithParam<DescribedCase> {};

// The robot describes, the map processes the description (every other frame
// through its bytes) and queries it: the map's answers and state are the
// image's.
TEST_P(Described, GivesTheResultsOfTheImage) {
  const DescribedCase c = GetParam();
  const DetectorOptions o = options(c);
  Detector reference(o), robot(o), map(o);
  const std::int64_t n = world().frames();
  std::int64_t loops = 0;
  for (std::int64_t i = 0; i < n; ++i) {
    const FrameDescription described = robot.describe_frame(frame(i));
    EXPECT_EQ(robot.size(), 0) << "describing stores nothing";
    const FrameDescription sent = i % 2 == 0 ? described : travelled(described);
    if (i % 7 == 3) expect_same(map.query(sent), reference.query(frame(i)));
    const Result expected = reference.process(frame(i));
    expect_same(map.process(sent), expected);
    loops += expected.loop ? 1 : 0;
    if (::testing::Test::HasFatalFailure()) return;
  }
  if (std::string(c.stages).find("geometric") != std::string::npos) {
    EXPECT_GT(loops, 10) << "the street's revisits";
  }
  expect_same_state(map, reference);
  EXPECT_EQ(index_of(map), index_of(reference));
}

INSTANTIATE_TEST_SUITE_P(
    Modes, Described,
    ::testing::Values(DescribedCase{kExhaustiveSearch, "temporal,geometric"},
                      DescribedCase{kExhaustiveSearch, "none"},
                      DescribedCase{kNodesSearch, "temporal,geometric"},
                      DescribedCase{kIndexSearch, "temporal,geometric", 0}));

TEST(DescribedFrames, BytesRoundTripExactAndCompact) {
  for (const HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    DetectorOptions o;
    o.descriptor.storage = storage;
    Detector robot(o);
    const FrameDescription d = robot.describe_frame(frame(5));
    const FrameDescription back = travelled(d);
    EXPECT_EQ(back.width, d.width);
    EXPECT_EQ(back.height, d.height);
    EXPECT_EQ(back.options_key, d.options_key);
    EXPECT_EQ(back.descriptor.storage, storage);
    EXPECT_EQ(back.descriptor.hist, d.descriptor.hist);
    EXPECT_EQ(back.descriptor.pixels, d.descriptor.pixels);
    EXPECT_EQ(back.descriptor.compact, d.descriptor.compact);
    EXPECT_EQ(back.descriptor.cell_pixels, d.descriptor.cell_pixels);
    EXPECT_EQ(back.stages, (std::vector<std::string>{"temporal", "geometric"}));
    EXPECT_EQ(back.records, d.records);
    EXPECT_GT(back.records[1].size(), 0u) << "the geometric stage's features";
    EXPECT_EQ(back.segment_ms, d.segment_ms);
  }
}

// Every cut of the bytes and every flipped byte of the header is a
// FormatError or a description the map refuses or takes whole: never a
// crash, never a frame stored half.
TEST(DescribedFrames, DamagedBytesAreFormatErrors) {
  Detector robot;
  const std::vector<std::uint8_t> bytes = encode_frame_description(robot.describe_frame(frame(0)));
  for (std::size_t cut = 0; cut < bytes.size(); cut += (cut < 200 ? 1 : 97)) {
    EXPECT_THROW(decode_frame_description(bytes.data(), cut), FormatError) << "cut at " << cut;
  }
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(decode_frame_description(longer.data(), longer.size()), FormatError);
  std::vector<std::uint8_t> other = bytes;
  other[0] = 'X';
  EXPECT_NE(message_of<FormatError>([&] { decode_frame_description(other.data(), other.size()); }).find("mark"),
            std::string::npos);
  other = bytes;
  other[8] = 4;  // version 4
  EXPECT_NE(message_of<FormatError>([&] { decode_frame_description(other.data(), other.size()); }).find("version 4"),
            std::string::npos);
  // Version 3 ends in a CRC-32 of its bytes: any flipped bit is refused
  // (before, 299 of 300 random flips decoded, 46 into another descriptor).
  for (std::size_t at = sizeof(std::uint64_t) * 2; at < bytes.size(); at += (at < 400 ? 1 : 13)) {
    std::vector<std::uint8_t> flipped = bytes;
    flipped[at] ^= static_cast<std::uint8_t>(1u << (at % 8));
    EXPECT_THROW(decode_frame_description(flipped.data(), flipped.size()), FormatError) << "byte " << at;
  }
  EXPECT_NE(message_of<FormatError>([&] {
              std::vector<std::uint8_t> flipped = bytes;
              flipped[200] ^= 1;
              decode_frame_description(flipped.data(), flipped.size());
            }).find("checksum"),
            std::string::npos);
  // Version 2 (no checksum) is still read, as it was written.
  std::vector<std::uint8_t> v2(bytes.begin(), bytes.end() - 4);
  v2[8] = 2;
  const FrameDescription old = decode_frame_description(v2.data(), v2.size());
  const FrameDescription now = decode_frame_description(bytes.data(), bytes.size());
  EXPECT_EQ(old.descriptor.hist, now.descriptor.hist);
  EXPECT_EQ(old.records, now.records);
  EXPECT_EQ(old.signature, now.signature);
  // Bins that do not add up to their cell's pixels are refused even under a
  // valid checksum (and in version 2): not a histogram describe() made.
  std::vector<std::uint8_t> counts = v2;
  counts[96] ^= 1;  // cell 0's bin 0 (after the 96 bytes of the header)
  EXPECT_NE(message_of<FormatError>([&] { decode_frame_description(counts.data(), counts.size()); })
                .find("cell 0's bins add up to"),
            std::string::npos);
  // A huge count in the header asks for nothing beyond the bytes given.
  for (std::size_t at = 8; at < 120; ++at) {
    std::vector<std::uint8_t> flipped = bytes;
    flipped[at] ^= 0x7f;
    Detector map;
    try {
      const FrameDescription d = decode_frame_description(flipped.data(), flipped.size());
      try {
        map.process(d);
      } catch (const InvalidArgument&) {
        EXPECT_EQ(map.size(), 0) << "byte " << at;
      }
    } catch (const FormatError&) {
    }
  }
}

TEST(DescribedFrames, AMapRefusesWhatDoesNotFitAndChangesNothing) {
  DetectorOptions o;
  o.search.min_gap = 20;
  Detector map(o), robot(o);
  for (std::int64_t i = 0; i < 30; ++i) map.process(robot.describe_frame(frame(i)));
  const std::vector<std::uint8_t> before = map.frame_state(29);

  DetectorOptions other = o;
  other.segmentation.superpixel_size += 5;
  Detector stranger(other);
  EXPECT_NE(message_of<InvalidArgument>([&] { map.process(stranger.describe_frame(frame(30))); }).find("other segmentation"),
            std::string::npos);
  DetectorOptions fewer = o;
  fewer.verification.geometric_options.max_features /= 2;
  EXPECT_THROW(map.process(Detector(fewer).describe_frame(frame(30))), InvalidArgument);

  FrameDescription d = robot.describe_frame(frame(30));
  FrameDescription wrong = d;
  wrong.width += 2;
  EXPECT_NE(message_of<InvalidArgument>([&] { map.process(wrong); }).find("same size"), std::string::npos);
  wrong = d;
  wrong.records[1].push_back(1);  // not whole keypoints
  EXPECT_NE(message_of<InvalidArgument>([&] { map.process(wrong); }).find("geometric record"), std::string::npos);
  wrong = d;
  wrong.records.pop_back();
  EXPECT_NE(message_of<InvalidArgument>([&] { map.process(wrong); }).find("records"), std::string::npos);
  wrong = d;
  std::swap(wrong.stages[0], wrong.stages[1]);
  std::swap(wrong.records[0], wrong.records[1]);
  EXPECT_THROW(map.process(wrong), InvalidArgument);
  wrong = d;
  wrong.descriptor.hist.pop_back();
  EXPECT_THROW(map.process(wrong), InvalidArgument);
  wrong = d;
  wrong.descriptor.grid.cols += 1;
  EXPECT_NE(message_of<InvalidArgument>([&] { map.process(wrong); }).find("descriptor"), std::string::npos);

  EXPECT_EQ(map.size(), 30);
  EXPECT_EQ(map.frame_state(29), before);
  Detector reference(o);
  for (std::int64_t i = 0; i < 30; ++i) reference.process(frame(i));
  expect_same(map.process(d), reference.process(frame(30)));
}

// A stage registered from outside whose begin() reads the image, and that
// does not say it describes: describing and processing a description are
// refused, naming it; processing images still works.
class ReadsTheImage final : public VerificationStage {
 public:
  const char* name() const override { return "test-reads-image"; }
  Role role() const override { return Role::kGate; }
  void begin(const StageQuery& q) override { pixels_ = q.gray.pixels.size(); }
  StageCheck check(std::int64_t, const Candidate&) override {
    return {pixels_ > 0, -1, "read the image", 0, nullptr};
  }

 private:
  std::size_t pixels_ = 0;
};

TEST(DescribedFrames, AStageThatCannotDescribeIsNamed) {
  register_verification_stage({"test-reads-image", "reads the image in begin()", [](const VerificationOptions&) {
                                 return std::unique_ptr<VerificationStage>(new ReadsTheImage);
                               }});
  DetectorOptions o;
  o.verification.stages = {"test-reads-image"};
  Detector d(o), plain;
  EXPECT_NE(message_of<InvalidArgument>([&] { d.describe_frame(frame(0)); }).find("test-reads-image cannot take"),
            std::string::npos);
  const FrameDescription described = plain.describe_frame(frame(0));
  EXPECT_THROW(d.process(described), InvalidArgument);
  EXPECT_EQ(d.size(), 0);
  d.process(frame(0));
  EXPECT_EQ(d.size(), 1);
}

}  // namespace
}  // namespace lsgd
